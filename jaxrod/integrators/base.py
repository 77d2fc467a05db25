"""The interface every integrator implements, and the fixed-step machinery they share."""

from __future__ import annotations

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._results import RESULTS
from ..models.base import AbstractModel, friction_work  # noqa: F401 (integrators import it here)
from ..solution import Solution
from . import progress

__all__ = ["AbstractIntegrator", "AbstractFixedStep", "RunOptions", "RunState"]


class RunOptions(eqx.Module):
    """How a run stops and what it keeps (all static).

    - `buckle_threshold`: amplitude [rad] past which the run counts as buckled (`None`: the
      model's default, 0.5 rad for the rod models, `inf` for one mode).
    - `stop_on_buckle`: freeze the state once it has buckled (otherwise the run goes on, and
      `buckled`, `t_buckle` record the first crossing).
    - `stop_when_stuck`: freeze the state once the whole system is stuck under a constant load
      (exact for the sharp law: nothing can release it).
    - `early_exit`: stop stepping as soon as the run (every member of a batch) has stopped:
      the rest of its save interval is left at once and each later save costs one record
      instead of its steps. Uses a `while_loop`, which forward-mode AD supports but reverse mode
      does not: set `False` for `jax.grad`.
    - `save_state`: keep q and v at every save time (otherwise only the summaries).
    - `progress`: show a progress bar over the save intervals of a single run (tqdm, through a
      host callback; leave it off under `vmap`).
    """

    buckle_threshold: float | None = eqx.field(static=True, default=None)
    stop_on_buckle: bool = eqx.field(static=True, default=True)
    stop_when_stuck: bool = eqx.field(static=True, default=True)
    early_exit: bool = eqx.field(static=True, default=True)
    save_state: bool = eqx.field(static=True, default=True)
    progress: bool = eqx.field(static=True, default=False)

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
    accs = jax.vmap(model.accelerations)(qs, vs, ts)
    stuck = jax.vmap(model.is_stuck)(qs, vs, accs, ts)
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
        work_in=jnp.zeros_like(dissipated),
        observables={},
        buckled=buckled,
        t_buckle=t_buckle,
        t_stop=jnp.where(buckled, t_buckle, ts[-1]),
        q_final=qs[-1],
        v_final=vs[-1],
        result=result,
        n_steps=jnp.asarray(n_steps, dtype=jnp.int32),
    )


class RunState(eqx.Module):
    """Where one fixed-step run stands: the state and its stop bookkeeping.

    The same state is advanced by [`jaxrod.simulate`][] (one run, with saves) and by the
    continuous-batching pool of the sweeps (many runs in lanes), one step at a time, so a sweep
    member takes exactly the steps of its single run.

    **Fields:** `q`, `v` (the model's coordinates and velocities, arrays or pytrees), `a`
    (`model.accelerations` at (q, v, t)), `t` [s], `dissipated` (energy removed by friction and
    damping, per degree of freedom: the sum of its leaves is the total), `work_in` (work done by
    driven boundaries [J]), `buckled`, `t_buckle` [s] (`inf` if not), `stuck` (at the last save),
    `stopped` (buckled, stuck under a constant load, or non-finite: frozen before the horizon),
    `steps` (taken), `k` (steps since the last save), `saves` (save intervals completed),
    `amp_max` (largest amplitude seen at a save or at the stop), `control` (an error-controlled
    scheme's `jaxrod.integrators.adaptive.StepControl`; `None` for a fixed step).
    """

    q: Array
    v: Array
    a: Array
    t: Array
    dissipated: Array
    work_in: Array
    buckled: Array
    t_buckle: Array
    stuck: Array
    stopped: Array
    steps: Array
    k: Array
    saves: Array
    amp_max: Array
    control: Array | None = None

    def finished(self, n_save: int):
        """Whether the run is over: stopped, or all `n_save − 1` save intervals done."""
        return self.stopped | (self.saves >= n_save - 1)

    def solution(self, recs: dict, t1: float, n_save: int, v_final, result) -> Solution:
        """The [`jaxrod.Solution`][] of the run that ended in this state, from the records of
        its `n_save` saves (stacked), its velocity at the positions and its result code."""
        return Solution(
            ts=jnp.linspace(0.0, t1, n_save, dtype=self.t.dtype), q=recs.get("q"), v=recs.get("v"),
            stuck=recs["stuck"], amplitude=recs["amplitude"], energies=recs["energies"],
            dissipated=recs["dissipated"], work_in=recs["work_in"], observables=recs["observables"],
            buckled=self.buckled, t_buckle=self.t_buckle, t_stop=self.stop_time(t1, n_save), q_final=self.q,
            v_final=v_final, result=result, n_steps=self.steps,
            step_stats=None if self.control is None else self.control.stats(),
        )

    def stop_time(self, t1: float, n_save: int):
        """When the run stopped [s]: `t` if it stopped early, else the horizon `t1`."""
        return jnp.where(self.stopped, self.t, jnp.linspace(0.0, t1, n_save, dtype=self.t.dtype)[-1])


class AbstractFixedStep(AbstractIntegrator):
    """A fixed-step one-step scheme. Subclasses define `dt` and `step`.

    The time loop checks the buckling threshold and the stick test after every step (so
    `t_buckle` and the time a run sticks are resolved to one step); a stopped run is frozen, and with
    `early_exit` it takes no more steps once the run (every member of a vmapped batch) has
    stopped.
    The loop is written once, as `start` and `advance` on a [`RunState`][]: `integrate` runs
    it with saves, the sweeps run it in lanes with continuous batching.
    """

    dt: eqx.AbstractVar[float]

    velocity_in_step = False
    """Whether `step(..., h_save=, at_position=)` also computes `velocity_at` (a scheme that
    carries a velocity other than the one at its positions): the run then ends each save
    interval with one more pass through the step, the velocity pass, instead of compiling a
    second copy of what `step` computes ([`jaxrod.ProjectedLeapfrog`][])."""

    def held_is_fixed(self, model: AbstractModel) -> bool:
        """Whether a state of `model` that passes the stick test is a fixed point of `step`
        (then a run is frozen at the step it sticks; otherwise at the next save)."""
        return False

    @abc.abstractmethod
    def step(self, model: AbstractModel, q, v, a, t, h):
        """One step of size `h` from (q, v) at time t, with `a` = `model.accelerations` at
        (q, t) (reused across steps). Returns `(q, v, a, (lost, work_in))` at t + h: the energy
        friction (and damping) removed during the step per degree of freedom (the structure of
        `v`; see `friction_work`) and the work done by driven boundaries [J]."""

    def velocity_at(self, model: AbstractModel, q, v, a, t, h):
        """The velocity at the position `q` (time `t`) given the velocity `v` the run carries
        (what a save records): `v` itself for a scheme that carries the velocity at its
        positions; [`jaxrod.ProjectedLeapfrog`][] carries the half step's."""
        return v

    def step_limit(self, model):
        om = model.max_frequency()
        return jnp.where(om > 0, 2.0 / jnp.where(om > 0, om, 1.0), jnp.inf)

    @classmethod
    def default_step(cls, model, q=None) -> float:
        """The step [s] this scheme runs `model` at by default: half its stability limit 2/ω_max
        at `q` (the 3D rod's experiments' choice; the reduced models' scenes choose their own)."""
        return float(1.0 / model.max_frequency(q))

    def start(self, model: AbstractModel, q0, v0, options: RunOptions) -> RunState:
        """The [`RunState`][] at t = 0 (stuck at once if the initial state is held). A
        non-finite initial state starts as NaN everywhere, so that the run ends `nonfinite`
        (the friction pass would otherwise set a NaN velocity to zero and hold a finite rod)."""
        dtype = jnp.result_type(float)
        q0, v0 = as_state(q0), as_state(v0)
        finite = _all_finite((q0, v0))
        q0, v0 = jax.tree_util.tree_map(
            lambda x: x if x.dtype == bool else jnp.where(finite, x, jnp.nan), (q0, v0))
        t = jnp.zeros((), dtype)
        a = model.accelerations(q0, v0, t)
        stuck = model.is_stuck(q0, v0, a, t)
        lost = jax.eval_shape(lambda: model.impulse_work(v0, v0, v0, a, t)[0])
        return RunState(
            q=q0, v=v0, a=a, t=t, dissipated=jax.tree_util.tree_map(lambda x: jnp.zeros(x.shape, x.dtype), lost),
            work_in=jnp.zeros((), dtype), buckled=jnp.array(False), t_buckle=jnp.asarray(jnp.inf, dtype), stuck=stuck,
            stopped=stuck & _freezes_stuck(model, options),
            steps=jnp.array(0, jnp.int32), k=jnp.array(0, jnp.int32),
            saves=jnp.array(0, jnp.int32), amp_max=model.amplitude(q0),
        )

    def advance(self, model: AbstractModel, s: RunState, h, m: int, n_save: int, options: RunOptions) -> RunState:
        """One step of `h` [s] with the stop rules, after every step: buckling (amplitude past
        the threshold), a non-finite amplitude, and the stick test (which freezes the run under
        a constant load); at every `m`-th step a save. A finished run is left as it is:
        it takes a step of zero length (an exact identity of the scheme, and much cheaper than
        selecting between old and new arrays), and its bookkeeping is kept."""
        return self._advance(model, s, h, m, n_save, options)[0]

    def _advance(self, model, s: RunState, h, m: int, n_save: int, options: RunOptions, at_position=None):
        """`advance`, and for a scheme whose `step` computes `velocity_at` (`velocity_in_step`),
        where `at_position` is true the velocity pass instead of a step: the state and its
        bookkeeping are left as they are. **Returns:** the state and the velocity at the position
        (`None` without `at_position`)."""
        frozen = s.finished(n_save)
        h_run = jnp.where(frozen, jnp.zeros_like(h), h)
        v_at = None
        if at_position is None:
            q, v, a, (lost, work) = self.step(model, s.q, s.v, s.a, s.t, h_run)
        else:
            frozen = frozen | at_position
            h_run = jnp.where(at_position, jnp.zeros_like(h), h_run)
            q, v, a, (lost, work), v_at = self.step(model, s.q, s.v, s.a, s.t, h_run, h_save=h,
                                                    at_position=at_position)
        return self._book(model, s, q, v, a, lost, work, s.t + h_run, s.k + 1, s.k + 1 == m, frozen, options), v_at

    def _book(self, model, s: RunState, q, v, a, lost, work, t, k, at_save, frozen, options: RunOptions) -> RunState:
        """The run state after a step to (q, v, a) at `t` that removed `lost` and took in `work`: the
        stop rules and the save count (`at_save`: it ends a save interval; `k`: steps since the
        last save); a `frozen` run keeps its bookkeeping."""
        amp, held = model.stop_measures(q, v, a, t)
        over = amp > options.threshold(model)
        first = over & ~s.buckled
        blown = (over & options.stop_on_buckle) | ~jnp.isfinite(amp)
        # a held state under a constant load never moves again (for a scheme of which it is a
        # fixed point): freeze it at the step it is reached (`held` comes from the same
        # reduction as the amplitude, so the test costs nothing)
        freeze = held & ~over & _freezes_stuck(model, options) & (at_save | self.held_is_fixed(model))
        stuck = jnp.where(at_save | freeze, held & ~over, s.stuck & ~blown & ~over)
        stopped = blown | freeze
        keep = lambda old, new: jnp.where(frozen, old, new)
        return RunState(
            q=q, v=v, a=a, t=t, dissipated=jax.tree_util.tree_map(jnp.add, s.dissipated, lost),
            work_in=s.work_in + work,
            buckled=keep(s.buckled, s.buckled | over), t_buckle=keep(s.t_buckle, jnp.where(first, t, s.t_buckle)),
            stuck=keep(s.stuck, stuck), stopped=keep(s.stopped, stopped),
            steps=keep(s.steps, s.steps + 1), k=keep(s.k, jnp.where(at_save, 0, k)),
            saves=keep(s.saves, s.saves + at_save.astype(s.saves.dtype)),
            amp_max=keep(s.amp_max, jnp.where(at_save | stopped, jnp.maximum(s.amp_max, amp), s.amp_max)),
            control=s.control,
        )

    def integrate(self, model, q0, v0, t1, n_save, options=RunOptions(), check_step_limit=True):
        s0 = self.start(model, q0, v0, options)
        s, recs, v_final = self.run_saves(model, s0, 0, n_save - 1, t1, n_save, options)
        return self.solution(model, s0, s, recs, v_final, t1, n_save, options, check_step_limit)

    def save_step(self, t1, n_save):
        """The step a run to `t1` with `n_save` saves takes [s] (`save_grid`), as an array."""
        return jnp.asarray(save_grid(t1, n_save, self.dt)[1], jnp.result_type(float))

    def record(self, model, s: RunState, v_at, options: RunOptions) -> dict:
        """What a save records of the run state `s`, with `v_at` the velocity at its positions
        (`velocity_at`: the run's own for a scheme that carries it; at t = 0 `s.v` for every
        scheme)."""
        s = eqx.tree_at(lambda r: r.v, s, v_at)
        rec = {
            "stuck": s.stuck,
            "dissipated": sum(jnp.sum(x) for x in jax.tree_util.tree_leaves(s.dissipated)),
            "work_in": s.work_in,
            "amplitude": model.amplitude(s.q),
            "energies": model.energy_terms(s.q, s.v, s.t),
            "observables": model.observables(s.q, s.v, s.a, s.t),
        }
        if options.save_state:
            rec["q"], rec["v"] = s.q, s.v
        return rec

    def run_saves(self, model, s: RunState, first, count: int, t1, n_save: int, options: RunOptions):
        """`count` save intervals (static) of a run to `t1` with `n_save` saves, from the state
        `s` after save interval `first` (an index, may be traced): the state after them, their
        records, stacked, and the velocity at the last one's positions (`velocity_at`, computed
        once for the record and the solution: for the 3D rod a friction pass, thousands of
        operations to compile). `integrate` runs all n_save − 1 at once; [`jaxrod.simulate`][] with a
        progress bar runs them in blocks, reporting between blocks from the host (a compiled
        program that calls back to Python is never written to the compilation cache)."""
        m, _ = save_grid(t1, n_save, self.dt)
        h = self.save_step(t1, n_save)

        def interval(s):
            if self.velocity_in_step:
                return interval_with_velocity_pass(s)
            step = lambda s: self.advance(model, s, h, m, n_save, options)
            if options.early_exit:  # a stopped run leaves its interval at once, and skips the later ones
                _, s = jax.lax.while_loop(
                    lambda c: (c[0] < m) & ~c[1].stopped, lambda c: (c[0] + 1, step(c[1])), (0, s)
                )
            else:
                s = jax.lax.fori_loop(0, m, lambda _, s: step(s), s)
            v_at = self.velocity_at(model, s.q, s.v, s.a, s.t, h)
            return (s, v_at), self.record(model, s, v_at, options)

        def interval_with_velocity_pass(s):
            # m steps, then one pass more through the step: the velocity pass (`velocity_in_step`)
            def body(i, c):
                return self._advance(model, c[0], h, m, n_save, options, at_position=i == m)

            if options.early_exit:  # a stopped run goes to the velocity pass at once
                def next_of(c):
                    i, c = c[0], body(c[0], c[1:])
                    return (jnp.where(i == m, m + 1, jnp.where(c[0].stopped, m, i + 1)),) + c

                _, s, v_at = jax.lax.while_loop(lambda c: c[0] <= m, next_of, (jnp.where(s.stopped, m, 0), s, s.v))
            else:
                s, v_at = jax.lax.fori_loop(0, m + 1, body, (s, s.v))
            return (s, v_at), self.record(model, s, v_at, options)

        # the saves in a loop of known length: XLA compiles a loop over an unknown count (a
        # `while` that ends when the run stops) into a slower step (3D rod, 500 segments: 173–176
        # against 161–163 µs per step, benchmarks/README.md). After a stop the remaining saves
        # cost one record each (the state no longer changes: they repeat the last record).
        def scan_body(carry, i):
            (s, v_at), rec = interval(carry[0])
            if options.progress:
                jax.debug.callback(progress.tick, i + 1, n_save - 1, s.stopped)
            return (s, v_at), rec

        first = jnp.asarray(first)
        (s, v_at), recs = jax.lax.scan(scan_body, (s, s.v), first + jnp.arange(count, dtype=first.dtype))
        return s, recs, v_at

    def solution(self, model, s0: RunState, s: RunState, recs: dict, v_final, t1, n_save: int,
                 options: RunOptions, check_step_limit: bool = True) -> Solution:
        """The [`jaxrod.Solution`][] of a run from `s0` that ended at `s` (velocity at its
        positions `v_final`) with the records `recs` of its n_save − 1 save intervals."""
        h = self.save_step(t1, n_save)
        recs = jax.tree_util.tree_map(lambda x0, xs: jnp.concatenate([x0[None], xs]),
                                      self.record(model, s0, s0.v, options), recs)
        return s.solution(recs, t1, n_save, v_final, self.result(model, s, h, check_step_limit))

    def result(self, model, s: RunState, h, check_step_limit: bool = True) -> Array:
        """The [`jaxrod.RESULTS`][] code of a finished run (`check_step_limit=False` when the
        step was already checked against the limit of the concrete model)."""
        finite = _all_finite((s.q, s.v))
        too_big = h >= self.step_limit(model) if check_step_limit else False
        return jnp.where(
            too_big,
            RESULTS.step_limit,
            jnp.where(finite, RESULTS.successful, RESULTS.nonfinite),
        ).astype(jnp.int32)


def as_state(tree):
    """A state (array or pytree) with every non-boolean leaf a float array of the default
    dtype, so that new initial values never trigger a recompilation."""
    dtype = jnp.result_type(float)

    def leaf(x):
        x = jnp.asarray(x)
        return x if x.dtype == bool else x.astype(dtype)

    return jax.tree_util.tree_map(leaf, tree)


def _all_finite(tree):
    leaves = [x for x in jax.tree_util.tree_leaves(tree) if jnp.issubdtype(x.dtype, jnp.inexact)]
    return jnp.all(jnp.stack([jnp.isfinite(x).all() for x in leaves]))


def _freezes_stuck(model, options) -> bool:
    """A stuck run is frozen only under a constant load (then nothing can release it)."""
    return options.stop_when_stuck and model.autonomous
