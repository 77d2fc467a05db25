"""The implicit leapfrog with its step chosen by a local error estimate: rejected steps, user
tolerances, save times hit exactly, every lane of a batch at its own step."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._results import RESULTS
from .base import RunOptions, RunState, save_grid
from .implicit import ImplicitLeapfrog

__all__ = ["AdaptiveImplicitLeapfrog", "StepControl"]

SAFETY, FACTOR_MIN, FACTOR_MAX = 0.9, 0.2, 2.0
"""The controller's safety factor and the bounds of the step's change per attempt."""


class StepControl(eqx.Module):
    """Where the step controller of one run stands: `h_next` (the step it tries next) and
    `h_prev` (the last accepted) [s], `rejected` (attempts rejected), `forced` (steps accepted at
    `dt_min` with the estimate above tolerance), `h_min`, `h_max` (smallest and largest accepted
    step [s]), `rejected_last` (whether the last attempt was rejected: the next may not grow)."""

    h_next: Array
    h_prev: Array
    rejected: Array
    forced: Array
    h_min: Array
    h_max: Array
    rejected_last: Array

    def stats(self) -> dict:
        return dict(rejected=self.rejected, forced=self.forced, h_min=self.h_min, h_max=self.h_max)


class AdaptiveImplicitLeapfrog(ImplicitLeapfrog):
    """[`jaxrod.ImplicitLeapfrog`][] at a variable step chosen by the model's local error estimate
    (`model.step_error`, [`jaxrod.rod3d.Rod3D`][]: Zienkiewicz–Xie's (β − 1/6) h² Δa on the node
    translations, `jaxrod.rod3d.step_error`), as diffrax's `PIDController` with only its
    integral term: a step is accepted when the estimate, scaled by `atol + rtol·|Δx|`, is at most
    1; the next step is h·clip(0.9 err^(−1/3), 0.2, 2) (the local error is third order in h; no
    growth right after a rejection), at most `dt` and at least `dt_min`; a rejected step is retried from the same state. Within two
    steps of a save time the run takes two equal steps to land on it, and a step cut short by a
    save does not shrink the next one. A step at `dt_min` is accepted whatever its estimate, counted in `forced`, and
    the run then ends with the result code `tolerance`.

    The variable-step leapfrog kicks by the mean of the two steps around a position,
    v_{n+½} = v_{n−½} + ½(h_{n−1} + hₙ) aₙ, and drifts by hₙ: the kick and friction pass of
    [`jaxrod.ImplicitLeapfrog`][] with that length (its matrix with the step hₙ). Under `vmap`
    every lane keeps its own step, and the sweeps' pool advances each lane one attempt at a time.
    [`jaxrod.Solution`][]`.step_stats` gives the rejected and forced counts and the smallest and
    largest accepted step.

    **Arguments**, besides those of [`jaxrod.ImplicitLeapfrog`][] (the tolerances and steps
    below are array leaves: one compiled program serves any value, and a batch may vary them):

    - `dt`: the largest step [s] (static).
    - `gamma`: the numerical damping (static, default 0: the controller, not damping, deals with
      the stiff modes; the fixed step's γ damps the segment-scale modes a random perturbation
      releases at any step it is run at, which moves E4's answer: docs/rod3d.md, "Adaptive
      steps").
    - `rtol`: the tolerance relative to a node's displacement in the step (default 1e-2).
    - `atol`: the absolute tolerance on a node's position [m] (default 1e-9).
    - `dt_min`: the smallest step [s] (default `dt`/1000).
    - `dt0`: the first step tried [s] (default `dt`/100).
    """

    gamma: float = eqx.field(static=True, default=0.0)
    rtol: float | Array = 1e-2
    atol: float | Array = 1e-9
    dt_min: float | Array | None = None
    dt0: float | Array | None = None

    def __check_init__(self):
        def concrete(x):  # a value given (a float, or an array that is not traced)
            return not isinstance(x, jax.core.Tracer) and x is not None

        for name in ("rtol", "atol"):
            value = getattr(self, name)
            if concrete(value) and not np.all((np.asarray(value) >= 0.0) & np.isfinite(np.asarray(value))):
                raise ValueError(f"AdaptiveImplicitLeapfrog.{name} = {value!r} is invalid: expected a finite float >= 0.")
        for name in ("dt_min", "dt0"):
            value = getattr(self, name)
            if concrete(value) and not np.all((np.asarray(value) > 0.0) & (np.asarray(value) <= self.dt)):
                raise ValueError(f"AdaptiveImplicitLeapfrog.{name} = {value!r} is invalid: expected a float in "
                                 f"(0, dt = {self.dt!r}].")

    def _bounds(self):
        """`(dt_min, dt0)` [s], with their defaults."""
        dt_min = self.dt / 1000 if self.dt_min is None else self.dt_min
        return dt_min, jnp.maximum(dt_min, self.dt / 100 if self.dt0 is None else self.dt0)

    def start(self, model, q0, v0, options: RunOptions) -> RunState:
        s = super().start(model, q0, v0, options)
        dtype = s.t.dtype
        dt_min, dt0 = self._bounds()
        zero = jnp.zeros((), jnp.int32)
        control = StepControl(jnp.asarray(dt0, dtype), jnp.asarray(dt0, dtype), zero, zero,
                              jnp.asarray(jnp.inf, dtype), jnp.zeros((), dtype), jnp.array(False))
        return dataclasses.replace(s, control=control)

    def advance(self, model, s: RunState, h, m: int, n_save: int, options: RunOptions) -> RunState:
        """One attempt (the interface of the fixed-step engine, `h`·`m` the save interval): a step
        from `s` at the controller's step, cut to the next save time; accepted, the state after it
        (a save where it lands on the save time), else `s` with a smaller next step."""
        return self._attempt(model, s, h, m, n_save, options, jnp.array(False))[0]

    def _attempt(self, model, s: RunState, h, m: int, n_save: int, options: RunOptions, at_position):
        """`advance`, or where `at_position` (traced) the velocity pass at the position instead
        (the half kick and friction pass of the last step, as `velocity_at`; the state unchanged):
        one copy of the step to compile. **Returns:** the state and the velocity at the position."""
        c = s.control
        frozen = s.finished(n_save) | at_position
        dt_min, _ = self._bounds()
        t_save = (s.saves + 1).astype(s.t.dtype) * (m * h)
        left = t_save - s.t
        lands = left <= c.h_next * (1 + 1e-12)  # the step is cut to (or ends at) the save time
        # within two steps of the save: two equal steps, not a long one and a short one
        h_try = jnp.where(lands, left, jnp.where(left < 2 * c.h_next, 0.5 * left, c.h_next))
        h_try = jnp.where(frozen, 0.0, h_try)
        hk = jnp.where(frozen, 0.0, jnp.where(s.t > 0, 0.5 * (c.h_prev + h_try), 0.5 * h_try))
        # the leapfrog's step with this kick; at the position, its velocity pass with the last step
        q, v_new, a, (lost, work), v_at = self.step(model, s.q, s.v, s.a, s.t, h_try, h_save=c.h_prev,
                                                    at_position=at_position, hk=hk)
        err = model.step_error(s.q, q, s.a, a, h_try, self.beta, self.rtol, self.atol)
        err = jnp.where(jnp.isfinite(err), err, jnp.inf)
        at_min = h_try <= dt_min * (1 + 1e-9)
        accept = ~at_position & (frozen | (err <= 1.0) | at_min)
        moved = accept & ~frozen
        forced = moved & at_min & (err > 1.0)
        # no growth right after a rejection (Hairer, Nørsett & Wanner, II.4)
        grow = jnp.where(accept, jnp.where(c.rejected_last, 1.0, FACTOR_MAX), 0.9)
        factor = jnp.clip(SAFETY * jnp.where(err > 0, err, 1e-30) ** (-1.0 / 3.0), FACTOR_MIN, grow)
        h_prop = jnp.clip(h_try * factor, dt_min, self.dt)
        # a step cut short by a save does not shrink the next one
        cut = h_try < c.h_next * (1 - 1e-12)
        h_next = jnp.where(frozen, c.h_next, jnp.where(accept & cut, jnp.maximum(h_prop, c.h_next), h_prop))
        t = jnp.where(frozen, s.t, jnp.where(lands, t_save, s.t + h_try))  # a stopped run keeps its time
        done = dataclasses.replace(self._book(model, s, q, v_new, a, lost, work, t, s.k + 1, lands, frozen, options),
                                   control=None)
        tried = ~frozen
        control = StepControl(
            h_next=h_next, h_prev=jnp.where(moved, h_try, c.h_prev),
            rejected=c.rejected + (tried & ~accept).astype(c.rejected.dtype),
            forced=c.forced + forced.astype(c.forced.dtype),
            h_min=jnp.where(moved, jnp.minimum(c.h_min, h_try), c.h_min),
            h_max=jnp.where(moved, jnp.maximum(c.h_max, h_try), c.h_max),
            rejected_last=jnp.where(tried, ~accept, c.rejected_last))
        new = jax.tree_util.tree_map(lambda a_, b_: jnp.where(accept, a_, b_), done, dataclasses.replace(s, control=None))
        return dataclasses.replace(new, control=control), v_at

    def run_saves(self, model, s: RunState, first, count: int, t1, n_save: int, options: RunOptions):
        """`count` save intervals from the state `s` (as the fixed-step engine's): attempts until
        each save time is reached (or the run stops), then one pass more, the velocity pass at the
        saved position, through the same attempt."""
        m, h = save_grid(t1, n_save, self.dt)
        h = jnp.asarray(h, s.t.dtype)

        def interval(carry, _):
            s = carry[0]
            target = s.saves + 1

            def body(c):
                s, v_at, _ = c
                at_position = (s.saves >= target) | s.stopped
                s, v_new = self._attempt(model, s, h, m, n_save, options, at_position)
                return s, jax.tree_util.tree_map(lambda a, b: jnp.where(at_position, a, b), v_new, v_at), at_position

            s, v_at, _ = jax.lax.while_loop(lambda c: ~c[2], body, (s, s.v, jnp.array(False)))
            return (s, v_at), self.record(model, s, v_at, options)

        (s, v_at), recs = jax.lax.scan(interval, (s, s.v), None, length=count)
        return s, recs, v_at

    def result(self, model, s: RunState, h, check_step_limit: bool = True):
        """The base code, or `RESULTS.tolerance` where a step was forced at `dt_min`."""
        code = super().result(model, s, h, check_step_limit)
        return jnp.where((code == RESULTS.successful) & (s.control.forced > 0), RESULTS.tolerance, code).astype(code.dtype)
