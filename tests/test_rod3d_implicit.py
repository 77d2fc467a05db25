"""The 3D rod's implicit leapfrog (`jaxrod.ImplicitLeapfrog`, `jaxrod.rod3d.hessian`) against
independent references: the dense solve for the block-tridiagonal one, AD of the potential for
the closed-form stiffness, the explicit leapfrog for the scheme (β = γ = 0 is that scheme), the
trapezoidal rule's energy conservation, exact stick, and the explicit scheme's committed v₀*
(docs/rod3d.md) for the answers."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import theory
from jaxrod._banded import block_tridiagonal_matvec, block_tridiagonal_solve
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit
from jaxrod.rod3d.hessian import _turned, hessian_blocks, hessian_blocks_ad
from jaxrod.rod3d.so3 import skew

from test_rod3d_stiffness import _dense  # the dense matrix of blocks




def test_block_tridiagonal_solve_matches_a_dense_solve_and_flags_an_indefinite_matrix():
    rng = np.random.default_rng(0)
    nb, m = 9, 6
    U = rng.normal(size=(nb - 1, m, m))
    G = rng.normal(size=(nb, m, m))
    D = 12.0 * np.eye(m) + np.einsum("kij,klj->kil", G, G)
    b = rng.normal(size=(nb, m))
    A = _dense(D, U)
    assert np.linalg.eigvalsh(A).min() > 0
    x = block_tridiagonal_solve(jnp.asarray(D), jnp.asarray(U), jnp.asarray(b))
    np.testing.assert_allclose(np.asarray(x).ravel(), np.linalg.solve(A, b.ravel()), rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(block_tridiagonal_matvec(jnp.asarray(D), jnp.asarray(U), x), b, rtol=1e-10, atol=1e-11)
    bad = D.copy()
    bad[4] = -bad[4]  # not positive definite: NaN, never a silent answer
    assert not np.isfinite(np.asarray(block_tridiagonal_solve(jnp.asarray(bad), jnp.asarray(U), jnp.asarray(b)))).all()


def _bent_state(n=6, turn=0.05, seed=1):
    model = Rod3D(jr.RodChannel.reference(mu=0.3), n, control="force", preload=3.0)
    q, _ = model.initial_state(3.0, lateral_offset=2e-3 * jnp.sin(jnp.linspace(0, 3, n + 1)))
    rng = np.random.default_rng(seed)
    x = q.x + 1e-4 * rng.normal(size=q.x.shape)  # some nodes in the wall, some off it
    phi = jnp.asarray(turn * rng.normal(size=(n, 3)))
    Q = jax.vmap(lambda p, Q: jax.scipy.linalg.expm(-skew(p)) @ Q)(phi, q.Q)
    return model, x, Q


def _ad_dense(model, x, Q):
    """The Hessian of `model.potential` in (x, φ) by AD of the whole potential, in block order."""
    n = model.n

    def U(z):
        xx = z[:3 * (n + 1)].reshape(n + 1, 3)
        p = z[3 * (n + 1):].reshape(n, 3)
        return model.potential(xx, jax.vmap(_turned)(p, Q))

    H = np.asarray(jax.jit(jax.hessian(U))(jnp.concatenate([x.ravel(), jnp.zeros(3 * n)])))  # one program
    perm = []
    for k in range(n + 1):
        perm += [3 * k, 3 * k + 1, 3 * k + 2] + ([3 * (n + 1) + 3 * k + i for i in range(3)] if k < n else [-1] * 3)
    out = np.zeros((6 * (n + 1),) * 2)
    for i, pi in enumerate(perm):
        for j, pj in enumerate(perm):
            if pi >= 0 and pj >= 0:
                out[i, j] = H[pi, pj]
    return out


@pytest.mark.slow  # AD of the whole potential, dense (~25 s cold); the closed form against the AD blocks runs by default
def test_the_element_hessians_are_the_potentials():
    """The per-element AD blocks assembled are the Hessian of the whole potential (stretch, shear,
    bend, twist, the Hertz wall with nodes in and out of it), to rounding."""
    model, x, Q = _bent_state()
    ref = _ad_dense(model, x, Q)
    got = _dense(*eqx.filter_jit(hessian_blocks_ad)(model, x, Q))  # compiled as one program: seconds, not tens
    assert np.abs(got - ref).max() < 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("damped", [False, True])
@pytest.mark.parametrize("turn", [0.0, 0.05])
def test_the_closed_form_stiffness_against_ad(turn, damped):
    """Stretch, shear and the wall exact; bend and twist Gauss–Newton: their blocks differ from
    the exact ones by about |ψ| (the turn of a joint) relative to the bending stiffness EI/l̂.
    `damped`: the damping's matrix, shear, bend and twist (no stretch or wall in it)."""
    model, x, Q = _bent_state(turn=turn)
    D, U = hessian_blocks(model, x, Q, damped=damped)
    Da, Ua = eqx.filter_jit(hessian_blocks_ad)(model, x, Q, damped=damped)
    if damped:  # it leaves out what the full one has: stretch (and the wall, if touching)
        Df, _ = hessian_blocks(model, x, Q)
        assert float(jnp.abs(Df[:, 0, 0] - D[:, 0, 0]).min()) > 0.5 * float(model.rod.EA / model.l0)
    scale = float(jnp.abs(Da).max())
    np.testing.assert_allclose(D[:, :3, :], Da[:, :3, :], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(U[:, :, :3], Ua[:, :, :3], rtol=0, atol=1e-12 * scale)
    bend = float(model.rod.EI / model.l0)
    tol = 4 * float(jnp.abs(model.strains(x, Q)[1]).max() * model.l0)  # 4 |ψ|: the largest turn of a joint
    assert float(jnp.abs(U[:, 3:, 3:] - Ua[:, 3:, 3:]).max()) < tol * bend
    assert float(jnp.abs(D[:, 3:, 3:] - Da[:, 3:, 3:]).max()) < tol * bend + 1e-12 * scale


def test_the_damping_impulse_is_gamma_h_times_the_damped_stiffness_on_every_free_unknown():
    """`implicit_kick(..., with_impulse=True)`: P = −γ h H_d (hk v + h Δv) on the free degrees of
    freedom, zero on the held ones, against the stacked damped Hessian and the block product of
    the tests' reference; on a rod of heavy nodes (4.3–8.5 kg each, a steel pipe's segments:
    the kick scales by M^{−½} < 1 there), resting on the wall under its weight: the wall's
    stiffness is in the kick's matrix but is not damped."""
    from jaxrod.rod3d.hessian import _blocks_of, _free, _wall_components, implicit_kick

    model = Rod3D(jr.RodChannel.reference(0.3, rho_v=6.45e6), 4, control="force")
    assert float(model.mass.min()) > 4.0
    q, v = model.initial_state(0.0, lateral_velocity=sine_velocity(model, 1e-3))
    assert float(jnp.min(_wall_components(model, q.x)[2])) > 1e6  # every node pressed on the wall [N/m]
    a = model.accelerations(q, v, 0.0)
    h, gamma = 1e-3, 0.1
    out, P = implicit_kick(model, q, v, a, h, h, 0.25, gamma, with_impulse=True)
    free = np.asarray(_free(model, jnp.float64)) > 0
    vel = np.where(free, np.asarray(_blocks_of(v)), 0.0)
    dv = np.where(free, np.asarray(_blocks_of(out)) - np.asarray(_blocks_of(v)), 0.0)
    D, U = hessian_blocks(model, q.x, q.Q, damped=True)
    ref = np.where(free, -gamma * h * np.asarray(block_tridiagonal_matvec(D, U, jnp.asarray(h * vel + h * dv))), 0.0)
    assert np.abs(ref[:, :3]).max() > 0.1 * np.abs(ref).max()  # the nodes take part
    np.testing.assert_allclose(np.asarray(P), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_the_damping_loss_is_the_kinetic_energy_the_damped_kick_takes_out():
    """A free straight rod in space (no wall, gravity, load: no force), its nodes moving at random
    and its segments not turning (strain rates in shear and bending), one kick with β = 0: then
    M Δv = P, the damping's impulse, exactly, so the kinetic energy the kick takes out is P·½(v + v′),
    which `damping_loss` must give, summing to K(v) − K(v′) > 0 to rounding (`dissipated` counts that
    sum). (The 3D rod's energy balance with the damping closes at second order: the slow test
    below.)"""
    from jaxrod.rod3d.hessian import damping_loss, implicit_kick

    rod = jr.RodChannel.reference(0.0)
    model = Rod3D(rod, 6, channel=False, gravity=False, ends="free", control="force")
    q, v = model.initial_state(0.0)
    rng = np.random.default_rng(3)
    v = type(v)(jnp.asarray(rng.normal(size=v.v.shape)) * 1e-3, v.w, v.stuck, v.force, v.residual, v.sweeps)
    a = model.accelerations(q, v, 0.0)
    assert float(jnp.abs(a.f).max()) < 1e-12 and float(jnp.abs(a.tau).max()) < 1e-12
    h = float(20 * step_limit(model))
    out, P = implicit_kick(model, q, v, a, h, h, 0.0, 0.5, with_impulse=True)
    K = lambda u: float(sum(model.kinetic_terms(u.v, u.w).values()))  # noqa: E731
    lost_n, lost_s = damping_loss(model, v, out, P)
    lost = float(jnp.sum(lost_n) + jnp.sum(lost_s))
    assert K(v) - K(out) > 0.01 * K(v)  # the damping takes out a measurable part (2.6 %) at this step
    assert lost == pytest.approx(K(v) - K(out), rel=1e-9)


def _loaded(n=12, mu=0.3, dF=5.0, v0=0.02):
    rod = jr.RodChannel.reference(mu) if mu > 0 else jr.RodChannel.reference(0.3).with_friction(0.0, 0.0)
    model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + dF)
    q0, v0 = model.initial_state(None, lateral_velocity=sine_velocity(model, v0))
    return model, q0, v0


def _run(model, integrator, q0, v0, t1, n_save=5, **opts):
    opts = jr.RunOptions(**{"stop_on_buckle": False, "stop_when_stuck": False, **opts})
    return jax.jit(lambda q, v: jr.simulate(model, integrator, q, v, t1, n_save=n_save, options=opts, throw=False))(q0, v0)


@pytest.mark.slow  # two 3D compilations (~20 s cold)
def test_with_beta_and_gamma_zero_it_is_the_explicit_leapfrog():
    model, q0, v0 = _loaded()
    dt = 0.5 * step_limit(model)
    a = _run(model, jr.ProjectedLeapfrog(dt), q0, v0, 200 * dt)
    b = _run(model, jr.ImplicitLeapfrog(dt, beta=0.0, gamma=0.0), q0, v0, 200 * dt)
    np.testing.assert_allclose(b.q.x, a.q.x, rtol=0, atol=1e-13)
    np.testing.assert_allclose(b.v.v, a.v.v, rtol=0, atol=1e-10)


def test_a_free_rod_stays_bounded_far_past_the_explicit_limit_and_gamma_damps_it():
    """A free rod in space (no wall, gravity or friction) in the linear regime (lateral velocity
    1 µm/s): at 30× the explicit limit the trapezoidal rule (γ = 0) stays bounded — the largest
    node speed of the last quarter of the run no larger than of the first, where the explicit
    leapfrog blows up at 1.05× — and the default γ = 0.1 lowers it. (Its energy at the saved
    positions is not a conserved quantity at such a step: the nodes drift h·v before the shear
    springs turn the segments, so the aliased shear mode holds a multiple of the kinetic energy
    put in, growing with the step; docs/rod3d.md.)"""
    rod = jr.RodChannel.reference(0.3).with_friction(0.0, 0.0)
    model = Rod3D(rod, 12, channel=False, control="force", gravity=False)
    q0, v0 = model.initial_state(0.0, lateral_velocity=sine_velocity(model, 1e-6))
    h = 30 * step_limit(model)
    speeds = {}
    for gamma in (0.0, 0.1):
        sol = _run(model, jr.ImplicitLeapfrog(h, gamma=gamma), q0, v0, 400 * h, n_save=41)
        assert int(sol.result) == 0
        speed = jnp.max(jnp.abs(sol.v.v), axis=(1, 2))
        speeds[gamma] = float(jnp.max(speed[30:]))
        assert speeds[gamma] <= 1.0 * float(jnp.max(speed[:10]))
        # nothing but γ takes energy out of this rod: its work is what `dissipated` counts
        assert (float(sol.dissipated[-1]) > 0.0) == (gamma > 0.0)
    assert speeds[0.1] < speeds[0.0]


@pytest.mark.parametrize("n, steps", [pytest.param(24, 500, marks=pytest.mark.slow), (8, 200)])
def test_a_held_rod_does_not_creep_at_a_large_step(n, steps):
    """A compressed rod resting on the bottom with μ = 0.3, pushed along its axis by 0.4 μ w per
    length (inside the friction cone): at 20× the explicit limit it does not slide, to 1e-9 m (exact
    stick of the implicit step's friction pass; a rod pushed outside the cone slides: with the
    explicit scheme in `tests/test_rod3d.py`, with this one in the slow steady slide of
    `tests/test_lockup_push.py`). The default suite runs 8 segments (one 3D compilation, ~15 s
    cold), the slow one 24."""
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, n, control="force", preload=2.0, friction_at="axis",
                  body_force=(0.4 * 0.3 * float(rod.w), 0.0, 0.0))
    q0, v0 = model.initial_state(2.0)
    h = 20 * step_limit(model)
    sol = _run(model, jr.ImplicitLeapfrog(h), q0, v0, steps * h)
    assert int(sol.result) == 0
    assert float(jnp.max(jnp.abs(sol.q.x[-1, :, 0] - q0.x[:, 0]))) < 1e-9


@pytest.mark.slow  # a 3D compilation and two runs (~15 s cold)
def test_the_critical_velocity_at_60_segments_matches_the_explicit_scheme():
    """E3's run (dead load F⁰₆ + 5 N, μ = 0.3, sine mode 6, 0.4 s) at the implicit scheme's default
    step (`jaxrod.rod3d.IMPLICIT_DT`, 8× the explicit step here): stable 1 % below the explicit
    scheme's v₀* (26.19 mm/s, bracket 26.13–26.26, results/paper/e3/rod3d_boundary_n60_leapfrog.csv),
    buckled 1 % above."""
    from jaxrod.experiments.e3.rod3d import label_3d
    from jaxrod.rod3d import IMPLICIT_DT

    label = label_3d(jr.RodChannel.reference(0.3), 60, IMPLICIT_DT, 0.4, scheme="implicit")
    assert float(label(5.0, 0.99 * 26.19e-3)) == 0.0
    assert float(label(5.0, 1.01 * 26.19e-3)) == 1.0


@pytest.mark.slow
@pytest.mark.parametrize("dF, v_star", [(5.0, 27.13e-3), (20.0, 8.23e-3)])
def test_the_critical_velocity_at_500_segments_matches_the_explicit_scheme(dF, v_star):
    """The [implicit3d] gate at the paper's 500 segments: within 1 % of the explicit scheme's v₀*
    (27.13 and 8.23 mm/s at ΔF = 5 and 20 N, results/paper/e3/rod3d_boundary_n500.csv)."""
    from jaxrod.experiments.e3.rod3d import label_3d
    from jaxrod.rod3d import IMPLICIT_DT

    label = label_3d(jr.RodChannel.reference(0.3), 500, IMPLICIT_DT, 0.4, scheme="implicit")
    assert float(label(dF, 0.99 * v_star)) == 0.0
    assert float(label(dF, 1.01 * v_star)) == 1.0


@pytest.mark.slow  # two E1 batches at 60 segments (~40 s)
def test_e1_critical_force_matches_the_explicit_scheme():
    """E1's critical force (60 segments, μ = 0.3, pushed at 1 mm/s, sine amplitudes 5, 15,
    30 mm/s) with the implicit scheme at its default step within 1 % of the explicit leapfrog's
    at half its limit, run side by side (measured +0.05 to +0.18 %,
    benchmarks/results/rod3d_implicit_gates.csv)."""
    from jaxrod.experiments.rod3d import e1_curves

    v0s = (5e-3, 15e-3, 30e-3)
    explicit = np.asarray(e1_curves(0.3, v0s, dt_fraction=0.5, scheme="leapfrog")["critical_force"])
    implicit = np.asarray(e1_curves(0.3, v0s)["critical_force"])
    np.testing.assert_allclose(implicit, explicit, rtol=0.01)


@pytest.mark.slow  # 7 s of a slow push at 60 segments (~30 s)
def test_the_frictionless_rod_goes_over_the_top_where_the_explicit_scheme_says():
    """The post-buckling experiment's frictionless rod (60 segments, 1 mm/s, damping 50/s) goes
    over the top of the channel at an end load within 1 % of the explicit scheme's 2.02–2.04 N
    (docs/paper.md; measured 2.038–2.054 N at 5e-5 s)."""
    from jaxrod.experiments.helix import helix_measures, load_path

    rod = jr.RodChannel.reference(0.0)
    p = load_path(rod, 60, [(1e-3, 7.0)], sps=20, progress=False)
    over = np.flatnonzero(helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])["over_top"])
    assert over.size
    i = int(over[0])
    onset = 0.5 * (p["reaction"][i - 1] + p["reaction"][i])
    assert abs(onset / 2.03 - 1) < 0.01, onset


@pytest.mark.slow  # four runs at 30 segments, two steps each (~40 s)
def test_the_energy_balance_counts_the_damping_and_closes_at_second_order():
    """E3's start at 30 segments (sine velocity on the nodes, segments not turning), μ = 0 and 0.3,
    γ's work counted in `dissipated` (`ImplicitLeapfrog.kick_loss`). The balance E + D − E(0) jumps
    in the first save interval — the start puts energy into the shear mode, which the trapezoidal
    rule aliases and γ then removes (measured 9.5 % then 2.4 % of the kinetic energy put in at
    5e-5 and 2.5e-5 s: second order) — and then holds: without friction γ goes on removing energy
    from the bending motion (D grows by 10 % of the kinetic energy put in at 5e-5 s) while the
    balance moves by under a tenth of that."""
    for mu in (0.0, 0.3):
        rod = jr.RodChannel.reference(mu)
        model = Rod3D(rod, 30, control="load", end_load=theory.reference_load(rod) + 5.0)
        errs = []
        for h in (5e-5, 2.5e-5):
            scheme = jr.ImplicitLeapfrog(h)
            q0, v0 = jr.SineVelocity(0.035, 6.0).initial_state(model, scheme)
            sol = _run(model, scheme, q0, v0, 0.03, n_save=7)
            assert int(sol.result) == 0
            k0 = float(sol.energies["kinetic"][0])
            balance, dissipated = np.asarray(sol.energy_balance) / k0, np.asarray(sol.dissipated) / k0
            errs.append(np.max(np.abs(balance)))
            if mu == 0.0:
                assert dissipated[1] > 0.01  # γ's loss is counted
                later = dissipated[-1] - dissipated[1]
                assert later > 0.02 and np.max(np.abs(balance[1:] - balance[1])) < 0.1 * later
        assert errs[1] < errs[0] / 3.0, errs
        assert errs[1] < 0.04, errs


def test_the_bend_and_twist_blocks_are_the_gauss_newton_hessian_of_each_joint():
    """K, RᵀKR and −RᵀK of joint k are JᵀBJ/l̂, J the Jacobian of its curvature
    ψ = log(Qₖ₊₁Qₖᵀ) in (φₖ, φₖ₊₁) by forward AD and B = diag(EI, EI, GJ): exact, at joints turned
    by up to about half a radian (where the Gauss–Newton blocks differ from the full Hessian by far
    more than rounding, so that comparison cannot see an error of this size)."""
    from jaxrod.rod3d import components as c3
    from jaxrod.rod3d.hessian import element_blocks

    model, x, Q = _bent_state(turn=0.3, seed=4)
    rod, l0 = model.rod, float(model.l0)
    B = jnp.diag(jnp.array([rod.EI, rod.EI, rod.GJ]))

    def psi(z, Qa, Qb):
        return jnp.stack(c3.log_rotation(c3.unpack_matrix(_turned(z[3:6], Qb) @ _turned(z[0:3], Qa).T)))

    J = jax.vmap(jax.jacfwd(psi), in_axes=(None, 0, 0))(jnp.zeros(6), Q[:-1], Q[1:])  # (n − 1, 3, 6)
    GN = jnp.einsum("kia,ij,kjb->kab", J, B, J) / l0
    _, _, _, RKR, K, KR = (np.stack([np.stack(row, -1) for row in piece], -2)
                           for piece in element_blocks(model, x, Q, weights=(0.0, 0.0, 1.0, 1.0)))
    scale = float(jnp.abs(GN).max())
    assert float(jnp.abs(J[:, :, :3] + J[:, :, 3:]).max()) > 0.1  # the joints are turned: R is far from I
    np.testing.assert_allclose(RKR, GN[:, :3, :3], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(K, GN[:, 3:, 3:], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(-np.swapaxes(KR, -1, -2), GN[:, :3, 3:], rtol=0, atol=1e-12 * scale)
