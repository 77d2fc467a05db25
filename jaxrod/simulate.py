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
        with jax.ensure_compile_time_eval():  # concrete even inside a caller's jit
            # the limit does not depend on dt: one compilation for every dt of a scheme
            limit = np.asarray(_step_limit(dataclasses.replace(integrator, dt=1.0), model))
        if np.any(integrator.dt >= limit):
            raise ValueError(
                f"{type(integrator).__name__}.dt = {integrator.dt!r} s is above the stability "
                f"limit 2/ω_max = {float(np.min(limit)):.4g} s for this model; use a smaller dt."
            )
    # Initial values become arrays so that new values never trigger a recompilation.
    q0, v0 = as_state(q0), as_state(v0)
    options = RunOptions() if options is None else options
    return _simulate(model, integrator, q0, v0, float(t1), n_save, options, throw, checked)


@eqx.filter_jit
def _step_limit(integrator, model):
    return integrator.step_limit(model)


@eqx.filter_jit
def _simulate(model, integrator, q0, v0, t1, n_save, options, throw, checked):
    if checked:  # the step limit was checked on the concrete model: not again inside the run
        sol = integrator.integrate(model, q0, v0, t1, n_save, options, check_step_limit=False)
    else:
        sol = integrator.integrate(model, q0, v0, t1, n_save, options)
    result = jnp.where(model.check(), sol.result, RESULTS.invalid_input).astype(jnp.int32)
    sol = eqx.tree_at(lambda s: s.result, sol, result)
    if throw:
        msgs = [RESULTS.messages[i] for i in range(len(RESULTS.messages))]
        sol = eqx.branched_error_if(sol, result != RESULTS.successful, result, msgs)
    return sol
