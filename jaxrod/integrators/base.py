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

__all__ = ["AbstractIntegrator", "AbstractFixedStep"]


class AbstractIntegrator(eqx.Module):
    """Integrates a model from (q₀, v₀) at t = 0 to `t1`, saving `n_save` equally spaced
    states (t = 0 and t = `t1` included)."""

    @abc.abstractmethod
    def integrate(self, model: AbstractModel, q0, v0, t1: float, n_save: int) -> Solution:
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


class AbstractFixedStep(AbstractIntegrator):
    """A fixed-step one-step scheme. Subclasses define `dt` and `step`."""

    dt: eqx.AbstractVar[float]

    @abc.abstractmethod
    def step(self, model: AbstractModel, q, v, t, h):
        """One step of size `h` from (q, v) at time t; returns (q, v) at t + h."""

    def step_limit(self, model):
        om = model.max_frequency()
        return jnp.where(om > 0, 2.0 / jnp.where(om > 0, om, 1.0), jnp.inf)

    def integrate(self, model, q0, v0, t1, n_save):
        m, h = save_grid(t1, n_save, self.dt)
        q0 = jnp.asarray(q0, dtype=jnp.result_type(float))
        v0 = jnp.asarray(v0, dtype=jnp.result_type(float))

        def one(carry, _):
            q, v, t = carry
            q, v = self.step(model, q, v, t, h)
            return (q, v, t + h), None

        def save(carry, _):
            carry, _ = jax.lax.scan(one, carry, None, length=m)
            q, v, t = carry
            return carry, (q, v, model.is_stuck(q, v, t))

        t0 = jnp.zeros((), dtype=q0.dtype)
        _, (qs, vs, stuck) = jax.lax.scan(save, (q0, v0, t0), None, length=n_save - 1)
        qs = jnp.concatenate([q0[None], qs])
        vs = jnp.concatenate([v0[None], vs])
        stuck = jnp.concatenate([model.is_stuck(q0, v0, t0)[None], stuck])
        ts = jnp.linspace(0.0, t1, n_save, dtype=q0.dtype)
        finite = jnp.isfinite(qs).all() & jnp.isfinite(vs).all()
        too_big = h >= self.step_limit(model)
        result = jnp.where(
            too_big,
            RESULTS.step_limit,
            jnp.where(finite, RESULTS.successful, RESULTS.nonfinite),
        ).astype(jnp.int32)
        n_steps = jnp.array(m * (n_save - 1), dtype=jnp.int32)
        return Solution(ts=ts, q=qs, v=vs, stuck=stuck, result=result, n_steps=n_steps)
