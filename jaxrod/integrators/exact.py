"""The exact piecewise solution of the single-mode model, as an integrator."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ..models.single_mode import SingleMode, exact_solution
from .base import AbstractIntegrator, RunOptions, summarize

__all__ = ["Exact"]


class Exact(AbstractIntegrator):
    """The closed-form phase-by-phase solution of [`jaxrod.SingleMode`][] (docs/physics.md §4):
    the ground truth for every accuracy test. Exact up to rounding; only for `SingleMode`.

    **Arguments:** `max_phases` (static): cap on slip phases per save time.
    """

    max_phases: int = eqx.field(static=True, default=100_000)

    def integrate(self, model, q0, v0, t1, n_save, options=RunOptions()):
        if not isinstance(model, SingleMode):
            raise TypeError(
                f"Exact integrates only SingleMode models, got {type(model).__name__}."
            )
        ts = jnp.linspace(0.0, t1, n_save, dtype=jnp.result_type(float))
        fn = lambda t: exact_solution(
            q0, v0, model.k, model.f_s, model.f_d, t, self.max_phases
        )
        A, v, stuck, n, result = jax.vmap(fn)(ts)
        # the energy lost is exactly what friction dissipated
        e = jax.vmap(model.energy_terms)(A, v, ts)
        total = e["kinetic"] + e["potential"]
        sol = summarize(model, ts, A, v, total[0] - total, options, jnp.max(n))
        return eqx.tree_at(lambda s: s.result, sol, jnp.maximum(sol.result, jnp.max(result)))
