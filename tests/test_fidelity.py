"""Random perturbations belong to the scene: the same key gives the same field at every model
resolution (issue [fidelity])."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import boundary as bd
from jaxrod.perturbations import (RandomForce, RandomShape, RandomVelocity, SineVelocity, UserState, project_to_mode,
                                  scene_noise, scene_noise_modes)

ROD = jr.RodChannel.reference(mu=0.3)
KEY = jax.random.key(7)


def _modes(theta, m_max):
    return np.array([float(project_to_mode(theta, m)) for m in range(1, m_max + 1)])


@pytest.mark.parametrize("cls", [RandomVelocity, RandomShape])
def test_modal_amplitudes_do_not_depend_on_the_model_resolution(cls):
    """Modes 1-32 of the field on 192 and 384 nodes agree to 1e-12 (they drifted as 1/√n with
    per-node noise), and equal the sine coefficients of the 500-segment nodal field."""
    p = cls(0.015, KEY)
    per_n = []
    for n in (192, 384):
        m = jr.FieldModel.from_rod(ROD, n, dF=5.0)
        y, v = p.fields(m)
        per_n.append(_modes(v if cls is RandomVelocity else y, 32))
    np.testing.assert_allclose(per_n[0], per_n[1], rtol=0, atol=1e-12 * 0.015)
    # the coefficients of the nodal field on the paper's grid, computed independently here
    r = np.asarray(jax.random.uniform(KEY, (499,), jnp.float64, -1.0, 1.0)) * 0.015
    j = np.arange(1, 500)
    c = np.array([2 / 500 * np.sum(r * np.sin(np.pi * m * j / 500)) for m in range(1, 33)])
    np.testing.assert_allclose(per_n[1], c, rtol=0, atol=1e-12 * 0.015)
    # the old per-node noise is still there (grid=None), and it does depend on n
    old = [_modes(cls(0.015, KEY, grid=None).fields(jr.FieldModel.from_rod(ROD, n, dF=5.0))[1 if cls is RandomVelocity else 0], 32)
           for n in (192, 384)]
    assert np.max(np.abs(old[0] - old[1])) > 1e-4 * 0.015


def test_the_scene_field_on_its_own_grid_is_the_nodal_draw():
    """Evaluated at the 499 nodes of the 500-segment grid, the series gives back the draw."""
    s = jnp.arange(1, 500, dtype=jnp.float64) * (3.0 / 500)
    f = scene_noise(KEY, 0.015, s, 3.0)
    r = jax.random.uniform(KEY, (499,), jnp.float64, -1.0, 1.0) * 0.015
    np.testing.assert_allclose(f, r, rtol=0, atol=1e-14)


def test_galerkin_and_single_mode_get_the_same_modes():
    p = RandomVelocity(0.015, KEY)
    field = jr.FieldModel.from_rod(ROD, 384, dF=5.0)
    c = _modes(p.fields(field)[1], 12)
    gal = jr.GalerkinModel.from_rod(ROD, 12, dF=5.0)
    _, v = p.initial_state(gal)
    np.testing.assert_allclose(np.asarray(v) * float(ROD.R), c, rtol=1e-9, atol=1e-12)
    sc = jr.scene.Scene(ROD, 5.0, p, "mode", mode=6)
    _, v6 = sc.initial_state()
    assert float(v6) * float(ROD.R) == pytest.approx(c[5], rel=1e-9, abs=1e-14)


@pytest.mark.parametrize("kind,amplitude,ns", [("random-position", 2.0, (192, 384)),
                                                ("random-velocity", 15e-3, (499, 768))])
def test_critical_load_of_a_random_perturbation_converges_in_n(kind, amplitude, ns):
    """ΔF* at μ = 0.3 for one seed changes by less than 2 % between two resolutions. A random
    velocity needs every mode of the scene's field resolved (n ≥ 499): its high modes vibrate
    and release static friction, so fewer nodes see a stiffer rod (17.95, 14.87 N at 128, 256
    nodes; 12.95, 13.10 N at 499, 768), which is why the scene's default n is 499 for it."""
    roots = []
    for n in ns:  # the finer search starts from the coarser one's root (a departure confirms it)
        r, _ = bd.critical_load(ROD, amplitude, perturbation=kind, n=n, key=jax.random.key(3),
                                bracket=(0.1, 100.0), rtol=1e-4, sensitivities=(), start=roots[0] if roots else None)
        assert int(r.result) == 0
        roots.append(float(r.root))
    print(kind, f"dF* at n = {ns}:", roots)
    assert abs(roots[1] / roots[0] - 1) < 0.02
    assert jr.scene.Scene(ROD, 5.0, jr.registry.make_perturbation(kind, amplitude), "field").size() >= (
        499 if kind == "random-velocity" else 128)


def test_a_failed_search_names_no_root():
    """A bracket without the root: NaN with the result code, for every model."""
    r, _ = bd.critical_velocity(ROD, 5.0, model="field", n=32, bracket=(0.2, 1.0), sensitivities=())
    assert int(r.result) == bd.ROOT_RESULTS.invalid_bracket and np.isnan(float(r.root))
    r, _ = bd.critical_velocity(ROD, 5.0, model="mode", bracket=(0.2, 1.0), sensitivities=())
    assert int(r.result) == bd.ROOT_RESULTS.invalid_bracket and np.isnan(float(r.root))
    r, _ = bd.critical_load(ROD, 15e-3, model="mode", bracket=(50.0, 100.0), sensitivities=())
    assert int(r.result) == bd.ROOT_RESULTS.invalid_bracket and np.isnan(float(r.root))


def test_the_3d_rod_gets_the_same_modes_at_its_nodes():
    """The 3D rod's lateral node velocities carry the same modes 1-12 as the field model's
    nodal field (the 3D rod's n − 1 interior nodes resolve modes up to n − 1); its random
    position pulse: tests/test_rod3d_random_position.py."""
    p = RandomVelocity(0.015, KEY)
    c = _modes(p.fields(jr.FieldModel.from_rod(ROD, 384, dF=5.0))[1], 12)
    sc = jr.scene.Scene(ROD, 5.0, p, "rod3d", n=40, dt=1e-6)  # dt given: no step-limit compilation
    q, v = sc.initial_state()
    lateral = np.asarray(v.v[1:-1, 1])  # on the straight rod at the bottom, along y
    np.testing.assert_allclose(_modes(jnp.asarray(lateral), 12), c, rtol=0, atol=1e-12 * 0.015)
    assert np.all(np.asarray(v.v)[[0, -1]] == 0.0)


# -- perturbations on values worked out by hand (eager, no compilation) ------------------------

def _coefficients(r, grid, modes):
    """c_m = (2/grid) Σ_j r_j sin(mπj/grid), in NumPy."""
    j = np.arange(1, grid)
    return np.array([2 / grid * np.sum(r * np.sin(np.pi * m * j / grid)) for m in range(1, modes + 1)])


def test_scene_noise_on_a_small_grid_by_hand():
    """grid = 8: the draw on its 7 nodes, its 7 sine coefficients, and the series truncated to
    the modes asked for (or to what the points resolve, at most grid − 1)."""
    L, amp = 3.0, 0.015
    r = np.asarray(jax.random.uniform(KEY, (7,), jnp.float64, -1.0, 1.0)) * amp
    c = _coefficients(r, 8, 7)
    got = scene_noise_modes(KEY, amp, 8)
    assert got.shape == (7,) and got.dtype == jnp.float64
    np.testing.assert_allclose(got, c, rtol=0, atol=1e-15)
    np.testing.assert_allclose(scene_noise_modes(KEY, amp, 8, 3), c[:3], rtol=0, atol=1e-15)
    nodes = jnp.arange(1, 8, dtype=jnp.float64) * (L / 8)
    np.testing.assert_allclose(scene_noise(KEY, amp, nodes, L, grid=8), r, rtol=0, atol=1e-15)

    def series(s, modes):
        return np.array([np.sum(c[:modes] * np.sin(np.pi * np.arange(1, modes + 1) * x / L)) for x in s])

    s4 = jnp.asarray([0.2, 1.1, 1.7, 2.9])
    np.testing.assert_allclose(scene_noise(KEY, amp, s4, L, grid=8), series(s4, 4), rtol=0, atol=1e-15)
    np.testing.assert_allclose(scene_noise(KEY, amp, s4, L, grid=8, modes=2), series(s4, 2), rtol=0, atol=1e-15)
    s10 = jnp.linspace(0.1, 2.9, 10)
    np.testing.assert_allclose(scene_noise(KEY, amp, s10, L, grid=8), series(s10, 7), rtol=0, atol=1e-15)
    # per-point noise (grid=None): a uniform draw at the points themselves
    np.testing.assert_array_equal(scene_noise(KEY, amp, s4, L, grid=None),
                                  jax.random.uniform(KEY, (4,), jnp.float64, -1.0, 1.0) * amp)
    # a grid of two segments has one node and one mode; fewer, or not an int, is refused
    np.testing.assert_allclose(scene_noise(KEY, amp, s4, L, grid=2),
                               float(jax.random.uniform(KEY, (1,), jnp.float64, -1.0, 1.0)[0]) * amp
                               * np.sin(np.pi * np.asarray(s4) / L), rtol=0, atol=1e-15)
    for bad in (1, 0, 8.0):
        with pytest.raises(ValueError, match=rf"^grid = {bad!r} is invalid: expected an int >= 2 \(segments\) or None\.$"):
            scene_noise(KEY, amp, s4, L, grid=bad)


def test_sine_velocity_user_state_and_mode_projection_by_hand():
    rod = ROD
    R = float(rod.R)
    # 5 nodes at s = jL/6: mode 3 is sin(πj/2) = 1, 0, −1, 0, 1
    m5 = jr.FieldModel.from_rod(rod, 5, dF=5.0)
    q, v = SineVelocity(0.01, 3).initial_state(m5)
    np.testing.assert_array_equal(q, np.zeros(5))
    np.testing.assert_allclose(v, np.array([1, 0, -1, 0, 1]) * 0.01 / R, rtol=1e-14, atol=1e-13)
    # the default mode is 6: on 11 nodes (s = jL/12) sin(πj/2) again
    q, v = SineVelocity(0.02).initial_state(jr.FieldModel.from_rod(rod, 11, dF=5.0))
    np.testing.assert_allclose(v, np.array([1, 0, -1, 0] * 2 + [1, 0, -1]) * 0.02 / R, rtol=1e-14, atol=1e-13)
    assert SineVelocity(1, 2).amplitude.dtype == jnp.float64 and SineVelocity(1, 2).mode.dtype == jnp.float64
    # a state given in the model's coordinates is the initial state as it is; its fields are in metres
    q0, v0 = jnp.asarray([0.1, -0.2, 0.0, 0.3, 0.05]), jnp.asarray([1.0, 0.0, -2.0, 0.5, 0.25])
    us = UserState(q0, v0)
    q, v = us.initial_state(m5)
    np.testing.assert_array_equal(q, q0)
    np.testing.assert_array_equal(v, v0)
    y, u = us.fields(m5)
    np.testing.assert_allclose(y, np.asarray(q0) * R, rtol=1e-15)
    np.testing.assert_allclose(u, np.asarray(v0) * R, rtol=1e-15)
    # discrete orthogonality on 7 nodes: 0.3 sin(2πj/8) + 0.1 sin(5πj/8) has amplitudes 0.3, 0.1
    j = jnp.arange(1, 8, dtype=jnp.float64)
    theta = 0.3 * jnp.sin(2 * jnp.pi * j / 8) + 0.1 * jnp.sin(5 * jnp.pi * j / 8)
    np.testing.assert_allclose([float(project_to_mode(theta, m)) for m in (1, 2, 3, 5)], [0.0, 0.3, 0.0, 0.1],
                               rtol=0, atol=1e-15)
    assert float(project_to_mode(theta, 2.0)) == pytest.approx(0.3, abs=1e-15)  # a float mode too


def test_random_force_over_a_duration_that_is_not_a_whole_number_of_steps():
    """The forcing phase lasts exactly `duration` (1.3 ms with a 0.1 ms step: 13 steps of 0.1 ms
    would fall short or overshoot by rounding; 14 of 1.3/14 ms are taken): on the frictionless
    loaded rod the shape equals the exact forced response (matrix exponential) within the
    scheme's error, and a zero duration leaves the rod straight."""
    import scipy.linalg as sl

    rod = ROD.with_friction(0.0, 0.0)
    model = jr.FieldModel.from_rod(rod, 16, dF=5.0)
    for duration in (1.3e-3,):
        pert = RandomForce(2.0, KEY, duration=duration)
        q, v = pert.initial_state(model, jr.ProjectedVerlet(1e-4))
        assert np.all(np.asarray(v) == 0)
        force, _ = pert.fields(model)
        ext = np.asarray(force) / float(rod.rho * rod.R)
        zero = jnp.zeros(16)
        A = np.asarray(jax.jacfwd(lambda x: model.acceleration(x, 0.0))(zero))
        n = 16
        M = np.zeros((2 * n + 1, 2 * n + 1))
        M[:n, n:2 * n], M[n:2 * n, :n], M[n:2 * n, 2 * n] = np.eye(n), A, ext + np.asarray(model.acceleration(zero, 0.0))
        exact = (sl.expm(M * duration) @ np.r_[np.zeros(2 * n), 1.0])[:n]
        err = np.max(np.abs(np.asarray(q) - exact)) / np.max(np.abs(exact))
        print(f"duration {duration}: relative error {err:.2e}")
        assert err < 2e-3
    q, v = RandomForce(2.0, KEY, duration=0.0).initial_state(model, jr.ProjectedVerlet(1e-4))
    np.testing.assert_array_equal(q, np.zeros(16))


def test_the_forcing_phase_model_is_the_rod_plus_a_constant_acceleration():
    """`RandomForce`'s forcing phase runs the model with a constant extra acceleration and
    everything else of the rod unchanged: friction bounds μ·g/R (N = ρg), the kinetic energy
    ½ρR²Δ Σθ̇², the energies, the step limit; the module's `initial_state` is the
    perturbation's."""
    from jaxrod.models.dof import _Forced
    from jaxrod.perturbations import initial_state

    F0 = float(jr.theory.reference_load(ROD))
    model = jr.FieldModel.from_rod(ROD, 5, F=jr.loads.RampLoad(F0, F0 + 10.0, 0.0, 1.0))  # the load varies in t
    extra = jnp.asarray([1.0, -2.0, 0.5, 0.0, 3.0])
    forced = _Forced(model, extra)
    q, v = jnp.asarray([0.01, 0.02, -0.01, 0.0, 0.03]), jnp.asarray([0.5, -0.25, 0.0, 1.0, -2.0])
    np.testing.assert_allclose(forced.acceleration(q, 0.1), np.asarray(model.acceleration(q, 0.1)) + np.asarray(extra),
                               rtol=1e-14)
    g_R = float(ROD.g) / float(ROD.R)
    f_s, f_d = forced.friction_bounds(0.0)
    assert float(f_s) == pytest.approx(float(ROD.mu_s) * g_R, rel=1e-14)
    assert float(f_d) == pytest.approx(float(ROD.mu_d) * g_R, rel=1e-14)
    np.testing.assert_allclose(forced.friction_acceleration(jr.Coulomb(), v, 0.0),
                               float(ROD.mu_d) * g_R * np.sign(np.asarray(v)), rtol=1e-14)
    # one step of h = 1e-3 from rest: held while |v_trial| ≤ h·μ_s·g/R (≈ 0.27 rad/s here)
    h = 1e-3
    out = forced.friction_update(jr.Coulomb(), v, jnp.zeros(5), h, 0.0)
    want = np.where(np.abs(np.asarray(v)) <= h * float(f_s), 0.0, np.asarray(v) - h * float(f_d) * np.sign(np.asarray(v)))
    np.testing.assert_allclose(out, want, rtol=1e-14)
    spacing = float(ROD.L) / 6
    assert float(forced.kinetic_energy(v)) == pytest.approx(
        0.5 * float(ROD.rho) * float(ROD.R) ** 2 * spacing * float(np.sum(np.asarray(v) ** 2)), rel=1e-13)
    assert float(forced.max_frequency()) == float(model.max_frequency())
    e_f, e_m = forced.energy_terms(q, v, 0.1), model.energy_terms(q, v, 0.1)
    assert set(e_f) == set(e_m) and all(float(e_f[k]) == float(e_m[k]) for k in e_m)
    pert = RandomForce(2.0, KEY, duration=2e-5)
    for a, b in zip(initial_state(pert, model, jr.ProjectedVerlet(1e-5)), pert.initial_state(model, jr.ProjectedVerlet(1e-5))):
        np.testing.assert_array_equal(a, b)


def test_random_force_on_a_ramped_load_sees_the_load_at_each_step():
    """Forcing the frictionless rod while its load ramps by 400 N over the 1.3 ms pulse: the
    shape equals an independent high-order integration (SciPy's DOP853 at rtol 1e-11) within
    3e-4 of max|q| (3.2e-5 measured at a 1e-5 s step); under the initial load held constant it
    would be 22 % off. A non-fixed-step integrator is refused with a one-line error."""
    from scipy.integrate import solve_ivp

    rod = ROD.with_friction(0.0, 0.0)
    F0 = float(jr.theory.reference_load(rod))
    duration = 1.3e-3
    model = jr.FieldModel.from_rod(rod, 16, F=jr.loads.RampLoad(F0, F0 + 400.0, 0.0, duration))
    pert = RandomForce(2.0, KEY, duration=duration)
    q, v = pert.initial_state(model, jr.ProjectedVerlet(1e-5))
    ext = np.asarray(pert.fields(model)[0]) / float(rod.rho * rod.R)
    acc = jax.jit(lambda x, t: model.acceleration(x, t))
    sol = solve_ivp(lambda t, y: np.r_[y[16:], np.asarray(acc(jnp.asarray(y[:16]), t)) + ext], (0.0, duration),
                    np.zeros(32), method="DOP853", rtol=1e-11, atol=1e-16)
    ref = sol.y[:16, -1]
    assert np.max(np.abs(np.asarray(q) - ref)) < 3e-4 * np.max(np.abs(ref))
    assert np.all(np.asarray(v) == 0)
    with pytest.raises(TypeError, match=r"^RandomForce needs the run's fixed-step integrator \(e\.g\. ProjectedVerlet\) "
                                        r"to integrate its forcing phase; got Exact\.$"):
        pert.initial_state(model, jr.Exact())


def test_noise_fields_keep_the_points_dtype_and_the_3d_rod_gets_only_its_resolved_modes():
    """Single-precision sample points give a single-precision field (both noise paths); the 3D
    rod's n + 1 nodes (ends included) carry the modes 1..n − 1 of the scene's field only (mode n
    vanishes at the nodes and mode n + 1 would alias onto mode 1)."""
    s32 = jnp.asarray([0.2, 1.1, 1.7, 2.9], jnp.float32)
    for grid in (None, 8):
        assert scene_noise(KEY, 0.015, s32, 3.0, grid=grid).dtype == jnp.float32, grid
    assert scene_noise_modes(KEY, 0.015, 8, dtype=jnp.float32).dtype == jnp.float32
    from jaxrod.rod3d import Rod3D

    n = 8
    m = Rod3D(ROD, n)
    r = np.asarray(jax.random.uniform(KEY, (499,), jnp.float64, -1.0, 1.0)) * 0.015
    c = _coefficients(r, 500, n - 1)
    j = np.arange(n + 1)
    want = np.array([np.sum(c * np.sin(np.pi * np.arange(1, n) * jj / n)) for jj in j])
    y, v = RandomShape(0.015, KEY).fields(m)
    np.testing.assert_allclose(y, want, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(v, np.zeros(n + 1))
