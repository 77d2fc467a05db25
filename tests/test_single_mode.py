import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import event_driven_reference

import jaxrod as jr
from jaxrod import theory as th


def exact_traj(model, A0, v0, T, n):
    return jr.simulate(model, jr.Exact(), A0, v0, T, n_save=n)


# -- The exact solution against an independent event-driven diffrax integration ------------

@pytest.mark.parametrize(
    "case, A0, v0, k, f_s, f_d, T, expect_stuck, min_phases",
    [
        ("loaded slip to stick", 0.0, 0.6, -4.0, 2.0, 2.0, 2.0, True, 1),
        ("loaded, static > dynamic", 0.1, -0.9, -4.0, 2.6, 2.0, 2.0, True, 1),
        ("reversals then stick", 1.0, 0.0, 25.0, 3.0, 2.0, 4.5, True, 6),
        ("reversals, mu_s = mu_d", 0.0, 3.0, 9.0, 1.0, 1.0, 4.0, False, 3),
        ("zero stiffness", 0.3, 0.5, 0.0, 1.0, 0.5, 2.0, True, 1),
        ("loaded runaway", 0.0, 1.5, -4.0, 2.0, 2.0, 1.0, False, 1),
    ],
)
def test_exact_matches_event_driven_reference(case, A0, v0, k, f_s, f_d, T, expect_stuck, min_phases):
    ts = np.linspace(0.0, T, 201)
    A_ref, v_ref, n_ref = event_driven_reference(A0, v0, k, f_s, f_d, ts)
    sol = exact_traj(jr.SingleMode(k, f_s, f_d), A0, v0, T, 201)
    scale = max(np.max(np.abs(A_ref)), 1e-3)
    np.testing.assert_allclose(sol.q, A_ref, atol=1e-9 * scale)
    np.testing.assert_allclose(sol.v, v_ref, atol=1e-9 * max(np.max(np.abs(v_ref)), 1.0))
    assert bool(sol.stuck[-1]) == expect_stuck
    assert n_ref >= min_phases and int(sol.n_steps) >= min_phases
    assert int(sol.result) == jr.RESULTS.successful


def test_exact_is_smooth_through_zero_stiffness():
    """The Stumpff-function form has no singularity at k = 0 (values and forward gradients)."""
    f = lambda k: jr.exact_solution(0.2, 0.7, k, 1.0, 1.0, 0.3)[0]
    vals = [float(f(k)) for k in (-1e-9, 0.0, 1e-9)]
    assert max(vals) - min(vals) < 1e-9
    g = jax.jacfwd(f)(0.0)
    fd = (f(1e-5) - f(-1e-5)) / 2e-5
    assert bool(jnp.isfinite(g)) and float(g) == pytest.approx(float(fd), rel=1e-6)


def test_coulomb_oscillator_keeps_period_and_loses_4f_over_k_per_cycle():
    """PHYSICS.md §6, measured on a fine projected-Verlet run (independent of the closed form)."""
    k, f = 16.0, 0.5  # omega = 4, amplitude drops 2f/k = 0.0625 per half cycle
    sol = jr.simulate(jr.SingleMode(k, f, f), jr.ProjectedVerlet(1e-5), 1.0, 0.0, 4.0, n_save=40001)
    A, ts = np.asarray(sol.q), np.asarray(sol.ts)
    ext = [i for i in range(1, len(A) - 1) if abs(A[i]) >= abs(A[i - 1]) and abs(A[i]) > abs(A[i + 1])]
    ext = [0] + ext
    amps = np.abs(A[ext])
    assert len(ext) >= 6
    np.testing.assert_allclose(np.diff(amps)[:6], -2 * f / k, atol=2e-4)
    np.testing.assert_allclose(np.diff(ts[ext])[:6], math.pi / 4, atol=2e-4)


# -- Projected Verlet ------------------------------------------------------------------------

def _order(model, A0, v0, T, dts):
    ref = exact_traj(model, A0, v0, T, 11)
    errs = []
    for dt in dts:
        sol = jr.simulate(model, jr.ProjectedVerlet(dt), A0, v0, T, n_save=11)
        errs.append(float(jnp.max(jnp.abs(sol.q - ref.q))))
    return np.polyfit(np.log(dts), np.log(errs), 1)[0], errs


def test_projected_verlet_second_order_on_loaded_slip_to_stick():
    model = jr.SingleMode(-4.0, 2.5, 2.0)  # k < 0, static > dynamic
    dts = [4e-3 / 2**i for i in range(5)]
    p, errs = _order(model, 0.0, 0.6, 3.0, dts)
    assert exact_traj(model, 0.0, 0.6, 3.0, 2).stuck[-1]
    assert p >= 1.8, (p, errs)


def test_projected_verlet_first_order_with_many_reversals():
    model = jr.SingleMode(25.0, 2.0, 2.0)
    dts = [1e-2 / 2**i for i in range(6)]
    p, errs = _order(model, 1.0, 0.0, 2.0, dts)
    assert int(exact_traj(model, 1.0, 0.0, 2.0, 2).n_steps) >= 4
    assert p >= 0.9, (p, errs)


def test_projected_verlet_sticks_exactly():
    model = jr.SingleMode(-4.0, 2.5, 2.0)
    sol = jr.simulate(model, jr.ProjectedVerlet(1e-3), 0.0, 0.6, 3.0, n_save=3001)
    stuck = np.asarray(sol.stuck)
    first = int(np.argmax(stuck))
    assert stuck[first:].all() and first > 0
    assert np.all(np.asarray(sol.v)[first:] == 0.0)  # exactly zero, not small
    assert np.all(np.asarray(sol.q)[first:] == np.asarray(sol.q)[first])  # no creep at all
    # a state on the stick line (|kA| <= f_s) released from rest never moves
    rest = jr.simulate(model, jr.ProjectedVerlet(1e-3), 0.6, 0.0, 5.0, n_save=51)
    assert np.all(np.asarray(rest.q) == 0.6) and np.all(np.asarray(rest.v) == 0.0)


def test_vmapped_classification_matches_analytic_stable_zone():
    k, f = -4.0, 2.0
    lam, a = 2.0, 0.5
    dt = 3e-3
    n = 48
    A = jnp.linspace(-3 * a, 3 * a, n)
    V = jnp.linspace(-3 * lam * a, 3 * lam * a, n)
    AA, VV = (x.ravel() for x in jnp.meshgrid(A, V))
    model = jr.SingleMode(k, f, f)

    def stable(q0, v0):
        sol = jr.simulate(model, jr.ProjectedVerlet(dt), q0, v0, 15.0, n_save=2, throw=False)
        return sol.stuck[-1]

    num = np.asarray(jax.vmap(stable)(AA, VV))
    zone = np.asarray(th.in_stable_zone(AA, VV, k, f))
    # Band: points whose analytic label changes within two steps' worth of phase-plane motion.
    d = 2 * lam * dt
    near = np.zeros_like(zone)
    for sa in (-1, 0, 1):
        for sv in (-1, 0, 1):
            near |= np.asarray(th.in_stable_zone(AA + sa * d * a, VV + sv * d * lam * a, k, f)) != zone
    assert zone.sum() > 100 and (~zone).sum() > 100
    assert near.mean() < 0.1
    np.testing.assert_array_equal(num[~near], zone[~near])


@pytest.mark.parametrize("T", [0.3, 3.0])  # mid-slip, and after the mode has stuck
def test_projected_verlet_gradients_match_finite_differences(T):
    def final(p):
        k, f, v0 = p
        sol = jr.simulate(jr.SingleMode(k, f, f), jr.ProjectedVerlet(1e-3), 0.05, v0, T,
                          n_save=2, throw=False, options=jr.RunOptions(early_exit=False))
        return jnp.stack([sol.q[-1], sol.v[-1]])

    p0 = jnp.array([-4.0, 2.0, 0.6])
    J_fwd = jax.jacfwd(final)(p0)
    J_rev = jax.jacrev(final)(p0)
    h = 1e-6
    J_fd = jnp.stack([(final(p0.at[i].add(h)) - final(p0.at[i].add(-h))) / (2 * h) for i in range(3)], 1)
    np.testing.assert_allclose(J_fwd, J_rev, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(J_fwd, J_fd, rtol=1e-5, atol=1e-8)
    assert float(jnp.abs(J_fwd[0]).max()) > 0


def test_vmap_equals_loop_and_never_retraces():
    v0s = jnp.array([0.2, 0.6, 0.9, 1.4])
    ks = jnp.array([-4.0, -3.0, -5.0, 2.0])

    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def batch(ks, v0s):
        run = lambda k, v0: jr.simulate(jr.SingleMode(k, 2.0, 2.0), jr.ProjectedVerlet(1e-3), 0.0, v0, 2.0, n_save=5, throw=False).q
        return jax.vmap(run)(ks, v0s)

    out = batch(ks, v0s)
    batch(ks * 1.1, v0s * 0.9)  # new values, same shapes: no retrace
    for i in range(4):
        single = jr.simulate(jr.SingleMode(ks[i], 2.0, 2.0), jr.ProjectedVerlet(1e-3), 0.0, v0s[i], 2.0, n_save=5)
        np.testing.assert_array_equal(out[i], single.q)


def test_step_above_stability_limit_is_refused():
    model = jr.SingleMode(1e6, 1.0, 1.0)  # omega = 1000 rad/s: limit 2e-3 s
    with pytest.raises(ValueError, match=r"ProjectedVerlet.dt = 0.003 s is above the stability limit"):
        jr.simulate(model, jr.ProjectedVerlet(3e-3), 0.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="SymplecticEuler.dt"):
        jr.simulate(model, jr.SymplecticEuler(3e-3), 0.0, 1.0, 1.0)
    # Under vmap the values are traced: the member gets a result code instead.
    run = jax.vmap(lambda k: jr.simulate(jr.SingleMode(k, 1.0, 1.0), jr.ProjectedVerlet(3e-3), 0.0, 1.0, 1.0, throw=False).result)
    codes = run(jnp.array([1e6, 100.0]))
    assert codes.tolist() == [jr.RESULTS.step_limit, jr.RESULTS.successful]
    with pytest.raises(Exception, match="stability limit"):
        jax.vmap(lambda k: jr.simulate(jr.SingleMode(k, 1.0, 1.0), jr.ProjectedVerlet(3e-3), 0.0, 1.0, 1.0).q)(jnp.array([1e6]))


def test_bad_model_and_driver_inputs():
    with pytest.raises(ValueError, match=r"SingleMode.f_d = .* \[0, f_s\]"):
        jr.SingleMode(-1.0, 1.0, 2.0)
    with pytest.raises(ValueError, match="SingleMode.f_s"):
        jr.SingleMode(-1.0, -1.0, 0.0)
    with pytest.raises(ValueError, match="SingleMode.k"):
        jr.SingleMode(float("nan"), 1.0, 1.0)
    with pytest.raises(ValueError, match="t1 = -1.0"):
        jr.simulate(jr.SingleMode(-1.0, 1.0, 1.0), jr.ProjectedVerlet(1e-3), 0.0, 1.0, -1.0)
    with pytest.raises(ValueError, match="n_save = 1"):
        jr.simulate(jr.SingleMode(-1.0, 1.0, 1.0), jr.ProjectedVerlet(1e-3), 0.0, 1.0, 1.0, n_save=1)
    with pytest.raises(ValueError, match="ProjectedVerlet.dt"):
        jr.ProjectedVerlet(-1e-3)
    # An invalid member inside a vmapped run is flagged, the others complete.
    run = jax.vmap(lambda fd: jr.simulate(jr.SingleMode(-4.0, 1.0, fd), jr.ProjectedVerlet(1e-3), 0.0, 0.1, 1.0, throw=False))
    sol = run(jnp.array([0.5, 2.0]))
    assert sol.result.tolist() == [jr.RESULTS.successful, jr.RESULTS.invalid_input]


# -- The documented failure cases --------------------------------------------------------------

def test_explicit_sharp_sign_chatters_and_never_sticks():
    model = jr.SingleMode(-4.0, 2.0, 2.0)
    dt, T = 1e-3, 3.0
    ref = exact_traj(model, 0.0, 0.6, T, 3001)
    sol = jr.simulate(model, jr.SymplecticEuler(dt), 0.0, 0.6, T, n_save=3001)
    t_stick = float(ref.ts[int(np.argmax(np.asarray(ref.stuck)))])
    late = np.asarray(sol.ts) > t_stick + 0.1
    v = np.asarray(sol.v)[late]
    assert not np.asarray(sol.stuck).any()
    assert np.all(v != 0.0)
    sign_changes = np.count_nonzero(np.diff(np.sign(v)))
    assert sign_changes > 0.4 * v.size  # chatter: a reversal every other step or so
    assert np.max(np.abs(v)) <= 2.5 * dt * 2.0  # ... of size ~ h·f
    # the projected scheme at the same step sticks exactly
    pv = jr.simulate(model, jr.ProjectedVerlet(dt), 0.0, 0.6, T, n_save=3001)
    assert np.all(np.asarray(pv.v)[late] == 0.0)


@pytest.mark.slow  # 20 s of Kvaerno5 over 60 s; test_explicit_sharp_sign_chatters_and_never_sticks runs by default
def test_tanh_creep_turns_a_stable_loaded_state_into_runaway():
    k, f = -4.0, 2.0  # stick line |A| <= 0.5
    model = jr.SingleMode(k, f, f)
    A0 = 0.25
    assert bool(th.in_stable_zone(A0, 0.0, k, f))
    smooth = jr.DiffraxSmooth(jr.Tanh(0.05), diffrax.Kvaerno5(), rtol=1e-8, atol=1e-10)
    short = jr.simulate(model, smooth, A0, 0.0, 1.0, n_save=11)
    long = jr.simulate(model, smooth, A0, 0.0, 60.0, n_save=61)
    # short horizon: looks stuck (creeps only ~ eps |kA| / f per second)
    assert abs(float(short.q[-1]) - A0) < 0.05
    # long horizon: creeps off the stick line and runs away
    assert float(jnp.abs(long.q[-1])) > 20 * f / abs(k)
    assert not np.asarray(long.stuck)[1:].any()  # at rest only at t = 0
    exact = jr.simulate(model, jr.Exact(), A0, 0.0, 60.0, n_save=61)
    assert np.all(np.asarray(exact.q) == A0)


def test_tanh_tends_to_the_sharp_law_on_short_horizons():
    model = jr.SingleMode(25.0, 2.0, 2.0)
    ref = exact_traj(model, 1.0, 0.0, 1.0, 21)
    errs = []
    for eps in (1e-1, 1e-2, 1e-3):
        for solver in (diffrax.Tsit5(), diffrax.Kvaerno5()):
            sol = jr.simulate(model, jr.DiffraxSmooth(jr.Tanh(eps), solver, rtol=1e-9, atol=1e-11), 1.0, 0.0, 1.0, n_save=21)
            errs.append(float(jnp.max(jnp.abs(sol.q - ref.q))))
            # nothing works on the mode: its energy plus what the smooth law dissipated stays E(0)
            np.testing.assert_array_equal(np.asarray(sol.work_in), np.zeros(21))
            assert float(sol.energy_balance_error()) < 1e-6, (eps, solver)
    errs = np.array(errs).reshape(3, 2)
    np.testing.assert_allclose(errs[:, 0], errs[:, 1], rtol=1e-3)  # explicit = implicit
    assert errs[0, 0] > errs[1, 0] > errs[2, 0]
    assert errs[2, 0] < 5e-3


def test_a_smooth_run_out_of_steps_reports_max_steps():
    """`DiffraxSmooth(max_steps=…)` caps the adaptive solver: a run that needs more steps ends
    with the result `max_steps` (and `simulate(throw=True)` raises), not `successful`."""
    model = jr.SingleMode(25.0, 2.0, 2.0)
    capped = jr.DiffraxSmooth(jr.Tanh(1e-2), rtol=1e-9, atol=1e-11, max_steps=8)
    sol = jr.simulate(model, capped, 1.0, 0.0, 1.0, n_save=3, throw=False)
    assert int(sol.result) == jr.RESULTS.max_steps
    with pytest.raises(Exception, match="maximum number of steps"):
        jr.simulate(model, capped, 1.0, 0.0, 1.0, n_save=3)


# -- The friction laws' updates on values worked out by hand (eager, no compilation) ----------

def test_coulomb_update_by_hand_static_then_dynamic_bound():
    """h = 0.5, f_s = 3, f_d = 2: a point at rest holds while |v_trial| ≤ h·f_s = 1.5, a moving
    one stops while |v_trial| ≤ h·f_d = 1; a slipping one loses h·f_d = 1 of speed (all exact in
    binary)."""
    h, f_s, f_d = 0.5, jnp.asarray(3.0), jnp.asarray(2.0)
    v = jnp.asarray([0.0, 1.25, 1.5, -1.5, 1.75, -1.75, 0.75, 1.0, -1.0, 1.25, -1.25, 3.0])
    prev = jnp.asarray([0.0] * 6 + [0.1, 0.1, -0.2, 0.1, -0.1, 0.1])
    want = [0.0, 0.0, 0.0, 0.0, 0.75, -0.75, 0.0, 0.0, 0.0, 0.25, -0.25, 2.0]
    for law in (jr.coulomb_prox, jr.Coulomb().update):
        out = law(v, prev, h, f_s, f_d)
        np.testing.assert_array_equal(out, want)
        assert out.dtype == v.dtype
    np.testing.assert_array_equal(jr.Coulomb().acceleration(jnp.asarray([-2.0, 0.0, 3.0]), f_s, f_d), [-2.0, 0.0, 2.0])


def test_tanh_update_acceleration_and_vector_impulse_by_hand():
    law = jr.Tanh(0.5)
    f_d, h = jnp.asarray(2.0), 0.1
    v = jnp.asarray([-1.0, 0.0, 0.5, 4.0])
    want_a = [2.0 * math.tanh(v_ / 0.5) for v_ in (-1.0, 0.0, 0.5, 4.0)]
    np.testing.assert_allclose(law.acceleration(v, f_d, f_d), want_a, rtol=1e-15)
    # no static bound: the update is the explicit step v − h·f_d·tanh(v/ε), whatever v_prev
    np.testing.assert_allclose(law.update(v, jnp.zeros(4), h, jnp.asarray(9.0), f_d),
                               [v_ - h * a for v_, a in zip((-1.0, 0.0, 0.5, 4.0), want_a)], rtol=1e-15)
    # the vector impulse: norm bound·tanh(|u|/ε), against u; |u| = 5, 0.05 (x = |u|/ε = 10, 0.1)
    # and 5e-6 (x = 1e-5, the series branch), with bound 0.3
    b = jnp.asarray([0.3, 0.3, 0.3])
    u = (jnp.asarray([3.0, 0.03, 3e-6]), jnp.asarray([-4.0, 0.04, 4e-6]))
    (p1, p2), sticks = law.impulse_2d(u, (jnp.ones(3), jnp.zeros(3), jnp.ones(3)), b, b)
    for i, (norm, x) in enumerate(((5.0, 10.0), (0.05, 0.1), (5e-6, 1e-5))):
        mag = 0.3 * math.tanh(x)
        np.testing.assert_allclose([p1[i], p2[i]], [-mag * float(u[0][i]) / norm, -mag * float(u[1][i]) / norm],
                                   rtol=1e-14, err_msg=f"|u| = {norm}")
    assert sticks.dtype == bool and not np.asarray(sticks).any()
    # the 3D rod's friction pass may run in single precision: the impulse stays in it
    u32 = tuple(c.astype(jnp.float32) for c in u)
    b32 = b.astype(jnp.float32)
    (q1, q2), _ = law.impulse_2d(u32, tuple(jnp.ones(3, jnp.float32) for _ in range(3)), b32, b32)
    assert q1.dtype == q2.dtype == jnp.float32
    np.testing.assert_allclose(q1, p1, rtol=1e-6)


def test_vector_coulomb_impulse_with_isotropic_inverse_mass_by_hand():
    """W = w·I: the point sticks with p = −u/w while |u|/w ≤ the stick bound; else it slips with
    the impulse of the slip bound against u; a zero slip bound gives no impulse."""
    w = 2.0
    u = (jnp.asarray([0.3, 3.0, -6.0, 3.0, 1.0]), jnp.asarray([0.4, 4.0, 8.0, 4.0, 0.0]))  # |u| = 0.5, 5, 10, 5, 1
    stick = jnp.asarray([0.25, 2.5, 1.0, 1.0, 0.4])  # |u|/w = 0.25, 2.5, 5, 2.5, 0.5
    slip = jnp.asarray([0.2, 2.0, 0.8, 0.0, 0.3])
    W = (jnp.full(5, w), jnp.zeros(5), jnp.full(5, w))
    (p1, p2), sticks = jr.Coulomb().impulse_2d(u, W, stick, slip)
    np.testing.assert_array_equal(sticks, [True, True, False, False, False])
    np.testing.assert_allclose(p1, [-0.15, -1.5, 0.8 * 0.6, 0.0, -0.3], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(p2, [-0.2, -2.0, -0.8 * 0.8, 0.0, 0.0], rtol=1e-12, atol=1e-15)
    # started from a guess (the last sweep's impulse), the same answer
    (g1, g2), _ = jr.Coulomb().impulse_2d(u, W, stick, slip, guess=(jnp.full(5, 0.1), jnp.full(5, -0.1)))
    np.testing.assert_allclose(g1, p1, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(g2, p2, rtol=1e-12, atol=1e-15)


def _slip_impulse_by_bisection(u, W11, W12, W22, c):
    """The slip impulse p = −(W + λI)⁻¹u with |p| = c, by bisection on λ ≥ 0 in NumPy (|p(λ)|
    falls with λ); for points that do not stick (|W⁻¹u| > c)."""
    def p_of(lam):
        a11, a22 = W11 + lam, W22 + lam
        det = a11 * a22 - W12 * W12
        return -(a22 * u[0] - W12 * u[1]) / det, -(a11 * u[1] - W12 * u[0]) / det

    lo, hi = np.zeros_like(c), np.hypot(*u) / c
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        big = np.hypot(*p_of(mid)) > c
        lo, hi = np.where(big, mid, lo), np.where(big, hi, mid)
    return p_of(0.5 * (lo + hi))


def test_vector_coulomb_impulse_from_poor_and_degenerate_guesses():
    """A guess (the last sweep's impulse) only starts the Newton iterations: from a guess half
    the answer the impulse is within 2 % of the bound of the bisection's (0.8 % measured, for
    inverse masses up to 300× anisotropic); guesses whose λ estimate falls on a pole of
    (W + λI)⁻¹ (−4 here) or far above the bracket (3e150) give the exact impulse; a zero guess
    gives the hand-computed gradient."""
    rng = np.random.default_rng(3)
    N = 200
    a, b, ang = 10 ** rng.uniform(-1, 1.5, N), 10 ** rng.uniform(-1, 1.5, N), rng.uniform(0, np.pi, N)
    W11, W22 = a * np.cos(ang) ** 2 + b * np.sin(ang) ** 2, a * np.sin(ang) ** 2 + b * np.cos(ang) ** 2
    W12 = (a - b) * np.cos(ang) * np.sin(ang)
    u = rng.normal(size=(2, N))
    c = 10 ** rng.uniform(-3, -1.6, N) * np.hypot(*u)  # |W⁻¹u| ≥ |u|/31.6 > c: every point slips
    ref = np.stack(_slip_impulse_by_bisection(u, W11, W12, W22, c))
    args = (tuple(map(jnp.asarray, u)), tuple(map(jnp.asarray, (W11, W12, W22))), jnp.asarray(c), jnp.asarray(c))
    p, sticks = jr.Coulomb().impulse_2d(*args)
    assert not np.asarray(sticks).any()
    assert np.max(np.hypot(*(np.stack(p) - ref)) / c) < 1e-9
    p, _ = jr.Coulomb().impulse_2d(*args, guess=tuple(jnp.asarray(0.5 * r) for r in ref))
    err = np.hypot(*(np.stack(p) - ref)) / c
    assert err.max() < 0.02, err.max()
    # W = diag(1, 4), u = (3, 0), bound 1: p = (−1, 0) at λ = 2, from each of the three guesses
    three = lambda x: jnp.full(3, x)  # noqa: E731
    W, c3 = (three(1.0), three(0.0), three(4.0)), three(1.0)
    guess = (jnp.asarray([1.0, -1e-150, 0.0]), three(0.0))
    (p1, p2), _ = jr.Coulomb().impulse_2d((three(3.0), three(0.0)), W, c3, c3, guess=guess)
    np.testing.assert_allclose(p1, [-1.0] * 3, rtol=1e-12)
    np.testing.assert_allclose(p2, [0.0] * 3, atol=1e-12)
    # ∂p₂/∂u₂ = −(1/(4 + λ))/(u₁/(1 + λ)) = −1/6 there, also from a zero guess (finite: its λ
    # estimate, which would divide by |g|² = 0, is not used)
    zero = (three(0.0), three(0.0))
    d = jax.grad(lambda u2: jr.Coulomb().impulse_2d((three(3.0), u2), W, c3, c3, zero)[0][1].sum())(three(0.0))
    np.testing.assert_allclose(d, [-1 / 6] * 3, rtol=1e-9)


def test_vector_coulomb_impulse_at_a_vanishing_bound_in_float32():
    """A contact whose normal force vanishes (a node lifting off the wall) slips with a bound c
    far below |u|/|W|: the impulse is −c·(W + λI)⁻¹u/|…| with λ ≈ |u|/c, whose unscaled Newton
    step overflowed float32 from c ≈ 1e-12 here (the 3D rod's state became non-finite). In
    float32, from 1e-5 down to 1e-29 and with or without a guess, it is the float64 bisection's
    impulse to 1e-5 of the bound."""
    c = 10.0 ** np.arange(-5.0, -31.0, -3.0)
    k = len(c)
    u = np.stack([np.full(k, 0.8), np.full(k, 0.1)])
    W11, W12, W22 = np.full(k, 2e3), np.full(k, 300.0), np.full(k, 3e3)  # 1/kg, as the 3D rod's nodes
    ref = np.stack(_slip_impulse_by_bisection(u, W11, W12, W22, c))
    f32 = lambda a: jnp.asarray(a, jnp.float32)  # noqa: E731
    args = (tuple(map(f32, u)), tuple(map(f32, (W11, W12, W22))), f32(c), f32(c))
    for guess in (None, (f32(0.5 * ref[0]), f32(0.0 * c))):
        p, sticks = jr.Coulomb().impulse_2d(*args, guess=guess)
        assert not np.asarray(sticks).any()
        err = np.hypot(*(np.stack(p).astype(np.float64) - ref)) / c
        assert np.all(np.isfinite(err)) and err.max() < 1e-5, err


def test_linear_flow_is_the_exact_free_motion():
    """`linear_flow` (the exponential integrator's linear part): A(h) = A cos ωh + Ȧ sin(ωh)/ω
    for k = ω² > 0 and cosh/sinh for k < 0, on both sides of the Stumpff series' switch (kh² = 1e-3)."""
    for k, h in ((400.0, 1e-3), (400.0, 0.05), (-900.0, 0.02), (-900.0, 1e-4)):
        m = jr.SingleMode(k=k, f_s=0.0, f_d=0.0)
        A, Ad = m.linear_flow(jnp.asarray(0.3), jnp.asarray(-2.0), 0.0, h)
        w = math.sqrt(abs(k))
        if k > 0:
            ref = (0.3 * math.cos(w * h) - 2.0 * math.sin(w * h) / w, -0.3 * w * math.sin(w * h) - 2.0 * math.cos(w * h))
        else:
            ref = (0.3 * math.cosh(w * h) - 2.0 * math.sinh(w * h) / w, 0.3 * w * math.sinh(w * h) - 2.0 * math.cosh(w * h))
        assert (float(A), float(Ad)) == pytest.approx(ref, rel=1e-12, abs=1e-14)


def test_atan_ratio_and_the_slip_phase_duration_by_hand():
    """T(y) = atan(√y)/√y (atanh for y < 0) on both sides of its series' switch |y| = 1e-3, and
    the time a slip decelerated by ĝ > 0 against k = ω² > 0 takes to stop: atan(v̂ω/ĝ)/ω."""
    from jaxrod.models.single_mode import _atan_ratio, _phase_duration

    for y in (5e-4, -5e-4, 0.3, -0.3, 4.0):
        r = math.sqrt(abs(y))
        ref = math.atan(r) / r if y > 0 else math.atanh(r) / r
        assert float(_atan_ratio(jnp.asarray(y))) == pytest.approx(ref, rel=1e-14)
    for v, g, k in ((1.0, 0.5, 4.0), (0.2, 3.0, 100.0)):
        w = math.sqrt(k)
        assert float(_phase_duration(jnp.asarray(v), jnp.asarray(g), jnp.asarray(k))) == pytest.approx(
            math.atan(v * w / g) / w, rel=1e-12)
    # past the frictionless load (k = −s² < 0) a weak deceleration still stops it, at atanh(v s/g)/s
    for v, g, k in ((0.5, 0.8, -1.0), (0.1, 2.0, -9.0)):
        s_ = math.sqrt(-k)
        assert float(_phase_duration(jnp.asarray(v), jnp.asarray(g), jnp.asarray(k))) == pytest.approx(
            math.atanh(v * s_ / g) / s_, rel=1e-12)
    assert math.isinf(float(_phase_duration(jnp.asarray(2.0), jnp.asarray(0.8), jnp.asarray(-1.0))))  # v s > g
    # at the edge of T's domain, y = −1 (v s = g, reached by rounding), atanh is taken just below 1: finite
    assert float(_atan_ratio(jnp.asarray(-1.0))) == pytest.approx(math.atanh(1.0 - 2.0**-53), rel=1e-12)


def test_galerkin_energy_terms_are_the_field_integrals():
    """The Galerkin model's energies by name (what `Solution.energies` reports) against the
    integrals of its field θ(s) = Σ q_k sin(kπs/L), evaluated here by quadrature on a fine grid:
    kinetic ½ρR²∫θ_t², bending ½EI R²∫θ_ss², gravity ½wR∫θ² (the small-angle w R (1 − cos θ)) and
    the load's −½F R²∫θ_s²."""
    rod = jr.RodChannel.reference(0.3)
    F = float(th.reference_load(rod))
    m = jr.GalerkinModel.from_rod(rod, 4, F=F)
    q, v = np.array([1e-3, 0.0, -2e-3, 0.0]), np.array([0.1, 0.2, 0.0, -0.1])
    L, R, EI, rho, w = (float(x) for x in (rod.L, rod.R, rod.EI, rod.rho, rod.w))
    s = np.linspace(0.0, L, 20001)
    k = np.arange(1, 5)[:, None] * np.pi / L
    S, C = np.sin(k * s), np.cos(k * s)
    integral = lambda f: float(np.trapezoid(f, s))  # noqa: E731
    expected = dict(kinetic=0.5 * rho * R**2 * integral((v @ S) ** 2),
                    bending=0.5 * EI * R**2 * integral((-(q[:, None] * k**2) * S).sum(0) ** 2),
                    gravity=0.5 * w * R * integral((q @ S) ** 2),
                    load=-0.5 * F * R**2 * integral(((q[:, None] * k) * C).sum(0) ** 2))
    e = m.energy_terms(jnp.asarray(q), jnp.asarray(v), 0.0)
    assert set(e) == set(expected)
    for name, value in expected.items():
        assert float(e[name]) == pytest.approx(value, rel=1e-6), name
    assert float(m.kinetic_energy(jnp.asarray(v))) == pytest.approx(expected["kinetic"], rel=1e-6)


@pytest.mark.parametrize("z", [9e-4, -9e-4])
def test_the_stumpff_series_below_the_switch_is_the_closed_form_to_rounding(z):
    """c₀ = cos√z, c₁ = sin√z/√z, c₂ = 2 sin²(√z/2)/z (cosh, sinh for z < 0): below |z| = 1e-3 the
    series through z³ is used, whose next terms are below 1e-17 there, so it agrees with the closed
    forms (each accurate to a few units in the last place here) to 1e-15."""
    from jaxrod.models.single_mode import _stumpff

    r = math.sqrt(abs(z))
    if z > 0:
        ref = (math.cos(r), math.sin(r) / r, 2 * math.sin(r / 2) ** 2 / z)
    else:
        ref = (math.cosh(r), math.sinh(r) / r, 2 * math.sinh(r / 2) ** 2 / abs(z))
    for g, want in zip(_stumpff(jnp.asarray(z)), ref):
        assert float(g) == pytest.approx(want, rel=1e-15, abs=0)


def test_the_exact_solution_buckles_at_the_first_save_over_the_threshold():
    """A growing mode (k < 0) run by `Exact` past a threshold of 0.5: `t_buckle` and `t_stop` are
    the time of the first save whose amplitude is over it (a scalar); with a threshold it never
    reaches, not buckled, `t_buckle` inf and `t_stop` the horizon."""
    model = jr.SingleMode(-4.0, 0.5, 0.5)
    sol = jr.simulate(model, jr.Exact(), 0.1, 1.0, 3.0, n_save=31, options=jr.RunOptions(buckle_threshold=0.5))
    ts, amp = np.asarray(sol.ts), np.asarray(sol.amplitude)
    first = int(np.flatnonzero(amp > 0.5)[0])
    assert 0 < first < 30 and bool(sol.buckled) and np.shape(sol.t_buckle) == ()
    assert float(sol.t_buckle) == float(sol.t_stop) == ts[first]
    never = jr.simulate(model, jr.Exact(), 0.1, 1.0, 3.0, n_save=31, options=jr.RunOptions(buckle_threshold=1e9))
    assert not bool(never.buckled) and float(never.t_buckle) == np.inf and float(never.t_stop) == 3.0
