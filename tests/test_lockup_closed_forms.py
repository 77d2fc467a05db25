"""The soft-string closed forms of `jaxrod.lockup.closed_forms` (docs/physics.md §8) against
numbers worked out here by hand from the reference rod (RodChannel.reference(0.3)), against an
independent numerical integration of dF/ds = −μ w_c(F) (RK4 for one section, scipy's DOP853
with events at the onsets for the chain), and in their limits (μ → 0, unbounded push, with and
without the weight term), monotonicity and the F_far,max bound."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jaxrod as jr
from jaxrod import lockup as lk
from jaxrod.lockup import closed_forms as cf

ROD = jr.RodChannel.reference(0.3)
# The reference rod by hand: d = 1.5 mm, E = 77 GPa, ρ_v = 6450 kg/m³, g = 9.81 m/s², r = 5.125 mm.
d, E, rho_v, g, r = 1.5e-3, 77e9, 6450.0, 9.81, 5.125e-3
EI = E * math.pi * d**4 / 64  # 77e9 · π · 5.0625e-12 / 64 = 0.019134876 N·m²
W = rho_v * math.pi * d**2 / 4 * g  # 6450 · 1.76715e-6 · 9.81 = 0.11181527 N/m
F0 = math.sqrt(EI * W / r)  # √(0.019134876 · 0.11181527 / 5.125e-3) = √0.417477 = 0.646125 N
ELL = math.sqrt(EI / (r * W))  # √(0.019134876 / 5.73053e-4) = √33.3911 = 5.778503 m
MU = 0.3
ARGS = (EI, W, r)


def test_the_rods_numbers_are_the_reference_rods():
    assert float(ROD.EI) == pytest.approx(EI, rel=1e-14)
    assert float(ROD.w) == pytest.approx(W, rel=1e-14)
    assert float(ROD.R) == r


def test_units_and_onsets_by_hand():
    assert EI == pytest.approx(0.01913488, rel=1e-6)
    assert W == pytest.approx(0.1118153, rel=1e-6)
    assert float(lk.force_unit(*ARGS)) == pytest.approx(F0, rel=1e-14)
    assert float(lk.force_unit(*ARGS)) == pytest.approx(0.6461249, rel=1e-6)
    assert float(lk.length_unit(*ARGS)) == pytest.approx(ELL, rel=1e-14)
    assert float(lk.length_unit(*ARGS)) == pytest.approx(5.778503, rel=1e-6)
    # F₀ ℓ = EI/r and F₀/ℓ = w
    assert F0 * ELL == pytest.approx(EI / r, rel=1e-14) and F0 / ELL == pytest.approx(W, rel=1e-14)
    # sinusoidal 2F₀ = 1.29225 N (= §3's continuous F⁰_cr); Chen 2√2 F₀ = 1.82752 N;
    # Wu & Juvkam-Wold 2(2√2 − 1) F₀ = 3.65685 · 0.64612 = 2.36278 N
    assert float(lk.sinusoidal_onset(*ARGS)) == pytest.approx(1.292250, rel=1e-6)
    assert float(lk.sinusoidal_onset(*ARGS)) == pytest.approx(float(jr.theory.critical_load_continuous(ROD)),
                                                             rel=1e-14)
    assert float(lk.helical_onset(*ARGS)) == pytest.approx(2 * math.sqrt(2) * F0, rel=1e-14)
    assert float(lk.helical_onset(*ARGS)) == pytest.approx(1.827517, rel=1e-6)
    wjw = float(lk.helical_onset(*ARGS, variant="wu_juvkam_wold"))
    assert wjw == pytest.approx(2 * (2 * math.sqrt(2) - 1) * F0, rel=1e-14)
    assert wjw == pytest.approx(2.362784, rel=1e-6)
    # WJW's abstract: about 1.3 times Chen's load and 1.8 times the sinusoidal onset
    assert wjw / float(lk.helical_onset(*ARGS)) == pytest.approx(1.29, abs=0.01)
    assert wjw / float(lk.sinusoidal_onset(*ARGS)) == pytest.approx(1.83, abs=0.01)


def test_helix_pitch_and_wall_force_by_hand():
    # Lubinski at F = 1 N: π √(8 · 0.0191349 / 1) = π · 0.391253 = 1.229158 m
    assert float(lk.helix_pitch(EI, 1.0)) == pytest.approx(math.pi * math.sqrt(8 * EI), rel=1e-14)
    assert float(lk.helix_pitch(EI, 1.0)) == pytest.approx(1.229158, rel=1e-6)
    # its wavenumber k = 2π/p satisfies k² = F/(2EI)
    k = 2 * math.pi / float(lk.helix_pitch(EI, 1.0))
    assert k**2 == pytest.approx(1.0 / (2 * EI), rel=1e-13)
    # Mitchell at F = 2 N: r F²/(4EI) = 5.125e-3 · 4 / 0.0765395 = 0.2678355 N/m (+ w = 0.3796508)
    assert float(lk.helical_wall_force(2.0, *ARGS, weight=False)) == pytest.approx(0.2678355, rel=1e-6)
    assert float(lk.helical_wall_force(2.0, *ARGS)) == pytest.approx(0.3796508, rel=1e-6)
    # In units of w: (F/F₀)²/4 (+ 1)
    f = 2.0 / F0
    assert float(lk.helical_wall_force(2.0, *ARGS)) / W == pytest.approx(1 + f**2 / 4, rel=1e-13)


def test_straight_transfer_by_hand():
    # 2 N through 3 m at μ = 0.3: 2 − 0.3 · 0.1118153 · 3 = 1.899366 N
    assert float(lk.straight_transfer(2.0, 3.0, W, MU)) == pytest.approx(1.8993663, rel=1e-7)
    # the force dies out at s = F/(μw) = 2/0.0335446 = 59.62 m: beyond it nothing is pushed
    assert float(lk.straight_transfer(2.0, 59.0, W, MU)) > 0
    assert float(lk.straight_transfer(2.0, 60.0, W, MU)) == 0.0


def test_helical_transfer_by_hand():
    # without weight: 2/(1 + 0.3 · 5.125e-3 · 2 · 3/(4 · 0.0191349)) = 2/1.120526 = 1.784876 N
    x = MU * r * 2.0 * 3.0 / (4 * EI)
    assert x == pytest.approx(0.1205260, rel=1e-6)
    got = float(lk.helical_transfer(2.0, 3.0, *ARGS, MU, weight=False))
    assert got == pytest.approx(2.0 / (1 + x), rel=1e-13)
    assert got == pytest.approx(1.784876, rel=1e-6)
    # with weight: 2F₀ tan(arctan(2/(2F₀)) − 0.3 · 3/(2ℓ)) = 1.292250 · tan(0.997150 − 0.077875)
    #   = 1.292250 · tan(0.919275) = 1.694515 N
    phi = math.atan(2.0 / (2 * F0)) - MU * 3.0 / (2 * ELL)
    assert phi == pytest.approx(0.997150 - 0.077875, abs=2e-6)
    got = float(lk.helical_transfer(2.0, 3.0, *ARGS, MU))
    assert got == pytest.approx(2 * F0 * math.tan(phi), rel=1e-13)
    assert got == pytest.approx(1.694515, rel=1e-6)
    # the weight only adds friction
    assert got < float(lk.helical_transfer(2.0, 3.0, *ARGS, MU, weight=False))


def test_sinusoidal_transfer_by_hand():
    # weight law = straight law
    assert float(lk.sinusoidal_transfer(1.8, 3.0, *ARGS, MU)) == pytest.approx(1.8 - MU * W * 3.0, rel=1e-13)
    # half-helical: c = 2√2: 2√2 F₀ tan(arctan(1.8/(2√2 F₀)) − 0.3 · 3/(2√2 ℓ))
    c = 2 * math.sqrt(2)
    hand = c * F0 * math.tan(math.atan(1.8 / (c * F0)) - MU * 3.0 / (c * ELL))
    got = float(lk.sinusoidal_transfer(1.8, 3.0, *ARGS, MU, law="half_helical"))
    assert got == pytest.approx(hand, rel=1e-13)
    assert got < 1.8 - MU * W * 3.0  # more wall force than the weight alone


def _rk4(rhs, y0, s_end, n):
    h, y = s_end / n, y0
    for _ in range(n):
        k1 = rhs(y)
        k2 = rhs(y + h / 2 * k1)
        k3 = rhs(y + h / 2 * k2)
        k4 = rhs(y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


@pytest.mark.parametrize("weight", [True, False])
def test_helical_transfer_solves_the_soft_string_equation(weight):
    """dF/ds = −μ(rF²/(4EI) + w) (or without w) by RK4 with 4000 steps, from three entry forces
    over 0.5, 2 and 8 m: the closed form agrees to 1e-8."""
    F_in = np.array([2.0, 5.0, 20.0])
    rhs = lambda F: -MU * (r * F**2 / (4 * EI) + (W if weight else 0.0))
    for s in (0.5, 2.0, 8.0):
        ref = _rk4(rhs, F_in, s, 4000)
        got = np.asarray(lk.helical_transfer(jnp.asarray(F_in), s, *ARGS, MU, weight=weight))
        np.testing.assert_allclose(got, ref, rtol=1e-8)


def test_half_helical_sinusoid_solves_its_equation():
    rhs = lambda F: -MU * (W + r * F**2 / (8 * EI))
    F_in = np.array([1.5, 2.3])
    ref = _rk4(rhs, F_in, 10.0, 4000)
    got = np.asarray(lk.sinusoidal_transfer(jnp.asarray(F_in), 10.0, *ARGS, MU, law="half_helical"))
    np.testing.assert_allclose(got, ref, rtol=1e-8)


def _chain_ode(F_in, L, fh, a_s, b_s, a_h, b_h):
    """dF/ds = −μ w_c(F) through the helical, sinusoidal and straight pieces, each integrated by
    DOP853 and stopped by an event where F reaches the next onset."""
    Fh, Fs = fh * F0, 2 * F0
    pieces = [(Fh, a_h, b_h), (Fs, a_s, b_s), (0.0, 1.0, 0.0)]
    s, F = 0.0, F_in
    for F_low, a, b in pieces:
        if F <= F_low:
            continue
        ev = lambda _s, y, F_low=F_low: y[0] - F_low
        ev.terminal, ev.direction = True, -1
        sol = solve_ivp(lambda _s, y, a=a, b=b: [-MU * W * (a + b * (y[0] / F0) ** 2)], (s, L), [F],
                        method="DOP853", rtol=1e-13, atol=1e-15, events=ev)
        if sol.status == 1:  # the onset was reached inside the rod
            s, F = float(sol.t_events[0][0]), F_low
        else:
            return float(sol.y[0, -1])
    return 0.0


@pytest.mark.parametrize("laws", [{}, {"helical_onset": "wu_juvkam_wold"},
                                  {"sinusoidal_law": "half_helical", "helical_law": "without_weight"}])
def test_the_chain_solves_the_piecewise_equation(laws):
    fh = cf.HELICAL_ONSETS[laws.get("helical_onset", "chen")]
    a_s, b_s = cf.SINUSOIDAL_LAWS[laws.get("sinusoidal_law", "weight")]
    a_h, b_h = cf.HELICAL_LAWS[laws.get("helical_law", "with_weight")]
    for F_in in (1.0, 1.5, 2.0, 4.0, 15.0):
        for L in (1.0, 5.0, 20.0, 50.0):
            ref = _chain_ode(F_in, L, fh, a_s, b_s, a_h, b_h)
            got = float(lk.far_force(F_in, L, *ARGS, MU, **laws))
            assert got == pytest.approx(ref, rel=1e-8, abs=1e-12), (F_in, L)


def test_far_force_max_and_lockup_length_by_hand():
    """Default laws (Chen's onset, sinusoid = weight, Mitchell with weight); X = μL/ℓ.

    The helical section from an unbounded push down to 2√2 takes X_h = 2(π/2 − arctan √2) =
    2 arctan(1/√2) = 1.230959; the sinusoidal one 2√2 − 2 = 0.828427; the straight one 2.
    """
    Xh = 2 * math.atan(1 / math.sqrt(2))
    assert Xh == pytest.approx(1.230959, rel=1e-6)
    L_of = lambda X: X * ELL / MU
    fmax = lambda X: float(lk.far_force_max(L_of(X), *ARGS, MU)) / F0
    assert fmax(0.5) == pytest.approx(2 / math.tan(0.25), rel=1e-12)  # 2 cot(X/2) = 7.832635
    assert fmax(0.5) == pytest.approx(7.832635, rel=1e-6)
    assert fmax(2.0) == pytest.approx(2 * math.sqrt(2) - (2.0 - Xh), rel=1e-12)  # 2.059387
    assert fmax(3.5) == pytest.approx(2 - (3.5 - Xh - (2 * math.sqrt(2) - 2)), rel=1e-12)  # 0.559387
    X_lock = Xh + 2 * math.sqrt(2) - 2 + 2
    assert X_lock == pytest.approx(4.059387, rel=1e-6)
    L_lock = float(lk.lockup_length(*ARGS, MU))
    assert L_lock == pytest.approx(X_lock * ELL / MU, rel=1e-13)  # 4.059387 · 5.778503/0.3 = 78.19059 m
    assert L_lock == pytest.approx(78.19059, rel=1e-6)
    assert fmax(X_lock * (1 - 1e-9)) == pytest.approx(0.0, abs=1e-8)
    assert fmax(X_lock * (1 + 1e-9)) == 0.0 and fmax(6.0) == 0.0


@pytest.mark.parametrize("laws", [{}, dict(helical_law="without_weight"), dict(helical_onset="wu_juvkam_wold"),
                                  dict(sinusoidal_law="half_helical")])
def test_lockup_length_at_a_bounded_entry_force(laws):
    """At a bounded entry force the lock-up length is where `far_force` of that force reaches 0
    (found here by bisection on far_force, independently of the sum the code takes), and it
    tends to the unbounded one as the force grows."""
    for f in (1.5, 2.5, 3.2, 6.0, 20.0):
        lo, hi = 0.0, 20.0
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            far = float(lk.far_force(f * F0, mid * ELL / MU, *ARGS, MU, **laws))
            lo, hi = (mid, hi) if far > 1e-12 * F0 else (lo, mid)
        got = float(lk.lockup_length(*ARGS, MU, F_in=f * F0, **laws)) * MU / ELL
        assert got == pytest.approx(hi, rel=1e-9), f
    big = float(lk.lockup_length(*ARGS, MU, F_in=1e9 * F0, **laws))
    assert big == pytest.approx(float(lk.lockup_length(*ARGS, MU, **laws)), rel=1e-6 if laws.get("helical_law") else 1e-8)
    straight = float(lk.lockup_length(*ARGS, MU, F_in=1.5 * F0, **laws)) * MU / ELL
    assert straight == pytest.approx(1.5, rel=1e-12)  # below 2F0 the rod stays straight: X = f_in


def test_lockup_length_variants_by_hand():
    # Wu & Juvkam-Wold onset, f_h = 2(2√2 − 1): 2(π/2 − arctan(f_h/2)) + (f_h − 2) + 2
    fh = 2 * (2 * math.sqrt(2) - 1)
    X = 2 * (math.pi / 2 - math.atan(fh / 2)) + fh
    got = float(lk.lockup_length(*ARGS, MU, helical_onset="wu_juvkam_wold")) * MU / ELL
    assert got == pytest.approx(X, rel=1e-13)
    # without the weight term in the helix: 4/f_h + (f_h − 2) + 2 = √2 + 2√2
    got = float(lk.lockup_length(*ARGS, MU, helical_law="without_weight")) * MU / ELL
    assert got == pytest.approx(4 / (2 * math.sqrt(2)) + 2 * math.sqrt(2), rel=1e-13)
    # a helix all along: πℓ/μ with the weight term, none without
    assert float(lk.helical_lockup_length(*ARGS, MU)) == pytest.approx(math.pi * ELL / MU, rel=1e-14)
    assert math.isinf(float(lk.helical_lockup_length(*ARGS, MU, weight=False)))
    # no friction, no lock-up
    assert math.isinf(float(lk.lockup_length(*ARGS, 0.0)))


def test_helical_far_force_max_by_hand():
    L = 10.0
    X = MU * L / ELL
    assert float(lk.helical_far_force_max(L, *ARGS, MU)) == pytest.approx(2 * F0 / math.tan(X / 2), rel=1e-12)
    # without weight: 4EI/(μ r L) = 4 · 0.0191349/(0.3 · 5.125e-3 · 10) = 4.978179 N
    assert float(lk.helical_far_force_max(L, *ARGS, MU, weight=False)) == pytest.approx(4 * EI / (MU * r * L),
                                                                                         rel=1e-13)
    assert 4 * EI / (MU * r * L) == pytest.approx(4.978179, rel=1e-6)
    assert float(lk.helical_far_force_max(math.pi * ELL / MU * 1.01, *ARGS, MU)) == 0.0


def test_no_friction_transfers_everything():
    F_in = jnp.array([0.5, 1.5, 2.0, 5.0, 40.0])
    for laws in ({}, {"helical_law": "without_weight", "sinusoidal_law": "half_helical"}):
        np.testing.assert_allclose(np.asarray(lk.far_force(F_in, 100.0, *ARGS, 0.0, **laws)), F_in, rtol=1e-14)
        got = np.asarray(lk.far_force(F_in, 100.0, *ARGS, 1e-9, **laws))
        np.testing.assert_allclose(got, F_in, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(lk.helical_transfer(F_in, 100.0, *ARGS, 0.0)), F_in, rtol=1e-14)
    np.testing.assert_allclose(np.asarray(lk.helical_transfer(F_in, 100.0, *ARGS, 0.0, weight=False)), F_in,
                               rtol=1e-14)
    # and a zero length passes the force through at any μ
    np.testing.assert_allclose(np.asarray(lk.far_force(F_in, 0.0, *ARGS, MU)), F_in, rtol=1e-14)


def test_short_unbuckled_rod_loses_mu_w_L():
    """Below the sinusoidal onset the rod stays straight and loses μwL (the issue's short-rod test)."""
    got = float(lk.far_force(1.2, 2.0, *ARGS, MU))
    assert got == pytest.approx(1.2 - MU * W * 2.0, rel=1e-14)  # 1.2 − 0.0670892 = 1.132911 N
    assert got == pytest.approx(1.132911, rel=1e-6)


def test_monotone_and_bounded():
    F_in = jnp.linspace(0.0, 30.0, 61)
    L = jnp.linspace(0.0, 120.0, 49)
    for laws in ({}, {"helical_onset": "wu_juvkam_wold"}, {"helical_law": "without_weight"},
                 {"sinusoidal_law": "half_helical"}):
        grid = np.asarray(jax.vmap(lambda L_, laws=laws: lk.far_force(F_in, L_, *ARGS, MU, **laws))(L))
        assert np.all(np.diff(grid, axis=1) >= -1e-12), laws  # increasing in F_in
        assert np.all(np.diff(grid, axis=0) <= 1e-12), laws  # decreasing in L
        fmax = np.asarray(lk.far_force_max(L, *ARGS, MU, **laws))
        assert np.all(grid <= fmax[:, None] * (1 + 1e-12)), laws
        assert np.all(np.diff(fmax) <= 1e-12)
        # a push of 1e6 F₀ reaches the bound
        big = np.asarray(lk.far_force(1e6 * F0, L[1:], *ARGS, MU, **laws))
        # (1e-5 N: the helix without weight takes 4/(μ f_in) ℓ more to come down from f_in than from ∞)
        np.testing.assert_allclose(big, fmax[1:], rtol=1e-4, atol=1e-5)
    # more friction-carrying wall force, less at the far end
    w_h = np.asarray(lk.far_force(F_in, 30.0, *ARGS, MU))
    wo_h = np.asarray(lk.far_force(F_in, 30.0, *ARGS, MU, helical_law="without_weight"))
    assert np.all(w_h <= wo_h + 1e-12) and np.any(w_h < wo_h)


def test_the_gain_is_the_ratio_of_wall_forces():
    """dF_far/dF_in = w_c(F_far)/w_c(F_in) (P16), by jax.grad, through every piece."""
    g = jax.grad(lambda F, L: lk.far_force(F, L, *ARGS, MU))
    for F_in, L in ((1.5, 3.0), (2.2, 20.0), (5.0, 20.0), (5.0, 5.0), (12.0, 60.0)):
        far = lk.far_force(F_in, L, *ARGS, MU)
        assert float(far) > 0
        ratio = lk.wall_force(far, *ARGS) / lk.wall_force(F_in, *ARGS)
        assert float(g(F_in, L)) == pytest.approx(float(ratio), rel=1e-10), (F_in, L)
    # and dF_far/dL = −μ w_c(F_far)
    gL = jax.grad(lambda L: lk.far_force(5.0, L, *ARGS, MU))(20.0)
    assert float(gL) == pytest.approx(-MU * float(lk.wall_force(lk.far_force(5.0, 20.0, *ARGS, MU), *ARGS)),
                                      rel=1e-10)


def test_wall_force_pieces_by_hand():
    F = jnp.array([1.0, 1.5, 2.0])  # straight (< 1.2922), sinusoidal, helical (> 1.8275)
    got = np.asarray(lk.wall_force(F, *ARGS))
    np.testing.assert_allclose(got, [W, W, r * 4 / (4 * EI) + W], rtol=1e-13)
    got = np.asarray(lk.wall_force(F, *ARGS, sinusoidal_law="half_helical", helical_law="without_weight"))
    np.testing.assert_allclose(got, [W, W + r * 1.5**2 / (8 * EI), r * 4 / (4 * EI)], rtol=1e-13)


def test_section_extents():
    L = 40.0
    lh, ls = lk.section_extents(5.0, L, *ARGS, MU)
    # the helical section brings 5 N down to 2√2 F₀ over (2ℓ/μ)(arctan(5/(2F₀)) − arctan √2)
    lh_hand = 2 * ELL / MU * (math.atan(5.0 / (2 * F0)) - math.atan(math.sqrt(2)))
    ls_hand = (2 * math.sqrt(2) - 2) * ELL / MU  # then 2√2 F₀ − 2F₀ at μw per metre
    assert float(lh) == pytest.approx(lh_hand, rel=1e-13) and float(ls) == pytest.approx(ls_hand, rel=1e-13)
    # the profile at those points is the onsets
    assert float(lk.force_profile(5.0, lh_hand, *ARGS, MU)) == pytest.approx(2 * math.sqrt(2) * F0, rel=1e-12)
    assert float(lk.force_profile(5.0, lh_hand + ls_hand, *ARGS, MU)) == pytest.approx(2 * F0, rel=1e-12)
    # a short rod is all helical
    lh, ls = lk.section_extents(5.0, 1.0, *ARGS, MU)
    assert float(lh) == 1.0 and float(ls) == 0.0
    # without friction one section holds the whole rod
    assert tuple(map(float, lk.section_extents(1.5, 3.0, *ARGS, 0.0))) == (0.0, 3.0)
    assert tuple(map(float, lk.section_extents(5.0, 3.0, *ARGS, 0.0))) == (3.0, 0.0)
    assert tuple(map(float, lk.section_extents(1.0, 3.0, *ARGS, 0.0))) == (0.0, 0.0)


def test_dimensionless_transfer_and_length_are_inverse():
    f_in = jnp.array([0.5, 2.0, 3.0, 10.0])
    x = jnp.array([0.1, 0.4, 0.7, 0.2])
    for a, b in ((1.0, 0.0), (0.0, 0.25), (1.0, 0.25), (1.0, 0.125), (0.5, 0.75)):
        f = cf.transfer(f_in, x, a, b)
        assert np.all(np.asarray(f) > 0)
        np.testing.assert_allclose(np.asarray(cf.transfer_length(f_in, f, a, b)), np.asarray(x), rtol=1e-12)
        # semigroup: two pieces = one
        np.testing.assert_allclose(np.asarray(cf.transfer(cf.transfer(f_in, x / 3, a, b), 2 * x / 3, a, b)),
                                   np.asarray(f), rtol=1e-12)


def test_jit_vmap_and_no_retrace():
    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def run(F_in, L, EI_, w_, r_, mu):
        return lk.far_force(F_in, L, EI_, w_, r_, mu), lk.far_force_max(L, EI_, w_, r_, mu)

    f = lambda *v: jnp.asarray(v[0] if len(v) == 1 else v, dtype=float)
    for F_in, L, mu in ((3.0, 20.0, 0.3), (5.0, 40.0, 0.2), (1.0, 2.0, 0.5)):
        far, fmax = run(f(F_in), f(L), f(EI), f(W), f(r), f(mu))
        assert float(far) == pytest.approx(float(lk.far_force(F_in, L, *ARGS, mu)), rel=1e-14)
        assert float(fmax) == pytest.approx(float(lk.far_force_max(L, *ARGS, mu)), rel=1e-14)
    mus = jnp.array([0.1, 0.3, 0.6])
    Ls = jnp.array([5.0, 30.0, 90.0])
    batched = np.asarray(jax.vmap(lambda m, L: lk.far_force(4.0, L, *ARGS, m))(mus, Ls))
    loop = [float(lk.far_force(4.0, float(L), *ARGS, float(m))) for m, L in zip(mus, Ls)]
    np.testing.assert_allclose(batched, loop, rtol=1e-14)
    # only μL/ℓ matters: the same product, the same far force
    a = float(lk.far_force(4.0, 30.0, *ARGS, 0.2))
    b = float(lk.far_force(4.0, 20.0, *ARGS, 0.3))
    assert a == pytest.approx(b, rel=1e-13)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: lk.force_unit(-1.0, W, r), "EI"),
        (lambda: lk.length_unit(EI, 0.0, r), "w"),
        (lambda: lk.sinusoidal_onset(EI, W, float("nan")), "r"),
        (lambda: lk.helical_onset(EI, W, r, variant="mitchell"), "variant"),
        (lambda: lk.helix_pitch(EI, 0.0), "F"),
        (lambda: lk.helical_wall_force(-1.0, EI, W, r), "F"),
        (lambda: lk.straight_transfer(1.0, -2.0, W, MU), "s"),
        (lambda: lk.helical_transfer(1.0, 2.0, EI, W, r, -0.1), "mu"),
        (lambda: lk.helical_transfer(float("nan"), 2.0, EI, W, r, MU), "F_in"),
        (lambda: lk.sinusoidal_transfer(1.0, 2.0, EI, W, r, MU, law="cubic"), "law"),
        (lambda: lk.far_force(1.0, float("inf"), EI, W, r, MU), "L"),
        (lambda: lk.far_force(1.0, 2.0, EI, W, r, MU, helical_law="x"), "helical_law"),
        (lambda: lk.far_force(1.0, 2.0, EI, W, r, MU, sinusoidal_law="x"), "sinusoidal_law"),
        (lambda: lk.lockup_length(EI, W, r, MU, helical_onset="x"), "helical_onset"),
        (lambda: cf.transfer(1.0, 0.5, 0.0, 0.0), "(a, b)"),
        (lambda: cf.transfer(1.0, -0.5, 1.0, 0.0), "x"),
    ],
)
def test_invalid_input_names_the_argument(call, name):
    with pytest.raises(ValueError, match=r"^" + __import__("re").escape(name) + r" = "):
        call()


def test_the_entry_force_that_pushes_a_far_load_through_the_chain_by_hand():
    """`entry_force` runs the chain backward from the far end: with μL/ℓ = 1, a far load of 0.5 F₀
    needs 1.5 F₀ (straight all along); 2.5 F₀ climbs the sinusoidal section to Chen's onset 2√2 in
    2√2 − 2.5 = 0.328 of friction length, then the helix with the weight term over the remaining
    0.672: f = 2 tan(arctan(√2) + 0.672/2) = 6.963 F₀; above F_far,max = 2 cot(1/2) = 3.661 F₀
    nothing can push it (inf)."""
    L = 1.0 * ELL / MU
    f = lambda ff: float(lk.chain.entry_force(ff * F0, L, *ARGS, MU)) / F0
    assert math.isclose(f(0.5), 1.5, rel_tol=1e-9)
    assert math.isclose(f(0.0), 1.0, rel_tol=1e-12)  # nothing at the far end: the whole rod's friction, μwL
    x_h = 1.0 - (2 * math.sqrt(2) - 2.5)
    assert math.isclose(f(2.5), 2 * math.tan(math.atan(math.sqrt(2)) + x_h / 2), rel_tol=1e-9)
    assert math.isclose(2 / math.tan(0.5), 3.6609754, rel_tol=1e-7)
    assert math.isinf(f(3.7))


@pytest.mark.parametrize("onset", sorted(cf.HELICAL_ONSETS))
@pytest.mark.parametrize("sinusoidal", sorted(cf.SINUSOIDAL_LAWS))
@pytest.mark.parametrize("helical", sorted(cf.HELICAL_LAWS))
def test_far_force_of_entry_force_is_the_far_load(onset, sinusoidal, helical):
    """The round trip far_force(entry_force(F)) = F for every law and onset variant, at μL/ℓ =
    0.5, 1, 2 and 3 and far loads from 0+ to just below F_far,max(L) (every section of the chain
    crossed: straight, sinusoidal, helical), and entry_force = inf above F_far,max."""
    kw = dict(helical_onset=onset, sinusoidal_law=sinusoidal, helical_law=helical)
    for X in (0.5, 1.0, 2.0, 3.0):
        L = X * ELL / MU
        f_max = float(lk.chain.far_force_max(L, *ARGS, MU, **kw)) / F0
        loads = [f for f in (0.05, 0.5, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0) if f < 0.999 * f_max] + [0.999 * f_max]
        for f in loads:
            F_in = lk.chain.entry_force(f * F0, L, *ARGS, MU, **kw)
            assert np.isfinite(float(F_in)) and float(F_in) >= f * F0
            back = float(lk.chain.far_force(F_in, L, *ARGS, MU, **kw)) / F0
            assert math.isclose(back, f, rel_tol=1e-9, abs_tol=1e-12), (X, f, float(F_in) / F0, back)
        if math.isfinite(f_max):
            assert math.isinf(float(lk.chain.entry_force(1.001 * f_max * F0, L, *ARGS, MU, **kw)))
