"""A 3D rod released from rest, with the default options (the run stops when the rod is stuck).

A contact at rest starts under the static coefficient, and no friction pass has yet seen the
forces at t = 0: the stick stop must judge the forces themselves (a contact is held only while
the force it must resist from rest is within μ_s N), or every rod released from rest is
declared stuck at step 0. References: the same runs without the stop (which cannot freeze), and
Coulomb's law for a free rod pushed along the channel."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import SweepSpec, sweep
from jaxrod.rod3d import Rod3D
from jaxrod.registry import make_perturbation
from jaxrod.scene import Scene


@functools.lru_cache(maxsize=1)
def _random_shapes():
    """Random lateral shapes (±2 mm) released from rest at ΔF = 0 (below the frictionless load:
    they slide back and stay) and ΔF = 40 N (outside the stable zone: they buckle), through a
    3D sweep with the default stop (12 segments, to 0.05 s)."""
    spec = SweepSpec(model="rod3d", n=12, perturbation="random-shape", amplitude=2e-3, t1=0.05)
    return sweep(spec, {"dF": [0.0, 40.0], "realization": [0, 1]}, seed=3, progress=False)


def test_a_random_shape_sweep_released_from_rest_runs_until_it_buckles_or_to_its_end():
    """(The default suite's only 3D sweep: tests/test_sweep.py's is `slow`.) The members at
    ΔF = 0 run to t1 below the threshold of 0.5 rad; those at 40 N stop when they reach it; each
    reports its steps, its stop time and a dominant mode among the 11 interior nodes' modes.
    Before the force test every member stopped at step 0 and was reported stable."""
    res = _random_shapes()
    out, dt = res.outputs, res.meta["dt"]
    assert out["result"].tolist() == [0] * 4
    np.testing.assert_array_equal(out["buckled"], [False, False, True, True])
    np.testing.assert_array_equal(out["t_stop"][:2], [0.05, 0.05])
    np.testing.assert_array_equal(out["t_stop"][2:], out["t_buckle"][2:])
    assert np.all(out["max_theta"][:2] < 0.5) and np.all(out["max_theta"][2:] >= 0.5)
    assert np.all(np.isinf(out["t_buckle"][:2])) and np.all(out["t_buckle"][2:] < 0.05)
    # steps of the largest h ≤ dt that puts every save on a step (0.2 % below dt here)
    np.testing.assert_allclose(out["steps"] * dt, out["t_stop"], rtol=5e-3)
    assert np.all((out["dominant_mode"] >= 1) & (out["dominant_mode"] <= 11))


@pytest.mark.slow  # a 3D run without the stop (~20 s cold), beside the sweep above
def test_a_random_shape_released_from_rest_gets_the_label_of_the_run_without_the_stop():
    """Each member of the sweep above has the label, buckling time and amplitude of its single
    run without the stop (which cannot freeze a rod), to one step."""
    res = _random_shapes()
    rod, dt = jr.RodChannel.reference(0.3), res.meta["dt"]
    opts = jr.RunOptions(stop_when_stuck=False, save_state=False)
    for i in range(len(res)):
        pert = make_perturbation("random-shape", 2e-3, 6, jax.random.fold_in(jax.random.key(3), i))
        scene = Scene(rod, res.inputs["dF"][i], pert, "rod3d", n=12, dt=dt)
        sol = jr.simulate(scene.model(), scene.integrator(), *scene.initial_state(), 0.05, n_save=201,
                          options=opts, throw=False)
        assert bool(sol.buckled) == bool(res.outputs["buckled"][i])
        if sol.buckled:
            assert abs(float(sol.t_buckle) - res.outputs["t_buckle"][i]) <= 1.01 * dt
        else:  # not stopped before t1 either: the same run to the end
            np.testing.assert_allclose(res.outputs["max_theta"][i], float(jnp.max(sol.amplitude)), rtol=1e-4)


def test_the_stick_test_at_rest_holds_exactly_the_forces_inside_the_static_cone():
    """A free rod at rest on the channel bottom pushed along its axis by a body force b per
    length: with friction at the centre line it is held while b < μ_s w (0.49 w: held; 0.51 w:
    not), whatever the dynamic coefficient. With friction at the contact point the axial friction
    also tilts the segments (a couple r·F that nothing balances in the straight rod): not held
    even at 0.4 w — it must move, by an elastic micro-motion, before it can stick. The straight
    rod under a dead load F⁰₆ + 5 N (an equilibrium) is held; a random shape at F⁰₆ + 40 N is
    not (this was the state declared stuck at step 0)."""
    rod = jr.RodChannel.reference(0.5).with_friction(0.5, 0.3)
    w = float(rod.w)

    def stuck_at_rest(model, state):
        return bool(model.is_stuck(state[0], state[1], model.acceleration(state[0])))

    for at, ratio, held in (("axis", 0.49, True), ("axis", 0.51, False), ("surface", 0.4, False)):
        m = Rod3D(rod, 12, ends="free", body_force=(ratio * w, 0.0, 0.0), friction_at=at)
        assert stuck_at_rest(m, m.initial_state()) == held, (at, ratio)
    rod = jr.RodChannel.reference(0.3)
    F = float(jr.theory.frictionless_load(rod, 6))
    m = Rod3D(rod, 12, control="load", end_load=F + 5.0)
    assert stuck_at_rest(m, m.initial_state(F + 5.0))
    scene = Scene(rod, 40.0, make_perturbation("random-shape", 2e-3, 6, jax.random.key(0)), "rod3d", n=12, dt=1e-5)
    assert not stuck_at_rest(scene.model(), scene.initial_state())


def test_a_lateral_force_is_added_to_the_body_force_at_every_node():
    """`under_lateral_force` (the random-position forcing): the y component of each node's body
    force grows by the given force per length; x and z are unchanged."""
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 6, body_force=jnp.array([0.1, 0.2, -0.3]))
    f = jnp.linspace(-1.0, 1.0, 7)
    forced = model.under_lateral_force(f)
    np.testing.assert_array_equal(np.asarray(forced.body_force), np.stack([np.full(7, 0.1), 0.2 + np.asarray(f),
                                                                           np.full(7, -0.3)], -1))


def test_a_free_rod_in_space_is_held_only_where_its_supports_hold_it():
    """`static_equilibrium` without a channel: one flag per node and per segment, true only for
    the held ones (nothing else holds a rod in space)."""
    from jaxrod.rod3d.contact import static_equilibrium

    model = Rod3D(jr.RodChannel.reference(0.3), 6, channel=False, ends="clamped")
    q, v = model.initial_state(1.0)
    a = model.acceleration(q)
    nodes, segments = static_equilibrium(model, q.x, q.Q, a.f, a.tau, a.N)
    assert nodes.shape == (7,) and segments.shape == (6,)
    assert nodes.tolist() == [True, False, False, False, False, False, True]
    assert segments.tolist() == [True, False, False, False, False, True]


def test_the_stick_test_up_the_channel_wall_is_the_test_at_the_bottom_turned():
    """The channel is round: the rod at rest on its bottom, turned by φ = 0.6 rad about the axis
    together with its weight (a body force w(R ĝ − ĝ) per length), rests on the wall 0.6 rad up
    its side. A push along the wall's tangent t₂ = (0, cos φ, sin φ) of 0.49 w per length is held
    (μ_s = 0.5, friction at the centre line) and 0.51 w is not, as a lateral push at the bottom."""
    rod = jr.RodChannel.reference(0.5).with_friction(0.5, 0.3)
    w, phi = float(rod.w), 0.6
    c, s = np.cos(phi), np.sin(phi)
    R = jnp.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    g = np.array([0.0, 0.0, -1.0])
    turned_weight = w * (np.asarray(R) @ g - g)
    for ratio, held in ((0.49, True), (0.51, False)):
        push = ratio * w * np.array([0.0, c, s])
        m = Rod3D(rod, 12, ends="free", body_force=turned_weight + push, friction_at="axis")
        q, v = m.initial_state()
        q = type(q)(x=q.x @ R.T, Q=q.Q @ R.T)
        e = q.x[:, 1:] / jnp.linalg.norm(q.x[:, 1:], axis=-1, keepdims=True)
        np.testing.assert_allclose(np.asarray(e), np.tile([s, -c], (13, 1)), atol=1e-12)  # up the side
        assert bool(m.is_stuck(q, v, m.acceleration(q))) == held, ratio
        bottom = Rod3D(rod, 12, ends="free", body_force=(0.0, ratio * w, 0.0), friction_at="axis")
        qb, vb = bottom.initial_state()
        assert bool(bottom.is_stuck(qb, vb, bottom.acceleration(qb))) == held


@pytest.mark.parametrize("phi", [0.0, 0.6])
def test_torques_that_balance_the_contact_frictions_couples_hold_the_rod_on_the_wall(phi):
    """`static_equilibrium` with friction at the contact point: a rod resting φ up the channel's
    side, pushed along its axis (the wall's friction F₁ = p x̂ at each free node, inside the
    static cone), is held exactly when its segments' torques balance the friction couples
    r e_r × F (r = d/2, e_r the wall's outward normal; each node's couple shared between its
    segments as its spin is) — written here as the cross product. Torques of the opposite sign,
    or none, leave it free to roll; one segment's torque turned leaves that segment alone free."""
    from jaxrod.rod3d.contact import node_weights, static_equilibrium

    rod = jr.RodChannel.reference(0.5).with_friction(0.5, 0.3)
    n, c, s = 12, np.cos(phi), np.sin(phi)
    model = Rod3D(rod, n, ends="free", friction_at="surface")
    q, _ = model.initial_state()
    R = jnp.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    q = type(q)(x=q.x @ R.T, Q=q.Q @ R.T)
    e_r = np.array([0.0, s, -c])  # up the side
    N = np.full(n + 1, 0.01)  # [N]
    p = 0.3 * 0.5 * N  # within μ_s N
    f = np.stack([-p, 0.0 * p, 0.0 * p], -1)  # the push the wall's friction F₁ = p holds
    C = 0.5 * float(rod.d) * np.cross(e_r, np.stack([p, 0.0 * p, 0.0 * p], -1))  # (n + 1, 3) couples
    cl, cr = (np.asarray(w) for w in node_weights(model))
    on_seg = cr[:-1, None] * C[:-1] + cl[1:, None] * C[1:]
    tau = -np.einsum("kij,kj->ki", np.asarray(q.Q), on_seg)  # material frame
    one = tau.copy()
    one[4] *= -1.0
    for torques, held in ((tau, np.ones(n, bool)), (-tau, np.zeros(n, bool)), (0.0 * tau, np.zeros(n, bool)),
                          (one, np.arange(n) != 4)):
        nodes, segments = static_equilibrium(model, q.x, q.Q, jnp.asarray(f), jnp.asarray(torques), jnp.asarray(N))
        assert nodes.shape == (n + 1,) and bool(jnp.all(nodes)), phi
        np.testing.assert_array_equal(np.asarray(segments), held, err_msg=str(phi))
