"""The 3D discrete rod against beam theory, Euler's load, energy conservation and Coulomb's law.
Each compiled 3D run costs 5–7 s of compilation: the Euler load, the energy convergence and the
sharp-law gradient (several step sizes or laws each) are `slow`; `tests/test_engine.py` runs the
3D rod through `simulate` under jit and vmap and checks its energy balance in the default suite."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D, step_limit
from jaxrod.rod3d.so3 import exp_so3, log_so3


def simulate_rod3d(model, state, t1, n_save, *, dt=None, dt_fraction=0.5, law=jr.Coulomb(), scheme=None, **options):
    """The 3D rod through the one `jaxrod.simulate`, with its step `dt_fraction` of the
    explicit limit at the initial state, with the explicit scheme (projected leapfrog: the
    reference these tests hold the model to; the implicit default has its own,
    tests/test_rod3d_implicit.py) or `scheme` (an integrator class)."""
    dt = dt_fraction * step_limit(model, state[0]) if dt is None else dt
    opts = jr.RunOptions(**{"stop_when_stuck": False, **options})
    integrator = jr.ProjectedLeapfrog(dt, law) if scheme is None else scheme(dt, law)
    return jr.simulate(model, integrator, *state, t1, n_save=n_save, options=opts, throw=False)


def test_so3_roundtrip_and_finite_gradients_at_identity():
    phi = jnp.array([[0.3, -0.2, 0.5], [1e-7, 0.0, -2e-7], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(log_so3(exp_so3(phi)), phi, atol=1e-12)
    R = exp_so3(phi)
    np.testing.assert_allclose(jnp.einsum("iab,icb->iac", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-13)
    g = jax.jit(jax.grad(lambda p: jnp.sum(log_so3(exp_so3(p)) ** 2)))(phi)
    assert np.all(np.isfinite(g))
    np.testing.assert_allclose(g, 2 * phi, atol=1e-9)


def test_components_pack_along_the_last_axis_for_any_leading_shape():
    """`pack` puts three component arrays of any shape (…) on a last axis of 3 and `unpack`
    takes it apart again: per node, per lane and node (2 × 5), and a single vector."""
    from jaxrod.rod3d import components as c3

    for shape in [(5,), (2, 5), ()]:
        xyz = tuple(jnp.asarray(np.arange(np.prod(shape, dtype=int), dtype=float).reshape(shape) + 10.0 * k)
                    for k in range(3))
        v = c3.pack(xyz)
        assert v.shape == (*shape, 3)
        for k in range(3):
            np.testing.assert_array_equal(v[..., k], xyz[k])
            np.testing.assert_array_equal(c3.unpack(v)[k], xyz[k])


@pytest.mark.parametrize("theta", [0.0, 1e-9, 1e-4, 0.05, 0.7, 1.3, 2.2, 3.0])
def test_log_rotation_and_its_jacobian_against_the_library_arctangent(theta):
    """The step's logarithm (half-angle form, `components.log_rotation`) against `log_so3`
    (`jnp.arctan2`), and its couple J_l(ψ)⁻ᵀ m against reverse mode through `log_so3` of a
    left-perturbed rotation, at random axes and angles from the identity to 3 rad."""
    from jaxrod.rod3d import components as c3

    rng = np.random.default_rng(7)
    axis = rng.normal(size=(16, 3))
    R = exp_so3(jnp.asarray(theta * axis / np.linalg.norm(axis, axis=1, keepdims=True)))
    psi, c = c3.log_rotation(c3.unpack_matrix(R), with_jacobian=True)
    psi = c3.pack(psi)
    np.testing.assert_allclose(psi, log_so3(R), rtol=0, atol=5e-15 * max(theta, 1.0))
    m = jnp.asarray(rng.normal(size=(16, 3)))
    got = c3.pack(c3.left_jacobian_inv_t(c3.unpack(psi), c3.unpack(m), c))
    ref = jax.vmap(jax.grad(lambda d, Ri, mi: mi @ log_so3(exp_so3(d) @ Ri)))(jnp.zeros((16, 3)), R, m)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(m))))


def test_buckling_threshold_follows_the_control():
    """Dead load and displacement control: 0.5 rad, as the reduced models. Held ends after a
    pre-compression ΔF above F⁰: half the amplitude whose end shortening relieves ΔF, from
    the energy balance (2/(R ω₆)) √(ΔF/EA) written out here; 0.5 rad at or below F⁰."""
    rod = jr.RodChannel.reference(0.3)
    F0 = float(jr.theory.reference_load(rod))
    assert float(Rod3D(rod, 12, control="load", end_load=F0 + 5.0).buckle_threshold) == 0.5
    assert float(Rod3D(rod, 12, control="displacement", speed=1e-3).buckle_threshold) == 0.5
    assert float(Rod3D(rod, 12, control="force", preload=F0 - 1.0).buckle_threshold) == 0.5
    assert float(Rod3D(rod, 12, control="force", preload=F0).buckle_threshold) == 0.5  # at F⁰: A_held = 0
    for dF in (1.0, 5.0, 20.0):
        model = Rod3D(rod, 12, control="force", preload=F0 + dF)
        omega6 = 6 * np.pi / float(rod.L)
        held = 2.0 / (float(rod.R) * omega6) * np.sqrt(dF / float(rod.EA))
        assert float(model.buckle_threshold) == pytest.approx(min(0.5, 0.5 * held), rel=1e-12)
    model = Rod3D(rod, 12, control="force", preload=F0 + 5.0)
    assert float(model.buckle_threshold) < 0.2
    q, _ = model.initial_state()  # the model's own initial state is held at its preload
    np.testing.assert_allclose(model.axial_force(q.x, q.Q), F0 + 5.0, rtol=1e-9)


@pytest.mark.parametrize("control", ["load", "force", "displacement"])
def test_closed_form_forces_are_minus_the_energy_gradient(control):
    """The step's forces and torques (written out by hand) against reverse-mode AD of the
    potential, at a state with large rotations (0.3 rad per segment), wall contact, gravity,
    a body force and, under `control="load"`, the dead end load; under `"displacement"`, the
    far end's sliding load (`far_load`, on node 0)."""
    from jaxrod.rod3d.so3 import skew

    rod = jr.RodChannel.reference(0.3)
    ends = dict(far_load=3.0) if control == "displacement" else dict(end_load=3.0)
    model = Rod3D(rod, 20, control=control, body_force=(0.1, 0.2, -0.3), **ends)
    q, _ = model.initial_state(2.0, lateral_offset=1e-3 * jnp.sin(3 * jnp.pi * jnp.arange(21.0) / 20))
    rng = np.random.default_rng(1)
    x = q.x + 1e-4 * rng.normal(size=q.x.shape)
    Q = jnp.einsum("jab,jbc->jac", exp_so3(jnp.asarray(0.3 * rng.normal(size=(20, 3)))), q.Q)

    def U(x, dphi):
        return model.potential(x, Q - jnp.einsum("jab,jbc->jac", skew(dphi), Q))

    gx, gphi = jax.jit(jax.grad(U, argnums=(0, 1)))(x, jnp.zeros((20, 3)))
    f, tau = jax.jit(lambda x, Q: model.generalized_forces(x, Q))(x, Q)
    np.testing.assert_allclose(f, -gx, rtol=0, atol=1e-12 * np.max(np.abs(gx)))
    np.testing.assert_allclose(tau, -gphi, rtol=0, atol=1e-12 * np.max(np.abs(gphi)))


@pytest.mark.slow  # 17 s of 3D compilation; the static-friction 3D check stays in the default suite
def test_static_sag_of_a_simply_supported_rod_matches_beam_theory():
    """Midspan sag 5wL⁴/(384EI) (+ shear wL²/(8κGA)) of a pinned–roller rod under its weight,
    reached by damped dynamics."""
    rod = jr.RodChannel.reference(0.0, L=0.3)
    m = Rod3D(rod, 20, channel=False, control="load", damping=300.0)
    sol = simulate_rod3d(m, m.initial_state(), 0.12, 5, save_state=True)
    sag = -float(sol.q.x[-1, 10, 2])
    theory = 5 * float(rod.w) * 0.3**4 / (384 * float(rod.EI)) + float(rod.w) * 0.3**2 / (8 * float(m.shear_coefficient * rod.GA))
    assert abs(sag / theory - 1) < 0.01, (sag, theory)
    # settled: the last two saves (30 ms apart) agree to 1e-3 relative
    assert abs(float(sol.q.x[-2, 10, 2]) / float(sol.q.x[-1, 10, 2]) - 1) < 1e-3


@pytest.mark.slow
def test_planar_euler_load_from_the_frequency_drop():
    """ω₁² falls linearly with the compressive dead load and vanishes at the critical load:
    extrapolating from F = 0 and F = P_E/2 gives π²EI/L² within 1 % (no channel, no gravity)."""
    rod = jr.RodChannel.reference(0.0, L=0.3)
    PE = np.pi**2 * float(rod.EI) / 0.3**2
    s = np.linspace(0.0, 1.0, 17)
    om = []
    for F in (0.0, 0.5 * PE):
        m = Rod3D(rod, 16, channel=False, gravity=False, control="load", end_load=F)
        sol = simulate_rod3d(m, m.initial_state(F, lateral_velocity=1e-4 * np.sin(np.pi * s)), 0.05, 501, save_state=True)
        y, ts = np.asarray(sol.q.x[:, 8, 1]), np.asarray(sol.ts)
        i = np.where((y[1:-1] > 0) & (y[2:] <= 0))[0][0] + 1
        om.append(np.pi / (ts[i] + (ts[i + 1] - ts[i]) * y[i] / (y[i] - y[i + 1])))
    om1_theory = (np.pi / 0.3) ** 2 * np.sqrt(float(rod.EI) / float(rod.rho))
    assert abs(om[0] / om1_theory - 1) < 0.01
    Pcr = 0.5 * PE / (1 - om[1] ** 2 / om[0] ** 2)
    assert abs(Pcr / PE - 1) < 0.01, (Pcr, PE)


@pytest.mark.slow
def test_energy_is_conserved_without_friction_and_closes_with_it():
    """μ = 0, undamped contact: E(t) − E(0) stays within 2 % of the kinetic energy put in and
    falls at second order in dt (Verlet). With μ = 0.3 the balance E + dissipated closes as
    tightly while friction removes most of that kinetic energy."""
    s = np.linspace(0.0, 1.0, 31)
    for mu in (0.0, 0.3):
        rod = jr.RodChannel.reference(mu)
        m = Rod3D(rod, 30)
        s0 = m.initial_state(1.3081 + 5.0, lateral_velocity=0.035 * np.sin(6 * np.pi * s))
        errs = []
        for frac in (0.5, 0.25):
            sol = simulate_rod3d(m, s0, 0.03, 7, dt_fraction=frac)
            errs.append(np.max(np.abs(np.asarray(sol.energy_balance))))
            assert int(sol.result) == 0
        k0 = float(sol.energies["kinetic"][0])
        assert errs[0] < 2e-2 * k0
        assert errs[1] < errs[0] / 3.0, errs
        if mu > 0:
            assert float(sol.dissipated[-1]) > 0.1 * k0


def test_static_friction_holds_and_dynamic_friction_sets_the_deceleration():
    """A free rod on the bottom released from rest and pushed along its axis by a body force b,
    with the default options (the run stops when the rod is stuck): below μ_s·w it does not
    move (to elastic micro-motion, < 1e-9 m); above, it slides with (b/w − μ_d) g. (The stick
    stop once declared both stuck at step 0: the contacts start at rest, under μ_s.)"""
    rod = jr.RodChannel.reference(0.5).with_friction(0.5, 0.3)
    w = float(rod.w)
    for ratio in (0.4, 0.8):
        m = Rod3D(rod, 20, ends="free", body_force=(ratio * w, 0.0, 0.0))
        s0 = m.initial_state()
        sol = simulate_rod3d(m, s0, 0.02, 3, save_state=True, stop_when_stuck=True)
        dx = np.asarray(sol.q.x[-1, :, 0] - s0[0].x[:, 0])
        if ratio < 0.5:
            assert np.max(np.abs(dx)) < 1e-9
            assert bool(np.all(sol.v_final.stuck))
        else:
            expected = 0.5 * (ratio - 0.3) * 9.81 * 0.02**2
            np.testing.assert_allclose(dx, expected, rtol=1e-4)


@pytest.mark.slow  # 12 s of 3D compilation; the same check runs on the field model by default
def test_a_step_above_the_limit_is_refused():
    m = Rod3D(jr.RodChannel.reference(0.3), 10)
    s0 = m.initial_state(2.0)
    lim = step_limit(m, s0[0])
    # the limit is set by the axial wave: within 30 % of l̂/c
    c = np.sqrt(77e9 / 6450)
    assert 0.7 < lim / (0.3 / c) < 1.3
    # the same limit for the straight rod under its end load (what `simulate` checks)
    assert abs(step_limit(m) / lim - 1) < 0.05
    with pytest.raises(ValueError, match="dt"):
        simulate_rod3d(m, s0, 0.001, 3, dt=1.01 * step_limit(m))


def test_bad_arguments_name_the_argument():
    rod = jr.RodChannel.reference(0.3)
    with pytest.raises(ValueError, match="n_segments"):
        Rod3D(rod, 2)
    with pytest.raises(ValueError, match="control"):
        Rod3D(rod, 10, control="velocity")
    with pytest.raises(ValueError, match="rotary_scale"):
        Rod3D(rod, 10, rotary_scale=0.5)
    with pytest.raises(ValueError, match="friction_sweeps"):
        Rod3D(rod, 10, friction_sweeps=0)
    with pytest.raises(ValueError, match="friction_at"):
        Rod3D(rod, 10, friction_at="centre")
    with pytest.raises(ValueError, match="friction_precision"):
        Rod3D(rod, 10, friction_precision="float16")
    with pytest.raises(ValueError, match="speed"):
        Rod3D(rod, 10, control="displacement", speed=float("nan"))


@pytest.mark.slow  # 23-30 s of 3D compilation; the default suite keeps a quicker check
def _held_case(n, friction_at, **kw):
    """A rod pre-compressed to F⁰₆ + 20 N with a mode-12 offset whose net elastic + gravity
    force is 44 % of μN (the field model's stick condition, P1: it does not move)."""
    rod = jr.RodChannel.reference(0.3)
    F = float(jr.theory.frictionless_load(rod, 6)) + 20.0
    A, k = 1e-3, 12 * np.pi / float(rod.L)
    EI, w, R = float(rod.EI), float(rod.w), float(rod.R)
    margin = abs(EI * k**4 - F * k**2 + w / R) * A / (0.3 * w / R)
    assert 0.4 < margin < 0.5
    m = Rod3D(rod, n, control="load", end_load=F, friction_at=friction_at, **kw)
    s = jnp.linspace(0.0, 1.0, n + 1)
    return rod, m, margin, m.initial_state(F, lateral_offset=R * A * jnp.sin(12 * jnp.pi * s))


def _twist_figure(rod, margin, k=12 * np.pi / 3.0):
    """The largest |Δθ| [rad] of the roll that the holding friction sets up on a rod whose ends
    may spin: the friction at the contact point (radius r) holds a lateral force f(s) =
    f̂ sin(ks) (f̂ = margin·μw) with a couple r·f per length, which the twist carries to the
    torque-free ends, GJ φ' = r ∫₀ˢ f; the roll φ then has a ramp of amplitude r f̂ L/(2 GJ k)
    and the centre moves by r·φ along the wall, Δθ = r² f̂ L/(2 GJ k R)."""
    r = 0.5 * float(rod.d)
    f_hat = margin * float(rod.mu_s) * float(rod.w)
    return r**2 * f_hat * float(rod.L) / (2 * float(rod.GJ) * k * float(rod.R))


@pytest.mark.slow  # 12-17 s of 3D compilation per precision; the contact-point case below stays in the default suite
@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_a_compressed_rod_inside_the_friction_cone_holds_with_centre_line_friction(precision):
    """Friction at the centre line (sliding only): the held rod does not move. With the float64
    pass not at all (< 1e-12 rad; measured 6e-18). The float32 pass cancels each half step's
    trial velocity h·a to float32's rounding 2⁻²⁴, so a held node may drift by at most
    2⁻²⁴·t·h·max|a| along the wall, i.e. that over R in θ (3.7e-12 rad here; measured 1.0e-12)."""
    rod, m, _, s0 = _held_case(30, "axis", friction_precision=precision)
    t1, h = 0.02, 0.5 * float(step_limit(m, s0[0]))
    sol = simulate_rod3d(m, s0, t1, 3, stop_on_buckle=False)
    theta = np.asarray(sol.observables["theta"])
    a = np.abs(np.asarray(m.acceleration(s0[0]).f) / np.asarray(m.mass)[:, None])[1:-1].max()
    bound = 1e-12 if precision == "float64" else 2.0**-24 * t1 * h * a / float(rod.R)
    assert np.max(np.abs(theta[-1] - theta[0])) < bound
    assert bool(jnp.all(sol.v_final.stuck[1:-1]))


# 31 s of 3D compilation: slow. The default suite keeps quicker checks of a held rod: the free rod
# at 0.4 μ_s w stays within 1e-9 m (test_static_friction_holds_and_dynamic_friction_sets_the_deceleration)
# and the stick test at rest is sharp at μ_s (tests/test_rod3d_rest.py)
@pytest.mark.parametrize("n,t1", [pytest.param(30, 0.1, marks=pytest.mark.slow), pytest.param(60, 0.2, marks=pytest.mark.slow),
                                   pytest.param(240, 0.05, marks=pytest.mark.slow)])
def test_a_held_rod_stays_within_its_elastic_roll_with_contact_point_friction(n, t1):
    """Friction at the contact point: the held rod rolls by the elastic twist the holding
    friction sets up (at most 1.35e-5 rad, `_twist_figure`, reached when the end nodes slip;
    measured 1.2e-5 with 60 segments, 1.6e-6 with 30, whose longer end segments hold the end
    torque) and no further. Two defects made it creep and
    buckle (3.1 rad at 0.2 s with 60 segments): the held end nodes took no wall friction, so the
    interior could roll sideways as one body, only the end segments tilting (a mode the load
    destabilises once F > ~EI/l₀²); and each friction pass started cold, so a single
    Gauss–Seidel sweep left the coupled impulses unconverged every step (slip of ~3e-6 m/s)."""
    rod, m, margin, s0 = _held_case(n, "surface")
    sol = simulate_rod3d(m, s0, t1, 11, stop_on_buckle=False)
    d = np.abs(np.asarray(sol.observables["theta"]) - np.asarray(sol.observables["theta"])[0])[:, 1:-1].max(1)
    figure = _twist_figure(rod, margin)
    print(f"n = {n}: max|Δθ| over time {d.tolist()}; elastic roll {figure:.3e} rad")
    assert d.max() < 1.2 * figure
    # no drift: the second half of the run stays within the first half's range (the roll
    # oscillates about its equilibrium: nothing damps the rolling–torsion mode)
    assert d[6:].max() < 1.3 * d[1:6].max()
    assert float(np.max(np.asarray(sol.observables["friction_residual"]))) <= 1e-4
    # every pass converged before its cap (5-7 sweeps measured: the held rod's elastic roll
    # oscillates, so its impulses change from pass to pass)
    sweeps = np.asarray(sol.observables["friction_sweeps"])[1:]
    print(f"sweeps per pass at the saves: {sweeps.tolist()}")
    assert np.all(sweeps >= 1) and sweeps.max() < min(12, m.friction_sweeps)


@pytest.mark.slow  # 23 s per law; test_so3_roundtrip_and_finite_gradients_at_identity stays quick
@pytest.mark.parametrize("law", [jr.Coulomb(), jr.Tanh(1e-3)])
def test_gradients_are_finite_at_zero_slip(law):
    """d(final state)/d(perturbation amplitude) (forward mode) through a short run that starts at rest
    (zero slip everywhere) is finite for the sharp and the smooth law, and equals central
    differences away from zero slip."""
    rod = jr.RodChannel.reference(0.3)
    m = Rod3D(rod, 8)
    s = jnp.linspace(0.0, 1.0, 9)

    def f(a):
        s0 = m.initial_state(2.0, lateral_velocity=a * jnp.sin(2 * jnp.pi * s))
        sol = simulate_rod3d(m, s0, 4e-4, 3, dt=2e-5, law=law, stop_on_buckle=False)
        return sol.v_final.v[4, 1] + sol.dissipated[-1]

    g0 = jax.jvp(f, (0.0,), (1.0,))[1]
    g1 = jax.jvp(f, (0.01,), (1.0,))[1]
    assert np.isfinite(g0) and np.isfinite(g1)
    # and right: central differences of the same run (the sliding state at 0.01 m/s is smooth
    # in the amplitude; the float32 friction pass limits the differences' accuracy)
    h = 1e-4
    fd = (f(0.01 + h) - f(0.01 - h)) / (2 * h)
    print(f"{type(law).__name__}: jvp {float(g1):.6e}, central difference {float(fd):.6e}")
    np.testing.assert_allclose(g1, fd, rtol=1e-2)


_W = np.array([[2.0, 0.5], [0.5, 1.0]])  # the inverse mass of the impulse tests below


def _coulomb_impulse(u):
    """The vector Coulomb impulse for W = `_W`, stick bound 0.3, slip bound 0.2."""
    W = (jnp.array(_W[0, 0]), jnp.array(_W[0, 1]), jnp.array(_W[1, 1]))
    (p1, p2), _ = jr.Coulomb().impulse_2d((u[0], u[1]), W, jnp.array(0.3), jnp.array(0.2))
    return jnp.stack([p1, p2])


_impulse_jacobian_fwd = jax.jit(jax.jacfwd(_coulomb_impulse))
_impulse_jacobian_rev = jax.jit(jax.jacrev(_coulomb_impulse))


@pytest.mark.parametrize("u", [(0.0, 0.0), (0.1, -0.05), (2.0, 1.0)])
def test_the_vector_coulomb_impulse_has_its_derivative_in_both_modes_also_at_zero_slip(u):
    """dp/du of `Coulomb.impulse_2d`: −W⁻¹ while the contact sticks, at zero slip too (where the
    slip branch, not taken, divides by |u| = 0), in forward and in reverse mode; while it slips,
    central differences of the impulse."""
    p = _coulomb_impulse
    u = jnp.asarray(u)
    fwd, rev = np.asarray(_impulse_jacobian_fwd(u)), np.asarray(_impulse_jacobian_rev(u))
    np.testing.assert_allclose(rev, fwd, rtol=1e-12, atol=1e-15)
    if float(np.linalg.norm(np.linalg.solve(_W, u))) <= 0.3:  # |W⁻¹u| within the bound
        np.testing.assert_allclose(fwd, -np.linalg.inv(_W), rtol=1e-12)
    else:
        h = 1e-6
        fd = np.stack([(p(u + h * e) - p(u - h * e)) / (2 * h) for e in jnp.eye(2)], -1)
        np.testing.assert_allclose(fwd, fd, rtol=1e-6, atol=1e-9)


def test_vector_coulomb_impulse_minimises_the_kinetic_energy_over_the_disc():
    """`Coulomb.impulse_2d` against an independent reference: the impulse p that minimises the
    kinetic energy after it, ½(u + Wp)ᵀW⁻¹(u + Wp) = const + uᵀp + ½pᵀWp, over the disc
    |p| ≤ bound (maximal dissipation), found by a dense search over the circle |p| = bound
    refined by golden sections, for inverse masses up to 300× anisotropic at every orientation,
    slip velocities from 1e-3 to 1e3 times the bound's, and points that stick."""
    rng = np.random.default_rng(7)
    N = 400
    a, b, ang = 10 ** rng.uniform(-1, 1.5, N), 10 ** rng.uniform(-1, 1.5, N), rng.uniform(0, np.pi, N)
    W11 = a * np.cos(ang) ** 2 + b * np.sin(ang) ** 2
    W22 = a * np.sin(ang) ** 2 + b * np.cos(ang) ** 2
    W12 = (a - b) * np.cos(ang) * np.sin(ang)
    u = rng.normal(size=(2, N))
    Winv_u = np.linalg.solve(np.moveaxis(np.array([[W11, W12], [W12, W22]]), -1, 0), u.T[..., None])[..., 0]
    c = np.linalg.norm(Winv_u, axis=1) * 10 ** rng.uniform(-3, 0.3, N)  # ~10 % of the points stick
    (p1, p2), sticks = jr.Coulomb().impulse_2d(tuple(map(jnp.asarray, u)), tuple(map(jnp.asarray, (W11, W12, W22))),
                                               jnp.asarray(c), jnp.asarray(c))
    p = np.stack([p1, p2], 1)

    def energy(q, k=slice(None)):  # uᵀq + ½qᵀWq for q of shape (N, K, 2) (the points k)
        w11, w12, w22 = (x[k, None] for x in (W11, W12, W22))
        return (u.T[k, None] * q).sum(-1) + 0.5 * (w11 * q[..., 0] ** 2 + 2 * w12 * q[..., 0] * q[..., 1]
                                                   + w22 * q[..., 1] ** 2)

    def on(f):  # points of the circle |p| = c at the angles f (N, K)
        return c[:, None, None] * np.stack([np.cos(f), np.sin(f)], -1)

    inside = np.linalg.norm(Winv_u, axis=1) <= c
    np.testing.assert_array_equal(np.asarray(sticks), inside)
    np.testing.assert_allclose(p[inside], -Winv_u[inside], rtol=1e-12, atol=0)
    # on the circle: the best of 4096 angles, then golden sections in the bracket around it
    phi = np.broadcast_to(np.linspace(0, 2 * np.pi, 4097)[:-1], (N, 4096))
    best = phi[0, np.argmin(energy(on(phi)), axis=1)]
    lo, hi = best - 2 * np.pi / 4096, best + 2 * np.pi / 4096
    g = (np.sqrt(5) - 1) / 2
    for _ in range(80):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        left = energy(on(m1[:, None]))[:, 0] < energy(on(m2[:, None]))[:, 0]
        lo, hi = np.where(left, lo, m1), np.where(left, m2, hi)
    ref = on(0.5 * (lo + hi)[:, None])[:, 0]
    slip = ~inside
    np.testing.assert_allclose(np.linalg.norm(p[slip], axis=1), c[slip], rtol=1e-10)
    err = np.linalg.norm(p[slip] - ref[slip], axis=1) / c[slip]
    assert err.max() < 1e-7, err.max()
    e_p, e_ref = energy(p[slip][:, None], slip)[:, 0], energy(ref[slip][:, None], slip)[:, 0]
    assert np.all(e_p <= e_ref + 1e-12 * np.abs(e_ref))
    # started from a nearby impulse (the last sweep's: here the answer turned by 0.05 rad and 3 %
    # longer), three Newton iterations reach the same impulse; from any guess it is on the bound
    rot = np.array([[np.cos(0.05), -np.sin(0.05)], [np.sin(0.05), np.cos(0.05)]])
    near = 1.03 * p @ rot.T
    for guess, tol in ((near, 1e-9), (rng.normal(size=(N, 2)) * c[:, None], None)):
        (g1, g2), sticks_g = jr.Coulomb().impulse_2d(tuple(map(jnp.asarray, u)), tuple(map(jnp.asarray, (W11, W12, W22))),
                                                     jnp.asarray(c), jnp.asarray(c), tuple(map(jnp.asarray, guess.T)))
        pg = np.stack([g1, g2], 1)
        np.testing.assert_array_equal(np.asarray(sticks_g), inside)
        np.testing.assert_allclose(np.linalg.norm(pg[slip], axis=1), c[slip], rtol=1e-12)
        if tol is not None:
            assert (np.linalg.norm(pg[slip] - p[slip], axis=1) / c[slip]).max() < tol


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_amplitude_is_the_largest_wall_angle(seed):
    """`amplitude` (one arctangent of the largest half-angle tangent) against max|θ| of every
    interior node by `wall_angle` (an arctangent each): nodes anywhere in the clearance circle,
    on its wall, near the top (θ → ±π) and exactly on the ray above the axis (θ = π)."""
    rng = np.random.default_rng(seed)
    rod = jr.RodChannel.reference(0.3)
    m = Rod3D(rod, 12)
    q, _ = m.initial_state()
    R = float(rod.R)
    angle = rng.uniform(-np.pi, np.pi, m.n + 1)
    radius = R * rng.uniform(0.2, 1.1, m.n + 1)
    yz = np.stack([radius * np.sin(angle), -radius * np.cos(angle)], 1)
    cases = [yz, yz * np.array([1e-3, 1.0])]  # all near the bottom: small θ, full relative precision
    top = yz.copy()
    top[5] = (1e-12, R)  # next to the top, |θ| just below π
    cases.append(top)
    over = yz.copy()
    over[3] = (0.0, 0.7 * R)  # on the ray above the axis: θ = π
    cases.append(over)
    for c in cases:
        x = q.x.at[:, 1:].set(jnp.asarray(c))
        qc = type(q)(x, q.Q)
        expected = float(jnp.max(jnp.abs(m.theta(x)[1:-1])))
        assert float(m.amplitude(qc)) == pytest.approx(expected, rel=1e-15, abs=0)


def test_a_rod_counts_as_stuck_only_when_its_nodes_and_spins_are_at_rest_and_held():
    """`stop_measures`' second value: a straight rod at rest with every contact held by static
    friction is stuck; one free segment spinning (node velocities all zero), or one contact not
    held, is not."""
    from jaxrod.rod3d.measures import stop_measures

    model = Rod3D(jr.RodChannel.reference(0.3), 6)
    q, v = model.initial_state()
    v = eqx.tree_at(lambda s: s.stuck, v, jnp.ones_like(v.stuck))
    a = jnp.zeros_like(v.v)
    assert bool(stop_measures(model, q, v, a)[1])
    spinning = eqx.tree_at(lambda s: s.w, v, v.w.at[2, 0].set(0.1))
    assert not bool(stop_measures(model, q, spinning, a)[1])
    sliding = eqx.tree_at(lambda s: s.stuck, v, v.stuck.at[3].set(False))
    assert not bool(stop_measures(model, q, sliding, a)[1])


def test_the_initial_lateral_velocity_is_along_the_wall_in_a_channel_and_along_y_without_one():
    """`initial_state(lateral_velocity=u)`: each interior node moves at u along the wall's tangent,
    perpendicular to the rod and to the wall's normal (on a rod offset along the wall, not only
    along y); without a channel, along y. The held ends do not move."""
    rod = jr.RodChannel.reference(0.3)
    s = np.arange(13) / 12
    u = 0.02 * np.sin(np.pi * s)
    m = Rod3D(rod, 12)
    q, v = m.initial_state(1.0, lateral_velocity=u, lateral_offset=0.3 * float(rod.R) * np.sin(np.pi * s))
    x, vv = np.asarray(q.x), np.asarray(v.v)
    e_r = x[:, 1:] / np.linalg.norm(x[:, 1:], axis=-1, keepdims=True)
    np.testing.assert_allclose(vv[1:-1, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(np.sum(vv[1:-1, 1:] * e_r[1:-1], -1), 0.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(vv[1:-1], axis=-1), np.abs(u[1:-1]), rtol=1e-12)
    assert np.ptp(e_r[1:-1, 0]) > 0.1  # the wall's normal turns along the rod
    assert not vv[[0, -1]].any()
    free = Rod3D(rod, 12, channel=False, gravity=False)
    _, vf = free.initial_state(1.0, lateral_velocity=u)
    vf = np.asarray(vf.v)
    np.testing.assert_allclose(vf[1:-1, 1], u[1:-1], rtol=1e-12)
    np.testing.assert_array_equal(vf[1:-1][:, [0, 2]], 0.0)


def test_the_3d_sine_perturbation_is_the_scenes_sine_mode_unless_given():
    """`sine_velocity(model, v₀)`: v₀ sin(mπs/L) at the n + 1 nodes, m the mode of a scene's
    default sine perturbation (6) unless given."""
    from jaxrod.rod3d import sine_velocity

    m = Rod3D(jr.RodChannel.reference(0.3), 12)
    s = np.arange(13) / 12
    mode = int(jr.Scene(jr.RodChannel.reference(0.3), 5.0).perturbation.mode)
    assert mode == 6
    np.testing.assert_allclose(np.asarray(sine_velocity(m, 0.02)), 0.02 * np.sin(mode * np.pi * s), atol=1e-15)
    np.testing.assert_allclose(np.asarray(sine_velocity(m, 0.02, 3)), 0.02 * np.sin(3 * np.pi * s), atol=1e-15)


def _spinning_free_rod():
    """A free 4-segment rod in space (no channel, no gravity, free ends), its nodes moving and its
    segments spinning about axes off their principal ones (the gyroscopic couple ω × Jω ≠ 0)."""
    rod = jr.RodChannel.reference(0.3, L=0.2)
    model = Rod3D(rod, 4, channel=False, gravity=False, ends="free", control="force", preload=0.0)
    q0, v0 = model.initial_state(0.0)
    rng = np.random.default_rng(0)
    w0 = jnp.asarray(rng.normal(size=(4, 3)) * np.array([5.0, 5.0, 40.0]))
    v0 = eqx.tree_at(lambda v: (v.v, v.w), v0, (jnp.asarray(rng.normal(size=(5, 3)) * 0.01), w0))
    return model, q0, v0


def _momenta(model, q, v):
    """Linear momentum Σ mᵢvᵢ and angular momentum about the origin Σ xᵢ × mᵢvᵢ + Σ Qₖᵀ J wₖ
    (w in the material frame, Q lab → material), at every save."""
    mv = model.mass[None, :, None] * v.v
    spin = jnp.einsum("tkji,tkj->tki", q.Q, model.inertia[None, None] * v.w)
    return jnp.sum(mv, 1), jnp.sum(jnp.cross(q.x, mv), 1) + jnp.sum(spin, 1)


def test_a_free_spinning_rod_keeps_its_momenta_and_the_angular_one_converges_with_the_step():
    """No external force or couple: linear momentum is kept to rounding, angular momentum to a
    drift that halves with the step (first order: 2.1e-4 of |L| at half the explicit limit over
    0.0125 s, 1.2e-4 at a quarter). Without the gyroscopic couple ω × Jω in the kick the drift is
    about six times larger and does not shrink with the step (a model error, not a step error)."""
    model, q0, v0 = _spinning_free_rod()
    lim = float(step_limit(model))
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)

    def drifts(frac):
        sol = jr.simulate(model, jr.ProjectedLeapfrog(frac * lim), q0, v0, 1000 * lim, n_save=11, options=opts)
        assert int(sol.result) == 0
        lin, ang = (np.asarray(a) for a in _momenta(model, sol.q, sol.v))
        return (np.abs(lin - lin[0]).max() / np.abs(lin[0]).max(),
                np.abs(ang - ang[0]).max() / np.linalg.norm(ang[0]))

    (lin_h, ang_h), (lin_q, ang_q) = drifts(0.5), drifts(0.25)
    assert lin_h < 1e-12 and lin_q < 1e-12
    assert ang_h < 3e-4 and 0.4 < ang_q / ang_h < 0.65, (ang_h, ang_q)
