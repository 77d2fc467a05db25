"""The single-run driver: one `eqx.filter_jit` around any model and integrator."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._results import RESULTS
from .integrators.base import AbstractFixedStep, AbstractIntegrator, RunOptions, as_state
from .models.base import AbstractModel
from .solution import Solution

__all__ = ["simulate"]


def _is_concrete(tree) -> bool:
    return not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(tree))


def simulate(
    model: AbstractModel,
    integrator: AbstractIntegrator,
    q0,
    v0,
    t1: float,
    *,
    n_save: int = 101,
    options: RunOptions | None = None,
    throw: bool = True,
) -> Solution:
    """Integrate `model` from (`q0`, `v0`) at t = 0 to `t1` with `integrator`.

    **Arguments:**

    - `model`: any [`jaxrod.AbstractModel`][] (e.g. [`jaxrod.SingleMode`][]).
    - `integrator`: any [`jaxrod.AbstractIntegrator`][] (e.g. [`jaxrod.ProjectedVerlet`][]).
    - `q0`, `v0`: initial coordinates and velocities (rad, rad/s for modal amplitudes).
    - `t1`: final time [s], > 0 (static).
    - `n_save`: number of equally spaced save times including 0 and `t1` (static, ≥ 2).
    - `options`: a [`jaxrod.RunOptions`][]: buckling threshold, stopping when stuck, early
      exit from the time loop, whether to keep the full state (default `RunOptions()`).
    - `throw`: raise on a non-successful result (set `False` under `vmap`, where each
      member's `result` code says what happened).

    **Returns:** a [`jaxrod.Solution`][].

    **Raises:** `ValueError` for a bad `t1` or `n_save`, or — when the model's parameters are
    concrete — a fixed step above the integrator's stability limit; with `throw=True`, an
    `EquinoxRuntimeError` for any non-successful result.
    """
    if not (isinstance(t1, (int, float)) and np.isfinite(t1) and t1 > 0):
        raise ValueError(f"t1 = {t1!r} is invalid: expected a finite float > 0 [s].")
    if not (isinstance(n_save, int) and n_save >= 2):
        raise ValueError(f"n_save = {n_save!r} is invalid: expected an int >= 2.")
    # checked when the limit is concrete: the model's and the scheme's parameters (its friction
    # law's smoothing, say) known at trace time, whatever dt is
    checked = (isinstance(integrator, AbstractFixedStep) and _is_concrete(model)
               and _is_concrete(dataclasses.replace(integrator, dt=1.0)))
    if checked:
        # eagerly: the limit is 2/ω_max of the model, in closed form for every model (the 3D
        # rod's: `jaxrod.rod3d.stiffness.frequency_bound`, in NumPy). Inside a caller's jit it is
        # staged: then computed at trace time (a context in which JAX compiles a jitted function
        # anew, so only there)
        if isinstance(jnp.zeros(()) + 0.0, jax.core.Tracer):  # staged: inside a caller's jit
            with jax.ensure_compile_time_eval():
                limit = np.asarray(integrator.step_limit(model))
        else:
            limit = np.asarray(integrator.step_limit(model))
        if np.any(integrator.dt >= limit):
            raise ValueError(
                f"{type(integrator).__name__}.dt = {integrator.dt!r} s is above the stability "
                f"limit 2/ω_max = {float(np.min(limit)):.4g} s for this model; use a smaller dt."
            )
    # Initial values become arrays so that new values never trigger a recompilation.
    q0, v0 = as_state(q0), as_state(v0)
    options = RunOptions() if options is None else options
    if options.progress and isinstance(integrator, AbstractFixedStep) and _is_concrete((model, integrator, q0, v0)):
        return _simulate_in_blocks(model, integrator, q0, v0, float(t1), n_save, options, throw, checked)
    return _simulate(model, integrator, q0, v0, float(t1), n_save, options, throw, checked)


def _finalize(model, sol: Solution, throw: bool) -> Solution:
    result = jnp.where(model.check(), sol.result, RESULTS.invalid_input).astype(jnp.int32)
    sol = eqx.tree_at(lambda s: s.result, sol, result)
    if throw:
        msgs = [RESULTS.messages[i] for i in range(len(RESULTS.messages))]
        sol = eqx.branched_error_if(sol, result != RESULTS.successful, result, msgs)
    return sol


@eqx.filter_jit
def _simulate(model, integrator, q0, v0, t1, n_save, options, throw, checked):
    if checked:  # the step limit was checked on the concrete model: not again inside the run
        sol = integrator.integrate(model, q0, v0, t1, n_save, options, check_step_limit=False)
    else:
        sol = integrator.integrate(model, q0, v0, t1, n_save, options)
    return _finalize(model, sol, throw)


BLOCKS = 20
"""A run with a progress bar reports after each of about this many blocks of save intervals."""


def _block_size(intervals: int) -> int:
    """Save intervals per block: a divisor of `intervals` near intervals/`BLOCKS` (the smallest
    divisor at least that, unless it is more than 4× that: then the largest divisor below)."""
    target = max(1, -(-intervals // BLOCKS))
    up = next(b for b in range(target, intervals + 1) if intervals % b == 0)
    if up <= 4 * target:
        return up
    return next(b for b in range(target, 0, -1) if intervals % b == 0)


@eqx.filter_jit
def _start(model, integrator, q0, v0, t1, n_save, options):
    s0 = integrator.start(model, q0, v0, options)
    return s0, integrator.record(model, s0, s0.v, options)


@eqx.filter_jit
def _saves(model, integrator, s, first, count, t1, n_save, options, checked):
    """A block of save intervals, and what the solution needs of the state after it (the
    velocity at the positions and the result code: the last block's are the run's)."""
    s, recs, v_final = integrator.run_saves(model, s, first, count, t1, n_save, options)
    h = integrator.save_step(t1, n_save)
    code = integrator.result(model, s, h, check_step_limit=not checked)
    code = jnp.where(model.check(), code, RESULTS.invalid_input).astype(jnp.int32)
    return s, recs, v_final, code


def _simulate_in_blocks(model, integrator, q0, v0, t1, n_save, options, throw, checked):
    """`_simulate` with a progress bar: the save intervals run in blocks of one compiled program
    (`AbstractFixedStep.run_saves`), the bar advancing on the host between blocks, and the
    solution is put together on the host. The run is the same, step for step; no compiled
    program calls back to Python, so every one is written to the persistent compilation cache
    (jaxrod/_cache.py)."""
    from .integrators import progress

    quiet = dataclasses.replace(options, progress=False)
    size = next((f" ({getattr(model, k)} {k[2:]})" for k in ("n_segments", "n_nodes", "n_modes") if hasattr(model, k)), "")
    progress.compiling(f"{type(model).__name__}{size} with {type(integrator).__name__}",
                       (type(model), type(integrator), size, n_save, jax.tree_util.tree_structure(q0)))
    s0, rec0 = _start(model, integrator, q0, v0, t1, n_save, quiet)
    total = n_save - 1
    size = _block_size(total)
    s, blocks = s0, [jax.tree_util.tree_map(lambda x: x[None], rec0)]
    for first in range(0, total, size):
        s, recs, v_final, code = _saves(model, integrator, s, jnp.asarray(first, jnp.int32), size, t1, n_save,
                                        quiet, checked)
        blocks.append(recs)
        progress.tick(first + size, total, bool(s.stopped))
    recs = jax.tree_util.tree_map(lambda *xs: np.concatenate([np.asarray(x) for x in xs]), *blocks)
    if throw and int(code) != RESULTS.successful:
        raise eqx.EquinoxRuntimeError(RESULTS.messages[int(code)])
    return s.solution(recs, t1, n_save, v_final, code)
