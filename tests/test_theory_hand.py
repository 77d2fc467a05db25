"""The closed forms of `jaxrod.theory` against values computed here by hand from the reference
rod's numbers (PHYSICS.md), for the branches and arguments the other tests leave at their
defaults: the planar limit, an explicit μ, position perturbations, the held-end amplitude below
1 N, and the edges of the stable zone. Written to kill the mutants that `make mutants` found
surviving in theory.py (results/mutation/report.md)."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import theory as th

ROD = jr.RodChannel.reference(0.3)
L, d, E, rho_v, R, g = 3.0, 1.5e-3, 77e9, 6450.0, 5.125e-3, 9.81
EI = E * math.pi * d**4 / 64
EA = E * math.pi * d**2 / 4
RHO = rho_v * math.pi * d**2 / 4  # mass per length
W = RHO * g


def test_planar_limit_is_eulers_first_mode():
    assert float(th.critical_load_continuous(ROD, planar=True)) == pytest.approx(math.pi**2 * EI / L**2, rel=1e-12)
    assert float(th.critical_wavenumber(ROD, planar=True)) == pytest.approx(math.pi / L, rel=1e-12)
    m = th.critical_mode(ROD, planar=True)
    assert int(m) == 1 and jnp.issubdtype(m.dtype, jnp.integer)
    m = th.critical_mode(ROD)
    assert int(m) == 6 and jnp.issubdtype(m.dtype, jnp.integer)
    # the planar friction amplitude is a lateral acceleration [m/s²]: 4μg/π
    assert float(th.friction_amplitude(ROD, 0.5, planar=True)) == pytest.approx(4 * 0.5 * g / math.pi, rel=1e-12)


def test_explicit_friction_coefficient_is_used():
    """μ given explicitly, not the rod's μ_d (0.3): f = 4μg/(πR)."""
    f = lambda mu: 4 * mu * g / (math.pi * R)
    assert float(th.friction_amplitude(ROD, 0.5)) == pytest.approx(f(0.5), rel=1e-12)
    assert float(th.friction_amplitude(ROD)) == pytest.approx(f(0.3), rel=1e-12)
    om2 = (6 * math.pi / L) ** 2
    F0 = EI * om2 + W / (R * om2)
    Adot0 = 2.0
    assert float(th.critical_load_velocity(ROD, 6, Adot0, mu=0.5)) == pytest.approx(
        F0 + RHO * f(0.5) ** 2 / (om2 * Adot0**2), rel=1e-12)
    A0 = 0.01
    p7_pos = F0 + RHO * f(0.5) / (om2 * A0)
    assert float(th.critical_load_position(ROD, 6, A0, mu=0.5)) == pytest.approx(p7_pos, rel=1e-12)
    assert float(th.critical_load_position(ROD, 6, -A0, mu=0.5)) == pytest.approx(p7_pos, rel=1e-12)


@pytest.mark.parametrize("planar", [False, True])
def test_critical_loads_of_every_mode_by_hand(planar):
    """P7 for modes 1..8, velocity and position kinds, μ = 0.5, against the formula by hand;
    the lowest and its mode."""
    f = 4 * 0.5 * g / math.pi / (1.0 if planar else R)
    for kind, amp in (("velocity", 3.0), ("position", 0.02)):
        loads = np.asarray(th.critical_loads(ROD, 8, amp, kind, mu=0.5, planar=planar))
        hand = []
        for m in range(1, 9):
            om2 = (m * math.pi / L) ** 2
            F0 = EI * om2 + (0.0 if planar else W / (R * om2))
            hand.append(F0 + RHO * (f**2 / amp**2 if kind == "velocity" else f / amp) / om2)
        np.testing.assert_allclose(loads, hand, rtol=1e-12)
        F, m = th.min_critical_load(ROD, 8, amp, kind, mu=0.5, planar=planar)
        assert float(F) == pytest.approx(min(hand), rel=1e-12) and int(m) == int(np.argmin(hand)) + 1


def test_critical_loads_check_their_arguments():
    assert th.critical_loads(ROD, 1, 1.0).shape == (1,)
    with pytest.raises(ValueError, match=r"n_modes = 0 is invalid: expected an int >= 1"):
        th.critical_loads(ROD, 0, 1.0)
    with pytest.raises(ValueError, match=r"n_modes = 2.0 is invalid"):
        th.critical_loads(ROD, 2.0, 1.0)
    with pytest.raises(ValueError, match=r"kind = 'speed' is invalid"):
        th.critical_loads(ROD, 2, 1.0, kind="speed")


@pytest.mark.parametrize("dF", [0.25, 0.5, 5.0])
def test_held_end_amplitude_by_hand(dF):
    k6 = 6 * math.pi / L
    assert float(th.held_end_amplitude(ROD, dF)) == pytest.approx(2 / (R * k6) * math.sqrt(dF / EA), rel=1e-12)
    assert float(th.held_end_amplitude(ROD, -dF)) == 0.0


def test_intercepts_at_and_beyond_zero_stiffness():
    """P6's intercepts: f/√|k| and f/|k| for k < 0; ∞ where every trajectory is bounded (k ≥ 0
    for the velocity, k = 0 for the position: a stiff mode's stick line is f/k too)."""
    f = 0.7
    for k in (-0.5, -2.0):
        assert float(th.velocity_intercept(k, f)) == pytest.approx(f / math.sqrt(-k), rel=1e-14)
        assert float(th.position_intercept(k, f)) == pytest.approx(f / -k, rel=1e-14)
    for k in (0.0, 0.5, 1.0):
        assert float(th.velocity_intercept(k, f)) == math.inf
    assert float(th.position_intercept(0.0, f)) == math.inf
    for k in (0.5, 1.0, 2.0):
        assert float(th.position_intercept(k, f)) == pytest.approx(f / k, rel=1e-14)


def test_stable_zone_edges():
    """The zone's edges, state by state, for k = −4, f = 2 (λ = 2, a = 0.5): at rest the stick
    line |A| ≤ a_s is included; a state moving left is the mirror image of one moving right;
    without friction at k = 0 only rest is bounded."""
    k, f = -4.0, 2.0
    a = 0.5
    zone = lambda A, Ad, **kw: bool(th.in_stable_zone(A, Ad, k, f, **kw))
    assert zone(a, 0.0) and zone(-a, 0.0) and not zone(1.0001 * a, 0.0)
    assert zone(0.6, 0.0, f_static=2.4) and not zone(0.6001 * 1.0, 0.0)  # a_s = 0.6 with f_s = 2.4
    for A, Ad in ((0.1, 0.5), (-0.7, 1.0), (0.3, 0.39), (0.3, 0.41)):
        assert zone(A, Ad) == zone(-A, -Ad)
    # on the separatrix Ȧ = λ(a − A) the state is not stable (it creeps to the saddle)
    assert not zone(0.0, 2 * a) and zone(0.0, 2 * a * (1 - 1e-9))
    # the hyperbola: from A = −a − 0.5 the slip phase stops exactly at −a (stuck) when
    # Ȧ² = λ²((a − A)² − 4a²)
    A = -a - 0.5
    Ad = 2 * math.sqrt((a - A) ** 2 - 4 * a**2)
    assert zone(A, Ad) and not zone(A, 0.999 * Ad)
    assert bool(th.in_stable_zone(0.3, 0.0, 0.0, 0.0)) and not bool(th.in_stable_zone(0.3, 1.0, 0.0, 0.0))
    assert not bool(th.in_stable_zone(0.3, 0.5, -1.0, 0.0))


def test_stable_zone_polygon_spans_its_extent_and_is_symmetric():
    k, f, n = -4.0, 2.0, 50
    a = 0.5
    A, Ad = (np.asarray(x) for x in th.stable_zone_boundary(k, f, n=n, extent=10.0))
    assert A.shape == (4 * n,)
    np.testing.assert_allclose(A[: 2 * n], -A[2 * n:], rtol=0, atol=0)
    np.testing.assert_allclose(Ad[: 2 * n], -Ad[2 * n:], rtol=0, atol=0)
    assert A[0] == pytest.approx(a) and A[2 * n - 1] == pytest.approx(-a)
    assert A.min() == pytest.approx(-10 * a)
    # vertices cluster towards the saddle and the vertex: the first step along the separatrix
    # is (extent + 1)·a/(n − 1)², the last ~2(n − 1) times longer
    steps = np.abs(np.diff(A[:n]))
    assert steps[0] == pytest.approx(11 * a / (n - 1) ** 2, rel=1e-9)
    assert steps[-1] == pytest.approx(11 * a * (2 * n - 3) / (n - 1) ** 2, rel=1e-9)
    steps = np.abs(np.diff(A[n:2 * n]))
    assert steps[-1] == pytest.approx(9 * a / (n - 1) ** 2, rel=1e-9)


def test_reference_load_is_mode_6_by_hand_and_short_rods_take_mode_1():
    om2 = (6 * math.pi / L) ** 2
    assert float(th.reference_load(ROD)) == pytest.approx(EI * om2 + W / (R * om2), rel=1e-12)
    # a rod so short that its continuous critical wavenumber lies below the first mode
    # (ω₀L/π = 0.46): the mode with the lowest load, by brute force over m = 1..10
    short = eqx.tree_at(lambda r: r.L, ROD, jnp.asarray(0.25))
    loads = [float(th.frictionless_load(short, m)) for m in range(1, 11)]
    assert int(th.critical_mode(short)) == 1 + int(np.argmin(loads)) == 1
    # batched rods: one mode per rod, also in the planar limit
    two = eqx.tree_at(lambda r: r.L, ROD, jnp.asarray([3.0, 0.25]))
    assert th.critical_mode(two).tolist() == [6, 1] and th.critical_mode(two, planar=True).tolist() == [1, 1]


def test_planar_stiffness_and_default_is_not_planar():
    om2 = (6 * math.pi / L) ** 2
    F = 2.0
    assert float(th.stiffness(ROD, 6, F, planar=True)) == pytest.approx(om2 / RHO * (EI * om2 - F), rel=1e-12)
    np.testing.assert_array_equal(th.critical_loads(ROD, 4, 2.0), th.critical_loads(ROD, 4, 2.0, planar=False))


def test_dtypes_and_broadcasting_of_the_stable_zone():
    """float32 inputs stay float32 (a user's single-precision batch), ints become floats; the
    zone broadcasts over every argument (k, f, f_s as arrays of loads or coefficients)."""
    out = th.velocity_intercept(jnp.float32(-4.0), jnp.float32(2.0))
    assert out.dtype == jnp.float32 and float(out) == 1.0
    assert th.velocity_intercept(-4, 2).dtype == jnp.float64
    ks = jnp.asarray([-4.0, 0.0, 4.0])
    assert th.in_stable_zone(0.1, 0.0, ks, 2.0).shape == (3,)
    assert th.in_stable_zone(0.1, 0.0, -4.0, jnp.asarray([0.1, 2.0])).tolist() == [False, True]
    assert th.in_stable_zone(0.45, 0.0, -4.0, 1.6, f_static=jnp.asarray([1.6, 2.0])).tolist() == [False, True]
    # the gradient of the velocity intercept where nothing grows (k > 0) is 0, not NaN
    assert float(jax.grad(th.velocity_intercept, argnums=1)(1.0, 0.7)) == 0.0


def test_stick_line_with_static_above_dynamic_friction():
    """k = −4, f = 2, f_s = 2.4 (λ = 2, a = 0.5, a_s = 0.6): a slip from A < −a ends stuck iff
    A_stop = a − √((a − A)² − (Ȧ/λ)²) ≥ −a_s, i.e. Ȧ² ≥ λ²((a − A)² − (a + a_s)²)."""
    k, f, fs = -4.0, 2.0, 2.4
    A = -1.2
    edge = 2 * math.sqrt((0.5 - A) ** 2 - 1.1**2)
    zone = lambda Ad: bool(th.in_stable_zone(A, Ad, k, f, f_static=fs))
    assert zone(1.001 * edge) and not zone(0.999 * edge)


def test_stable_zone_polygon_defaults():
    k, f = -4.0, 2.0
    A, Ad = th.stable_zone_boundary(k, f)
    assert A.shape == (800,) and float(jnp.min(A)) == pytest.approx(-50 * 0.5)
    A40, _ = th.stable_zone_boundary(k, f, n=40)
    assert A40.shape == (160,)
    steps = np.abs(np.diff(np.asarray(A40)[:40]))
    assert steps[0] == pytest.approx(51 * 0.5 / 39**2, rel=1e-9)
