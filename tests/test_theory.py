import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import theory as th

# Reference rod, by hand.
L, d, E, rho_v, R, g = 3.0, 1.5e-3, 77e9, 6450.0, 5.125e-3, 9.81
EI = E * math.pi * d**4 / 64
RHO = rho_v * math.pi * d**2 / 4
W = RHO * g


def hand_F0(m):
    om = m * math.pi / L
    return EI * om**2 + W / (R * om**2)


def test_reference_frictionless_loads():
    rod = jr.RodChannel.reference()
    F0cr = 2 * math.sqrt(W * EI / R)
    assert F0cr == pytest.approx(1.292, abs=5e-4)  # PHYSICS.md
    assert float(th.critical_load_continuous(rod)) == pytest.approx(F0cr, rel=1e-12)
    assert float(th.critical_wavenumber(rod)) == pytest.approx((W / (EI * R)) ** 0.25, rel=1e-12)
    assert (W / (EI * R)) ** 0.25 == pytest.approx(5.81, abs=5e-3)
    loads = {m: hand_F0(m) for m in range(1, 40)}
    m_star = min(loads, key=loads.get)
    assert m_star == 6
    assert int(th.critical_mode(rod)) == m_star
    assert loads[6] == pytest.approx(1.308, abs=5e-4)
    assert loads[5] == pytest.approx(1.320, abs=5e-4)
    assert loads[7] == pytest.approx(1.434, abs=5e-4)
    for m in (1, 5, 6, 7, 12):
        assert float(th.frictionless_load(rod, m)) == pytest.approx(loads[m], rel=1e-12)


def test_stiffness_and_friction_amplitude_by_hand():
    rod = jr.RodChannel.reference(mu=0.3)
    m, F = 6, 1.308 + 5.0
    om = m * math.pi / L
    k = om**2 / RHO * (EI * om**2 + RHO * g / (R * om**2) - F)
    f = 4 * 0.3 * W / (math.pi * RHO * R)
    assert float(th.stiffness(rod, m, F)) == pytest.approx(k, rel=1e-12)
    assert float(th.friction_amplitude(rod)) == pytest.approx(f, rel=1e-12)
    assert float(th.velocity_intercept(k, f)) == pytest.approx(f / math.sqrt(-k), rel=1e-12)
    assert float(th.position_intercept(k, f)) == pytest.approx(f / -k, rel=1e-12)
    assert float(th.velocity_intercept(1.0, f)) == math.inf


def test_critical_load_inverts_intercepts():
    rod = jr.RodChannel.reference(mu=0.4)
    f = th.friction_amplitude(rod)
    for m in (4, 6, 9):
        Ad0 = 1.3  # rad/s
        F = th.critical_load_velocity(rod, m, Ad0)
        k = th.stiffness(rod, m, F)
        assert float(th.velocity_intercept(k, f)) == pytest.approx(Ad0, rel=1e-10)
        A0 = 0.02
        F = th.critical_load_position(rod, m, A0)
        assert float(th.position_intercept(th.stiffness(rod, m, F), f)) == pytest.approx(
            A0, rel=1e-10
        )


def test_min_critical_load_over_modes():
    rod = jr.RodChannel.reference(mu=0.3)
    f = 4 * 0.3 * W / (math.pi * RHO * R)
    for Ad0 in (0.5, 3.0, 30.0):
        hand = {m: hand_F0(m) + RHO * f**2 / ((m * math.pi / L) ** 2 * Ad0**2) for m in range(1, 31)}
        m_star = min(hand, key=hand.get)
        F, m = th.min_critical_load(rod, 30, Ad0)
        assert int(m) == m_star
        assert float(F) == pytest.approx(hand[m_star], rel=1e-12)
    # Higher modes' zones shrink faster: small perturbations are first unstable in a mode
    # at or above the frictionless one, never below it.
    _, m_small = th.min_critical_load(rod, 30, 0.5)
    assert int(m_small) >= 6
    with pytest.raises(ValueError, match="kind"):
        th.critical_loads(rod, 10, 1.0, kind="speed")


def test_planar_limit():
    rod = jr.RodChannel.reference(mu=0.3)
    assert int(th.critical_mode(rod, planar=True)) == 1
    assert float(th.frictionless_load(rod, 1, planar=True)) == pytest.approx(math.pi**2 * EI / L**2)
    # The gravity term vanishes as R grows: the channel result tends to the planar one.
    big = jr.RodChannel.reference(R=1e9)
    for m in (1, 3):
        assert float(th.frictionless_load(big, m)) == pytest.approx(
            float(th.frictionless_load(rod, m, planar=True)), rel=1e-6
        )
    # Friction in displacement units: f = 4 mu g / pi.
    assert float(th.friction_amplitude(rod, planar=True)) == pytest.approx(4 * 0.3 * g / math.pi)


def test_stable_zone_membership_against_exact_dynamics():
    """in_stable_zone agrees with where the exact piecewise solution ends (stuck or not)."""
    k, f = -4.0, 2.0  # lam = 2, a = 0.5
    rng = np.random.default_rng(0)
    A = rng.uniform(-3, 3, 400)
    Ad = rng.uniform(-4, 4, 400)
    zone = np.asarray(th.in_stable_zone(A, Ad, k, f))
    run = jax.vmap(lambda a, v: jr.exact_solution(a, v, k, f, f, 40.0))
    Af, vf, stuck, _, _ = run(jnp.asarray(A), jnp.asarray(Ad))
    assert zone.any() and (~zone).any()
    np.testing.assert_array_equal(zone, np.asarray(stuck))


def test_stable_zone_static_friction_and_special_cases():
    # static > dynamic widens the stick line
    assert bool(th.in_stable_zone(0.7, 0.0, -4.0, 2.0, f_static=3.0))
    assert not bool(th.in_stable_zone(0.7, 0.0, -4.0, 2.0))
    # k > 0 always stable; frictionless k = 0 only at rest; frictionless k < 0 only at 0
    assert bool(th.in_stable_zone(10.0, 10.0, 3.0, 0.0))
    assert not bool(th.in_stable_zone(0.0, 1e-3, 0.0, 0.0))
    assert bool(th.in_stable_zone(0.3, 1e-3, 0.0, 0.1))
    assert not bool(th.in_stable_zone(1e-3, 0.0, -1.0, 0.0))
    # intercepts are exactly the zone's extent along the axes
    k, f = -9.0, 3.0
    Adcr, Acr = float(th.velocity_intercept(k, f)), float(th.position_intercept(k, f))
    assert bool(th.in_stable_zone(0.0, 0.999 * Adcr, k, f))
    assert not bool(th.in_stable_zone(0.0, 1.001 * Adcr, k, f))
    assert bool(th.in_stable_zone(0.999 * Acr, 0.0, k, f))
    assert not bool(th.in_stable_zone(1.001 * Acr, 0.0, k, f))
    # one answer per combination of the arguments, the dynamic amplitude's included: the state
    # A = 1.5, Ȧ = 0.2 at k = −1 is in the zone only for f = 2 and 4 (Ȧ < λ(a − A) needs
    # a = f/|k| > 1.7)
    zone = th.in_stable_zone(1.5, 0.2, -1.0, jnp.array([0.5, 1.0, 2.0, 4.0]), f_static=1.0)
    assert zone.shape == (4,) and zone.tolist() == [False, False, True, True]


def test_stable_zone_boundary_polygon_is_on_the_boundary():
    k, f = -4.0, 2.0
    A, Ad = th.stable_zone_boundary(k, f, n=50)
    A, Ad = np.asarray(A), np.asarray(Ad)
    assert A.shape == (200,)
    # Points just inside the polygon vertices (towards the stick line's middle along Adot)
    # are in the zone, points just outside are not; checked on the separatrix arc.
    sep = slice(1, 50)
    scale = 1e-6
    inside = th.in_stable_zone(A[sep], Ad[sep] * (1 - scale), k, f)
    outside = th.in_stable_zone(A[sep], Ad[sep] * (1 + scale), k, f)
    assert bool(jnp.all(inside)) and not bool(jnp.any(outside))
    hyp = slice(51, 99)
    inside = th.in_stable_zone(A[hyp], Ad[hyp] * (1 + scale), k, f)
    outside = th.in_stable_zone(A[hyp], Ad[hyp] * (1 - scale), k, f)
    assert bool(jnp.all(inside)) and not bool(jnp.any(outside))


def test_theory_is_jit_vmap_grad_safe():
    """The velocity intercept f/√(−k₆(F)) [rad/s] under jit, vmap and grad: the values against the closed form
    by hand, and dv_cr/dF against central differences and against the chain rule by hand,
    dv_cr/dF = −v_cr · (ω₆²/ρ)/(2|k₆|) (k₆ = (ω₆²/ρ)(F⁰₆ − F))."""
    rod = jr.RodChannel.reference()
    v = lambda F: th.velocity_intercept(th.stiffness(rod, 6, F), th.friction_amplitude(rod))
    F0 = float(th.frictionless_load(rod, 6))
    Fs = F0 + jnp.linspace(1.5, 10.0, 7)
    out = jax.jit(jax.vmap(v))(Fs)
    grad = jax.jit(jax.vmap(jax.grad(v)))(Fs)
    om2_rho = (6 * math.pi / float(rod.L)) ** 2 / float(rod.rho)
    k = om2_rho * (F0 - np.asarray(Fs))
    f = float(th.friction_amplitude(rod))
    np.testing.assert_allclose(out, f / np.sqrt(-k), rtol=1e-12)
    np.testing.assert_allclose(grad, -np.asarray(out) * om2_rho / (2 * np.abs(k)), rtol=1e-10)
    h = 1e-5
    fd = (jax.vmap(v)(Fs + h) - jax.vmap(v)(Fs - h)) / (2 * h)
    np.testing.assert_allclose(grad, fd, rtol=1e-7)


@pytest.mark.parametrize("k, f", [(-3.0, 0.7), (-0.01, 2.0), (-250.0, 30.0)])
def test_intercept_gradients_match_finite_differences(k, f):
    g = jax.grad(th.velocity_intercept, argnums=(0, 1))(k, f)
    h = 1e-6
    dk = (th.velocity_intercept(k * (1 + h), f) - th.velocity_intercept(k * (1 - h), f)) / (2 * h * k)
    df = (th.velocity_intercept(k, f * (1 + h)) - th.velocity_intercept(k, f * (1 - h))) / (2 * h * f)
    np.testing.assert_allclose(g[0], dk, rtol=1e-7)
    np.testing.assert_allclose(g[1], df, rtol=1e-7)
    np.testing.assert_allclose(g[1], 1 / math.sqrt(-k), rtol=1e-12)  # analytic
    gp = jax.grad(th.position_intercept, argnums=(0, 1))(k, f)
    np.testing.assert_allclose(gp[0], f / k**2, rtol=1e-12)


def test_held_end_amplitude_takes_up_the_load_excess():
    """EA/L times the end shortening ∫½y'² of mode m at the held-end amplitude equals ΔF
    (trapezoidal quadrature of the shortening, independent of the closed form)."""
    rod = jr.RodChannel.reference(0.3)
    for dF, m in ((5.0, 6), (20.0, 12)):
        A = float(jr.theory.held_end_amplitude(rod, dF, m))
        s = np.linspace(0.0, float(rod.L), 20001)
        k = m * np.pi / float(rod.L)
        slope = float(rod.R) * A * k * np.cos(k * s)
        shortening = np.trapezoid(0.5 * slope**2, s)
        assert float(rod.EA) * shortening / float(rod.L) == pytest.approx(dF, rel=1e-6)
    assert float(jr.theory.held_end_amplitude(rod, 5.0)) == pytest.approx(0.376, abs=0.002)


@pytest.mark.parametrize("F", [0.5, 3.0, 20.0, 200.0])
def test_max_growth_rate_is_the_fastest_wave_on_a_fine_grid(F):
    """λ_max(F) against a brute-force maximum of √(−k(κ)) over 200 001 wavenumbers, with
    −k(κ) = κ²(F − EIκ²)/ρ − w/(ρR) written out by hand (PHYSICS.md P3 for a continuous κ); 0
    where no wave grows (F² < 4EIw/R: 0.5 N for the reference rod)."""
    rod = jr.RodChannel.reference()
    EI, rho, R = float(rod.EI), float(rod.rho), float(rod.R)
    w = rho * float(rod.g)
    kappa = np.linspace(0.0, 4 * math.sqrt(F / (2 * EI)), 200_001)
    minus_k = kappa**2 * (F - EI * kappa**2) / rho - w / (rho * R)
    brute = math.sqrt(max(minus_k.max(), 0.0))
    got = float(th.max_growth_rate(rod, F))
    if brute == 0.0:
        assert got == 0.0
    else:
        assert got == pytest.approx(brute, rel=1e-8)
    assert (F**2 > 4 * EI * w / R) == (got > 0)
