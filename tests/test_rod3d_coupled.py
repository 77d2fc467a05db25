"""The implicit kick with the wall friction solved on the step's operator
(`jaxrod.rod3d.coupled`, `ImplicitLeapfrog(coupled=True)`), one kick at a time on a short rod:
the Coulomb law at the velocities the impulses produce through the coupled system (a dense
rebuild of the system and of the contacts' Jacobian), a rod held inside the cone and one pushed
past it, and a kick of zero length."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit
from jaxrod.rod3d.coupled import coupled_kick
from jaxrod.rod3d.hessian import hessian_blocks
from jaxrod.rod3d.state import held_pattern

from test_rod3d_stiffness import _dense, _free_mask


def _kick(model, q, v, hk, h, gamma=0.1, **kw):
    a = model.accelerations(q, v, 0.0)
    out, trial, _ = jax.jit(lambda q, v, a: coupled_kick(model, q, v, a, hk, h, 0.25, gamma, **kw))(q, v, a)
    return a, out, trial


def _dense_system(model, q, v, a, hk, h, gamma):
    """A = M + βh²H + γh²H_d (β = ¼) and the kick's right-hand side, dense, over all block unknowns."""
    n = model.n
    mass = np.concatenate([np.repeat(np.asarray(model.mass)[:, None], 3, 1),
                           np.concatenate([np.repeat(np.asarray(model.inertia)[None], n, 0), np.ones((1, 3))])], -1)
    H = _dense(*(np.asarray(b) for b in hessian_blocks(model, q.x, q.Q)))
    Hd = _dense(*(np.asarray(b) for b in hessian_blocks(model, q.x, q.Q, damped=True)))
    A = np.diag(mass.reshape(-1)) + 0.25 * h * h * H + gamma * h * h * Hd
    W = np.asarray(v.w)
    gyro = np.cross(W, np.asarray(model.inertia) * W)
    F = np.concatenate([np.asarray(a.f), np.concatenate([np.asarray(a.tau) - gyro, np.zeros((1, 3))])], -1).reshape(-1)
    vel = np.concatenate([np.asarray(v.v), np.concatenate([W, np.zeros((1, 3))])], -1).reshape(-1)
    free = _free_mask(model)
    rhs = hk * F - gamma * h * hk * Hd @ np.where(free, vel, 0.0)
    return A, rhs, vel, free


def _contact_jacobian(model, q):
    """G (2(n + 1), 6(n + 1)): the slip of node i's contact point, t_a·vᵢ + Σ_seg c r (Q û_a)·w_seg,
    written out from its definition (t₁ = x̂, t₂ = x̂ × e_r, û₁ = e_r × x̂, û₂ = x̂; c = ½ inside,
    1 at the ends; r = d/2)."""
    n = model.n
    x, Q = np.asarray(q.x), np.asarray(q.Q)
    r = 0.5 * float(model.rod.d)
    G = np.zeros((2 * (n + 1), 6 * (n + 1)))
    xhat = np.array([1.0, 0.0, 0.0])
    for i in range(n + 1):
        e = np.array([0.0, x[i, 1], x[i, 2]]) / np.hypot(x[i, 1], x[i, 2])
        t = (xhat, np.cross(xhat, e))
        u = (np.cross(e, xhat), xhat)
        segs = [s for s in (i - 1, i) if 0 <= s < n]
        for a_ in range(2):
            G[2 * i + a_, 6 * i:6 * i + 3] = t[a_]
            for s in segs:
                G[2 * i + a_, 6 * s + 3:6 * s + 6] += r / len(segs) * Q[s] @ u[a_]
    return G


@pytest.mark.parametrize("v0, spin, method", [(0.02, 0.0, "newton"), (0.002, 40.0, "newton"), (0.02, 0.0, "admm")])
def test_the_impulses_satisfy_coulomb_at_the_velocities_of_the_coupled_system(v0, spin, method):
    """One kick of 100× the explicit limit on an 8-segment rod on the wall (μ_s = μ_d = 0.3),
    moving along the wall (and spinning): with p the impulses the solve returns (force × hk),
    A Δv = rhs + Gᵀp on the free unknowns to rounding (A, rhs and G rebuilt densely from their
    definitions), and at every contact ‖p‖ ≤ μ N hk, with a stuck contact's slip G v zero and a
    sliding one's impulse μ N hk against its slip, to the solve's tolerance; by Newton (a few
    iterations) and by ADMM."""
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 8, control="load", end_load=2.0, friction_tol=1e-8)
    q, v = model.initial_state(None, lateral_velocity=sine_velocity(model, v0))
    w = np.random.default_rng(1).normal(size=v.w.shape) * spin
    v = type(v)(v.v, jnp.where(jnp.asarray(held_pattern(model)[1]), 0.0, jnp.asarray(w)), v.stuck, v.force, v.residual, v.sweeps)
    h = float(100 * step_limit(model))
    a, out, _ = _kick(model, q, v, h, h, max_iter=2000, method=method)
    assert int(out.sweeps) < (8 if method == "newton" else 2000)

    A, rhs, vel, free = _dense_system(model, q, v, a, h, h, 0.1)
    G = _contact_jacobian(model, q)
    p = (np.asarray(out.force) * h).reshape(-1)
    new = np.concatenate([np.asarray(out.v), np.concatenate([np.asarray(out.w), np.zeros((1, 3))])], -1).reshape(-1)
    delta = np.where(free, new - vel, 0.0)
    resid = (A @ delta - rhs - G.T @ p)[free]
    assert np.abs(resid).max() <= 1e-8 * np.abs(rhs[free]).max()

    u = (G @ new).reshape(-1, 2)
    p = p.reshape(-1, 2)
    bound = 0.3 * np.asarray(a.N) * h
    pn, un = np.hypot(*p.T), np.hypot(*u.T)
    stuck = np.asarray(out.stuck)
    assert np.all(pn <= bound * (1 + 1e-6))
    scale_u = np.abs(np.asarray(v.v)).max()
    assert np.all(un[stuck] < 1e-6 * scale_u)
    sliding = ~stuck & (un > 1e-6 * scale_u)
    assert np.any(sliding) or np.all(stuck)
    if np.any(sliding):
        np.testing.assert_allclose(p[sliding], -bound[sliding, None] * u[sliding] / un[sliding, None], rtol=0,
                                   atol=1e-5 * bound.max())


def test_a_rod_held_inside_the_cone_stays_and_one_pushed_past_it_slides_at_its_rate():
    """A free 10-segment rod at rest on the bottom (μ_s = 0.5, μ_d = 0.3) pushed along its axis by
    0.4 w per length: in a kick of 100× the explicit limit no contact point slips (solved to
    friction_tol 1e-9: the slip is the solve's residual), every contact stuck and the friction
    forces sum to the push; pushed by 0.8 w it slides, every node gaining (0.8 − μ) g hk."""
    rod = jr.RodChannel.reference(0.5).with_friction(0.5, 0.3)
    w = float(rod.w)
    for ratio in (0.4, 0.8):
        model = Rod3D(rod, 10, ends="free", body_force=(ratio * w, 0.0, 0.0), friction_tol=1e-9)
        q, v = model.initial_state()
        h = float(100 * step_limit(model))
        a, out, trial = _kick(model, q, v, h, h, max_iter=5000)
        if ratio < 0.5:  # held: no contact point slips (the segments may roll elastically, by < 1e-6 m/s)
            new = np.concatenate([np.asarray(out.v), np.concatenate([np.asarray(out.w), np.zeros((1, 3))])], -1)
            slip = _contact_jacobian(model, q) @ new.reshape(-1)
            assert bool(np.all(out.stuck)) and np.abs(slip).max() < 1e-10
            assert np.abs(np.asarray(out.v)).max() < 1e-5
            assert float(jnp.sum(out.force[:, 0])) == pytest.approx(-ratio * w * float(rod.L), rel=1e-4)
        else:
            # the first kick starts from contacts held at rest: the static bound (the local pass's
            # rule too); the next, from a sliding rod, the dynamic one
            assert not bool(np.any(out.stuck))
            np.testing.assert_allclose(np.asarray(out.v[:, 0]), (ratio - 0.5) * 9.81 * h, rtol=1e-6)
            _, second, _ = _kick(model, q, out, h, h, max_iter=5000)
            np.testing.assert_allclose(np.asarray(second.v[:, 0] - out.v[:, 0]), (ratio - 0.3) * 9.81 * h, rtol=1e-6)
        # the trial velocity is the one the friction impulse brought to v_new: M (trial − new) = −Gᵀp
        np.testing.assert_allclose(np.asarray(model.mass) * np.asarray(trial.v[:, 0] - out.v[:, 0]),
                                   -np.asarray(out.force[:, 0]) * h, rtol=1e-9, atol=1e-15)


def test_a_kick_of_zero_length_changes_nothing():
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 6, control="load", end_load=2.0)
    q, v = model.initial_state(None, lateral_velocity=sine_velocity(model, 0.01))
    v = type(v)(v.v, v.w, jnp.ones_like(v.stuck), jnp.full_like(v.force, 0.01), v.residual, v.sweeps)
    _, out, _ = _kick(model, q, v, 0.0, 1e-4)
    np.testing.assert_array_equal(np.asarray(out.v), np.asarray(v.v))
    np.testing.assert_array_equal(np.asarray(out.stuck), np.asarray(v.stuck))
    np.testing.assert_array_equal(np.asarray(out.force), np.asarray(v.force))


def test_the_wrinkling_load_and_where_each_scheme_runs():
    """F_w = 2√(EI k_w), k_w = 1.5 w/δ₀ at the default wall (δ₀ = 1e-3 R): 50.05 N for the reference
    rod, from its own numbers; none without a channel. A sine scene runs the implicit default below
    it and the explicit leapfrog past it (a given `scheme_key` wins); the implicit scheme's local
    pass ends a run past it with the result code `inadequate`, the coupled solve does not."""
    from jaxrod import RESULTS, theory
    from jaxrod.perturbations import SineVelocity
    from jaxrod.scene import Scene

    rod = jr.RodChannel.reference(0.3)
    EI = float(rod.E) * np.pi * float(rod.d) ** 4 / 64
    w = float(rod.rho_v) * np.pi * float(rod.d) ** 2 / 4 * float(rod.g)
    F_w = 2 * np.sqrt(EI * 1.5 * w / (1e-3 * float(rod.R)))
    assert float(Rod3D(rod, 6).wrinkling_load()) == pytest.approx(F_w, rel=1e-9)
    assert F_w == pytest.approx(50.05, abs=0.01)
    assert np.isinf(float(Rod3D(rod, 6, channel=False).wrinkling_load()))

    F0 = float(theory.reference_load(rod))
    below, past = F_w - F0 - 1.0, F_w - F0 + 1.0
    sine = SineVelocity(1e-3)
    assert Scene(rod, below, sine, kind="rod3d", n=12).scheme() is None
    assert Scene(rod, past, sine, kind="rod3d", n=12).scheme() == "leapfrog"
    assert Scene(rod, past, sine, kind="rod3d", n=12, scheme_key="implicit").scheme() == "implicit"

    for dF, coupled, code in ((below, False, RESULTS.successful), (past, False, RESULTS.inadequate),
                              (past, True, RESULTS.successful)):
        model = Rod3D(rod, 6, control="load", end_load=F0 + dF)
        scheme = jr.ImplicitLeapfrog(5e-5, coupled=coupled)
        q0, v0 = model.initial_state()
        s = scheme.start(model, q0, v0, jr.RunOptions())
        assert int(scheme.result(model, s, jnp.asarray(5e-5))) == code
