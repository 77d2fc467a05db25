"""The error-controlled implicit leapfrog (`jaxrod.AdaptiveImplicitLeapfrog`) on a short 3D rod, in
the default suite: one compiled program (the tolerances are array leaves, one lane each under
`vmap`) whose lanes take their own steps, land on the save times, reject steps where the first
is too long, and approach the explicit scheme as the tolerance tightens (to a floor); and the local error
estimate it steers by against a hand computation."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit
from jaxrod.rod3d.state import held_pattern

RTOLS = (1e-1, 1e-2, 1e-3, 1e-4)


def _rod():
    """A free rod in space (no wall, gravity or friction), 8 segments, fork ends, in the linear
    regime: its lowest bending mode moving at 1 mm/s."""
    rod = jr.RodChannel.reference(0.0)
    model = Rod3D(rod, 8, channel=False, gravity=False, ends="fork", control="force")
    q0, v0 = model.initial_state(0.0, lateral_velocity=sine_velocity(model, 1e-3, mode=1))
    return model, q0, v0


@pytest.fixture(scope="module")
def runs():
    model, q0, v0 = _rod()
    lim = float(step_limit(model))
    dt = 50 * lim
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)
    t1 = 0.25

    @jax.jit
    def lanes(rtol):
        def one(r):
            integ = jr.AdaptiveImplicitLeapfrog(dt, rtol=r, atol=1e-12, dt0=dt)
            return jr.simulate(model, integ, q0, v0, t1, n_save=6, options=opts, throw=False)

        return jax.vmap(one)(rtol)

    sols = lanes(jnp.asarray(RTOLS))
    return model, sols, dt, lim, t1


def test_lanes_take_their_own_steps_and_land_on_the_save_times(runs):
    model, sols, dt, lim, t1 = runs
    assert np.asarray(sols.result).tolist() == [0] * len(RTOLS)
    np.testing.assert_array_equal(np.asarray(sols.ts[0]), np.linspace(0.0, t1, 6))
    steps = np.asarray(sols.n_steps)
    # from 1e-2 down, a tighter tolerance takes more steps; at 1e-1 the controller thrashes (grows the
    # step into the aliased stiff modes, rejects: measured 3917 steps, 1666 of them rejected)
    assert steps[1] < steps[3] and steps[2] < steps[3], steps
    stats = {k: np.asarray(v) for k, v in sols.step_stats.items()}
    assert np.all(stats["rejected"] >= 1)  # the first step, dt = 50 explicit limits, is too long
    assert np.all(stats["forced"] == 0)
    assert np.all(stats["h_max"] <= dt * (1 + 1e-12)) and np.all(stats["h_min"] >= dt / 1000 * (1 - 1e-12))
    assert stats["h_max"][0] > 5 * lim  # the loosest lane steps far past the explicit limit
    np.testing.assert_allclose(np.asarray(sols.t_stop), t1, rtol=1e-12)


def test_the_error_falls_with_the_tolerance_against_the_explicit_scheme(runs):
    """Every save against the explicit leapfrog at 0.02 of its limit: the lateral displacement's
    error falls with the tolerance down to a floor, at every save time (a save taken at a wrong
    time would not)."""
    model, sols, dt, lim, t1 = runs
    _, q0, v0 = _rod()
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)
    ref = jax.jit(lambda q, v: jr.simulate(model, jr.ProjectedLeapfrog(0.02 * lim), q, v, t1, n_save=6, options=opts))(q0, v0)
    y_ref = np.asarray(ref.q.x[..., 1])
    scale = np.abs(y_ref).max()
    errs = np.abs(np.asarray(sols.q.x[..., 1]) - y_ref[None]).max(axis=(1, 2)) / scale
    print("relative errors by rtol:", dict(zip(RTOLS, errs)))
    assert scale > 1e-5  # the rod moved
    # measured 4.4e-3, 6.6e-6, 2.73e-6, 2.71e-6: it falls, then stays at 2.7e-6 from 1e-3 on (the
    # estimate, a mean over the nodes, is blind to the start's small shear-mode content; docs/rod3d.md)
    assert errs[0] > 100 * errs[1] and errs[1] > 2 * errs[2] and errs[3] <= 1.01 * errs[2] < 1e-5, errs


def test_the_error_estimate_is_newmarks_local_error_on_the_free_translations():
    """`Rod3D.step_error` by hand: |β − 1/6| h² |Δa| per node, against atol + rtol·|Δx|, root mean
    square over the nodes not wholly held."""
    model, q0, v0 = _rod()
    a0 = model.accelerations(q0, v0, 0.0)
    h = 1e-4
    q1 = model.drift(q0, v0, h)
    a1 = model.accelerations(q1, v0, h)
    err = float(model.step_error(q0, q1, a0, a1, h, 0.25, 1e-3, 1e-12))
    free = ~np.all(np.asarray(held_pattern(model)[0]), -1)
    e = (0.25 - 1 / 6) * h * h * np.linalg.norm(np.asarray(a1.f) - np.asarray(a0.f), axis=-1) / np.asarray(model.mass)
    ratio = e / (1e-12 + 1e-3 * np.linalg.norm(np.asarray(q1.x - q0.x), axis=-1))
    assert free.tolist() == [False] + [True] * 7 + [False]  # fork ends: both end nodes held (control "force")
    assert err == pytest.approx(np.sqrt(np.mean(ratio[free] ** 2)), rel=1e-12)
    assert err > 0
    # the factor |β − 1/6| at another β (at ¼ it is 1/12, as |¼ − 1/3| would be): zero at 1/6
    assert float(model.step_error(q0, q1, a0, a1, h, 0.5, 1e-3, 1e-12)) == pytest.approx(err * 4.0, rel=1e-12)
    assert float(model.step_error(q0, q1, a0, a1, h, 1.0 / 6.0, 1e-3, 1e-12)) == pytest.approx(0.0, abs=1e-12 * err)


def test_a_step_after_a_rejection_does_not_grow_and_one_after_an_acceptance_doubles_at_most():
    """The controller's factor clip(0.9 err^(−1/3), 0.2, 2) with a loose tolerance (err ≪ 1): the
    next step twice the one just taken, but equal to it right after a rejected attempt (Hairer,
    Nørsett & Wanner, II.4); a tight tolerance rejects the attempt, keeps the state and shrinks
    the step by at most 5×."""
    import dataclasses

    from jaxrod.integrators.base import save_grid

    model, q0, v0 = _rod()
    dt = 50 * float(step_limit(model))
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)
    m, h = save_grid(0.25, 6, dt)
    h = jnp.asarray(h)
    for rejected_last, grows in ((False, 2.0), (True, 1.0)):
        integ = jr.AdaptiveImplicitLeapfrog(dt, rtol=1.0, atol=1.0, dt0=dt / 8)
        s = integ.start(model, q0, v0, opts)
        s = dataclasses.replace(s, control=dataclasses.replace(s.control, rejected_last=jnp.array(rejected_last)))
        s1 = integ.advance(model, s, h, m, 6, opts)
        assert int(s1.steps) == 1 and int(s1.control.rejected) == 0
        assert float(s1.control.h_prev) == pytest.approx(dt / 8, rel=1e-12)
        assert float(s1.control.h_next) == pytest.approx(grows * dt / 8, rel=1e-12)
    tight = jr.AdaptiveImplicitLeapfrog(dt, rtol=0.0, atol=1e-30, dt0=dt / 8)
    s = tight.start(model, q0, v0, opts)
    s1 = tight.advance(model, s, h, m, 6, opts)
    assert int(s1.steps) == 0 and int(s1.control.rejected) == 1 and bool(s1.control.rejected_last)
    assert np.array_equal(np.asarray(s1.q.x), np.asarray(q0.x))
    assert float(s1.control.h_next) == pytest.approx(0.2 * dt / 8, rel=1e-12)
    # accepted exactly where the scaled estimate is at most 1: at 0.9 taken, at 1.5 rejected
    loose = jr.AdaptiveImplicitLeapfrog(dt, rtol=0.0, atol=1.0, dt0=dt / 8)
    s = loose.start(model, q0, v0, opts)
    s1 = loose.advance(model, s, h, m, 6, opts)
    err = float(model.step_error(s.q, s1.q, s.a, s1.a, dt / 8, 0.25, 0.0, 1.0))  # the attempt's, in metres
    for ratio, taken in ((0.9, 1), (1.5, 0)):
        integ = jr.AdaptiveImplicitLeapfrog(dt, rtol=0.0, atol=err / ratio, dt0=dt / 8)
        s1 = integ.advance(model, integ.start(model, q0, v0, opts), h, m, 6, opts)
        assert (int(s1.steps), int(s1.control.rejected)) == (taken, 1 - taken)


@pytest.mark.parametrize("kw, name", [(dict(rtol=-1.0), "rtol"), (dict(atol=float("nan")), "atol"),
                                      (dict(dt_min=2.0), "dt_min"), (dict(dt0=0.0), "dt0")])
def test_bad_tolerances_are_refused_by_name(kw, name):
    with pytest.raises(ValueError, match=name):
        jr.AdaptiveImplicitLeapfrog(1e-3, **kw)
