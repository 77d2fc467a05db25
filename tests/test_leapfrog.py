"""Projected leapfrog (one friction pass per step, the 3D rod's default) against projected
Verlet (two): the same positions without friction, the same first step with it, and the same
limit as the step shrinks. Runs of the field model (24 nodes), where both are cheap; the 3D rod
runs its own tests (tests/test_rod3d.py) with its default, the leapfrog."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.scene import Scene


def _run(scheme, mu, dt, t1, n_save, amplitude=20e-3, dF=5.0):
    rod = jr.RodChannel.reference(mu) if mu > 0 else jr.RodChannel.reference(0.3).with_friction(0.0, 0.0)
    scene = Scene(rod, dF, jr.SineVelocity(amplitude, 6.0), "field", n=24)
    q0, v0 = scene.initial_state()
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=True)
    return jax.jit(lambda q, v: jr.simulate(scene.model(), scheme(dt), q, v, t1, n_save=n_save, options=opts,
                                            throw=False))(q0, v0)


def _dt():
    return Scene(jr.RodChannel.reference(0.3), 5.0, kind="field", n=24).step()


def test_without_friction_the_leapfrog_takes_verlets_positions_and_velocities():
    dt = _dt()
    # below the frictionless load (ΔF < 0) the rod oscillates about the straight state
    a, b = (_run(s, 0.0, dt, 400 * dt, 9, dF=-1.0) for s in (jr.ProjectedVerlet, jr.ProjectedLeapfrog))
    scale = float(jnp.max(jnp.abs(a.q)))
    np.testing.assert_allclose(b.q, a.q, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(b.v, a.v, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(a.v))))
    np.testing.assert_allclose(b.energy_balance, a.energy_balance, rtol=0, atol=1e-12 * float(a.energies["kinetic"][0]))


def test_with_friction_the_first_step_is_verlets():
    """From (q₀, v₀) the leapfrog's first kick and pass are half a step: one step of each scheme
    gives the same position, and the velocity the leapfrog records there (a half kick and pass
    from its half-step velocity) is Verlet's. Its second step merges Verlet's two passes at q₁."""
    dt = _dt()
    one = [_run(s, 0.3, dt, dt, 2) for s in (jr.ProjectedVerlet, jr.ProjectedLeapfrog)]
    np.testing.assert_allclose(one[1].q, one[0].q, rtol=0, atol=1e-15)
    np.testing.assert_allclose(one[1].v, one[0].v, rtol=0, atol=1e-15)
    two = [_run(s, 0.3, dt, 2 * dt, 2) for s in (jr.ProjectedVerlet, jr.ProjectedLeapfrog)]
    assert float(jnp.max(jnp.abs(two[1].v - two[0].v))) > 0  # a different scheme from the second step


def test_with_friction_both_schemes_converge_to_the_same_run():
    """A sliding rod that comes to rest (stick–slip events at every node): the leapfrog's
    distance from a fine Verlet reference falls with the step (at second order here: 2.3e-4 rad
    at the scene's step, 1.6e-5 at a quarter, measured), and at each step it is Verlet's own
    (the per-node law of the reduced models: one pass of h equals two of h/2 unless a node
    stops inside the step)."""
    dt, t1 = _dt(), 0.1
    ref = _run(jr.ProjectedVerlet, 0.3, dt / 16, t1, 11)
    err = {}
    for name, scheme in (("verlet", jr.ProjectedVerlet), ("leapfrog", jr.ProjectedLeapfrog)):
        for k in (1, 4):
            sol = _run(scheme, 0.3, dt / k, t1, 11)
            assert int(sol.result) == 0
            err[name, k] = float(jnp.max(jnp.abs(sol.q - ref.q)))
    print(err)
    scale = float(jnp.max(jnp.abs(ref.q)))
    assert err["leapfrog", 4] < 0.25 * err["leapfrog", 1]
    assert err["leapfrog", 1] < 0.02 * scale
    for k in (1, 4):
        assert err["leapfrog", k] < 1.5 * err["verlet", k] + 1e-12 * scale


@pytest.mark.parametrize("scheme", ["leapfrog", "verlet"])
def test_a_rod_held_by_static_friction_does_not_move(scheme):
    """A mode-6 offset scaled so that the largest conservative acceleration it leaves is 0.95 of
    the static bound μ_s N/(ρR) (μ_s = 0.3 above μ_d = 0.2): the rod at rest stays exactly at rest
    with either scheme (the hold condition of one pass of h is that of two of h/2). At 1.05 of
    the static bound it moves, and under the dynamic coefficient it slips at once."""
    rod = jr.RodChannel.reference(0.3).with_friction(0.3, 0.2)
    scene = Scene(rod, -1.0, jr.SineVelocity(0.0, 6.0), "field", n=24)
    model = scene.model()
    shape = jnp.sin(6 * jnp.pi * jnp.asarray(model.sample_points()) / float(rod.L))  # a mode-6 offset [rad]
    t = jnp.zeros(())
    f_s, f_d = model.friction_bounds(t)
    unit = float(jnp.max(jnp.abs(model.acceleration(shape, t)) / f_s))  # the offset's share of the bound per rad
    integ = (jr.ProjectedLeapfrog if scheme == "leapfrog" else jr.ProjectedVerlet)(scene.step())
    opts = jr.RunOptions(stop_when_stuck=False, save_state=True)
    for share, held in ((0.95, True), (1.05, False)):
        q0 = share / unit * shape
        sol = jr.simulate(model, integ, q0, jnp.zeros_like(q0), 0.02, n_save=5, options=opts, throw=False)
        moved = float(jnp.max(jnp.abs(sol.q - q0[None])))
        assert (moved == 0.0) == held, (share, moved)
        assert bool(sol.stuck[0]) == held


@pytest.mark.parametrize("kind, scheme", [("field", "leapfrog"), ("rod3d", "leapfrog"),
                                          pytest.param("rod3d", "implicit", marks=pytest.mark.slow)])  # ~20 s cold
def test_the_velocity_pass_in_the_step_leaves_the_run_as_it_is(kind, scheme):
    """A save interval ends with one more pass through the step, the velocity pass
    (`ProjectedLeapfrog.velocity_in_step`: one copy of the friction pass to compile): it returns
    the velocity at the position — a half kick and friction pass of h/2, computed here by hand —
    and the run's state and bookkeeping bit for bit (a drift of 0, the forces recomputed from the
    same inputs, no work counted)."""
    rod = jr.RodChannel.reference(0.3)
    scene = Scene(rod, 5.0, jr.SineVelocity(20e-3, 6.0), kind, n=24 if kind == "field" else 12)
    model, q0, v0 = scene.model(), *scene.initial_state()
    step = jr.integrators.default_step(model, scheme=scheme) if kind == "rod3d" else scene.step()
    scheme = jr.integrators.SCHEMES[scheme](step)
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)
    h = jnp.asarray(step)

    @jax.jit
    def passes(q0, v0):
        s = scheme.start(model, q0, v0, opts)

        def body(i, c):  # 7 steps, then the pass, in one loop body as a run takes them
            after, v_at = scheme._advance(model, c[0], h, 10, 5, opts, at_position=i == 7)
            return after, v_at, c[0]

        after, v_at, s = jax.lax.fori_loop(0, 8, body, (s, s.v, s))
        v_trial = scheme.kick(model, s.q, s.v, s.a, 0.5 * h, h)  # velocity_at as it was written before
        by_hand = model.friction_update(scheme.friction, v_trial, s.v, 0.5 * h, s.t, s.q, s.a)
        return s, after, v_at, by_hand, scheme.velocity_at(model, s.q, s.v, s.a, s.t, h)

    s, after, v_at, by_hand, method = passes(q0, v0)
    assert float(s.t) > 0 and int(s.steps) == 7
    for old, new in zip(jax.tree_util.tree_leaves(s), jax.tree_util.tree_leaves(after)):
        np.testing.assert_array_equal(np.asarray(new), np.asarray(old))
    moved = False
    for a, b, v in zip(jax.tree_util.tree_leaves(v_at), jax.tree_util.tree_leaves(by_hand),
                       jax.tree_util.tree_leaves(s.v)):
        # to rounding of the leaf's largest entry (the sum's order may differ), times the implicit
        # solve's conditioning: 2e-12 of it seen on the spins
        b = np.asarray(b, float)
        np.testing.assert_allclose(np.asarray(a, float), b, rtol=0, atol=1e-11 * max(np.max(np.abs(b)), 1e-300))
        moved |= bool(np.any(np.asarray(a) != np.asarray(v)))
    assert moved  # the pass changed the velocity: the comparison is not of two unchanged copies
    # the scheme's own `velocity_at` (what a caller asks outside a run) is the same pass, to the
    # same rounding (compiled apart from the loop)
    for a, b in zip(jax.tree_util.tree_leaves(method), jax.tree_util.tree_leaves(v_at)):
        b = np.asarray(b, float)
        np.testing.assert_allclose(np.asarray(a, float), b, rtol=0, atol=1e-11 * max(np.max(np.abs(b)), 1e-300))
