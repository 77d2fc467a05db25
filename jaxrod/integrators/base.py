"""The interface every integrator implements, and the fixed-step machinery they share."""

from __future__ import annotations

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp

from .._results import RESULTS
from ..models.base import AbstractModel
from ..solution import Solution

__all__ = ["AbstractIntegrator", "AbstractFixedStep", "RunOptions"]


class RunOptions(eqx.Module):
    """How a run stops and what it keeps (all static).

    - `buckle_threshold`: amplitude [rad] past which the run counts as buckled and the state is
      frozen (`None`: the model's default, 0.5 rad for the rod models, `inf` for one mode).
    - `stop_when_stuck`: freeze the state once the whole system is stuck under a constant load
      (exact for the sharp law: nothing can release it).
    - `early_exit`: leave the time loop as soon as the run (every member of a batch) has
      stopped. Uses a `while_loop`, which forward-mode AD supports but reverse mode does not:
      set `False` for `jax.grad`.
    - `save_state`: keep q and v at every save time (otherwise only the summaries).
    """

    buckle_threshold: float | None = eqx.field(static=True, default=None)
    stop_when_stuck: bool = eqx.field(static=True, default=True)
    early_exit: bool = eqx.field(static=True, default=True)
    save_state: bool = eqx.field(static=True, default=True)

    def threshold(self, model) -> float:
        return model.buckle_threshold if self.buckle_threshold is None else self.buckle_threshold


class AbstractIntegrator(eqx.Module):
    """Integrates a model from (q₀, v₀) at t = 0 to `t1`, saving `n_save` equally spaced
    states (t = 0 and t = `t1` included)."""

    @abc.abstractmethod
    def integrate(
        self, model: AbstractModel, q0, v0, t1: float, n_save: int, options: RunOptions
    ) -> Solution:
        """Run the model; returns a [`jaxrod.Solution`][]."""

    def step_limit(self, model: AbstractModel):
        """The largest stable step for `model` [s] (`inf` when there is none)."""
        return jnp.inf


def friction_work(model, v_prev, v_trial, v_after):
    """Energy friction dissipated by an impulse that took `v_trial` to `v_after` over a
    (half) step that began at velocity `v_prev`: the impulse times the mean velocity over the
    step, (v_trial − v_after)·M·(v_prev + v_after)/2 (a midpoint rule for ∫ f|v| dt). Zero for
    a point held at rest: it does not move, so friction does no work on it."""
    return jax.jvp(model.kinetic_energy, (0.5 * (v_prev + v_after),), (v_trial - v_after,))[1]


def save_grid(t1: float, n_save: int, dt: float) -> tuple[int, float]:
    """Steps per save interval and the step actually used: the largest h ≤ `dt` that puts
    every save time on a step."""
    interval = t1 / (n_save - 1)
    m = max(1, math.ceil(interval / dt * (1 - 1e-12)))
    return m, interval / m


def summarize(model, ts, qs, vs, dissipated, options, n_steps, extra_bad=False):
    """A [`jaxrod.Solution`][] from saved states (for integrators that do not stop early)."""
    thr = options.threshold(model)
    amp = jax.vmap(model.amplitude)(qs)
    energies = jax.vmap(model.energy_terms)(qs, vs, ts)
    stuck = jax.vmap(model.is_stuck)(qs, vs, ts)
    over = amp > thr
    buckled = jnp.any(over)
    i_b = jnp.argmax(over)
    t_buckle = jnp.where(buckled, ts[i_b], jnp.inf)
    finite = jnp.isfinite(qs).all() & jnp.isfinite(vs).all()
    result = jnp.where(
        extra_bad, RESULTS.max_steps, jnp.where(finite, RESULTS.successful, RESULTS.nonfinite)
    ).astype(jnp.int32)
    return Solution(
        ts=ts,
        q=qs if options.save_state else None,
        v=vs if options.save_state else None,
        stuck=stuck,
        amplitude=amp,
        energies=energies,
        dissipated=dissipated,
        buckled=buckled,
        t_buckle=t_buckle,
        t_stop=jnp.where(buckled, t_buckle, ts[-1]),
        q_final=qs[-1],
        v_final=vs[-1],
        result=result,
        n_steps=jnp.asarray(n_steps, dtype=jnp.int32),
    )


class AbstractFixedStep(AbstractIntegrator):
    """A fixed-step one-step scheme. Subclasses define `dt` and `step`.

    The time loop checks the buckling threshold after every step (so `t_buckle` is resolved to
    one step) and the stick test at every save; a stopped run is frozen, and with
    `early_exit` the loop ends once the run (every member of a vmapped batch) has stopped.
    """

    dt: eqx.AbstractVar[float]

    @abc.abstractmethod
    def step(self, model: AbstractModel, q, v, a, t, h):
        """One step of size `h` from (q, v) at time t, with `a` = the conservative acceleration
        at (q, t) (reused across steps). Returns `(q, v, a, dissipated)` at t + h, where
        `dissipated` is the energy friction removed during the step."""

    def step_limit(self, model):
        om = model.max_frequency()
        return jnp.where(om > 0, 2.0 / jnp.where(om > 0, om, 1.0), jnp.inf)

    def integrate(self, model, q0, v0, t1, n_save, options=RunOptions()):
        m, h = save_grid(t1, n_save, self.dt)
        dtype = jnp.result_type(float)
        q0 = jnp.asarray(q0, dtype=dtype)
        v0 = jnp.asarray(v0, dtype=dtype)
        thr = options.threshold(model)
        freeze_stuck = options.stop_when_stuck and model.autonomous
        zero = jnp.zeros((), dtype)
        t_ = jnp.asarray(0, dtype)
        a0 = model.acceleration(q0, t_)

        # carry: q, v, a, t, D, buckled, t_buckle, done, steps
        def one(c, _):
            q, v, a, t, D, buckled, t_b, done, steps = c
            q1, v1, a1, dD = self.step(model, q, v, a, t, h)
            t1_ = t + h
            new_b = model.amplitude(q1) > thr
            keep = lambda old, new: jnp.where(done, old, new)
            return (
                keep(q, q1), keep(v, v1), keep(a, a1), keep(t, t1_), keep(D, D + dD),
                keep(buckled, new_b), keep(t_b, jnp.where(new_b, t1_, t_b)),
                done | new_b, steps + jnp.where(done, 0, 1),
            ), None

        def record(q, v, t, stuck, D):
            rec = {
                "stuck": stuck,
                "dissipated": D,
                "amplitude": model.amplitude(q),
                "energies": model.energy_terms(q, v, t),
            }
            if options.save_state:
                rec["q"], rec["v"] = q, v
            return rec

        def interval(c):
            c, _ = jax.lax.scan(one, c, None, length=m)
            q, v, a, t, D, buckled, t_b, done, steps = c
            stuck = model.is_stuck(q, v, t)
            if freeze_stuck:
                done = done | stuck
            c = (q, v, a, t, D, buckled, t_b, done, steps)
            return c, record(q, v, t, stuck, D)

        c0 = (q0, v0, a0, t_, zero, jnp.array(False), jnp.asarray(jnp.inf, dtype), jnp.array(False),
              jnp.array(0, jnp.int32))
        stuck0 = model.is_stuck(q0, v0, t_)
        if freeze_stuck:
            c0 = c0[:7] + (stuck0,) + c0[8:]
        rec0 = record(q0, v0, t_, stuck0, zero)

        if options.early_exit:
            bufs = jax.tree_util.tree_map(
                lambda x: jnp.zeros((n_save,) + x.shape, x.dtype).at[0].set(x), rec0
            )

            def cond(state):
                i, c, _ = state
                return (i < n_save - 1) & ~c[7]

            def body(state):
                i, c, bufs = state
                c, rec = interval(c)
                bufs = jax.tree_util.tree_map(lambda b, x: b.at[i + 1].set(x), bufs, rec)
                return i + 1, c, bufs

            i_end, c, bufs = jax.lax.while_loop(cond, body, (jnp.array(0), c0, bufs))
            later = jnp.arange(n_save) > i_end
            bufs = jax.tree_util.tree_map(
                lambda b: jnp.where(
                    later.reshape((-1,) + (1,) * (b.ndim - 1)), b[i_end][None], b
                ),
                bufs,
            )
            recs = bufs
        else:
            c, recs = jax.lax.scan(lambda c, _: interval(c), c0, None, length=n_save - 1)
            recs = jax.tree_util.tree_map(
                lambda x0, xs: jnp.concatenate([x0[None], xs]), rec0, recs
            )

        q, v, a, t, D, buckled, t_b, done, steps = c
        ts = jnp.linspace(0.0, t1, n_save, dtype=dtype)
        finite = jnp.isfinite(q).all() & jnp.isfinite(v).all() & jnp.isfinite(recs["amplitude"]).all()
        too_big = h >= self.step_limit(model)
        result = jnp.where(
            too_big,
            RESULTS.step_limit,
            jnp.where(finite, RESULTS.successful, RESULTS.nonfinite),
        ).astype(jnp.int32)
        return Solution(
            ts=ts,
            q=recs.get("q"),
            v=recs.get("v"),
            stuck=recs["stuck"],
            amplitude=recs["amplitude"],
            energies=recs["energies"],
            dissipated=recs["dissipated"],
            buckled=buckled,
            t_buckle=t_b,
            t_stop=jnp.where(done, t, ts[-1]),
            q_final=q,
            v_final=v,
            result=result,
            n_steps=steps,
        )
