"""Symplectic Euler with an explicit friction force: the documented failure case."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from ..friction import AbstractFriction, Coulomb
from .base import AbstractFixedStep, friction_work

__all__ = ["SymplecticEuler", "SplitLinearFriction"]


class SymplecticEuler(AbstractFixedStep):
    """Symplectic Euler with friction evaluated explicitly from the old velocity:
    `v ← v + h(a(q) − friction(v))`, `q ← q + h v`.

    **This is a failure case, kept for comparison.** With the sharp sign law
    ([`jaxrod.Coulomb`][], whose explicit force is `f_d·sgn(v)`) the velocity never becomes
    exactly zero: where the true solution sticks, it chatters between ±h·f_d with a sign change
    nearly every step, and a loaded mode held by friction drifts. First order. Stable for
    `dt · ω_max < 2`. Use [`jaxrod.ProjectedVerlet`][] instead.

    **Arguments:** `dt` [s] (static); `friction` (default [`jaxrod.Coulomb`][]).
    """

    dt: float = eqx.field(static=True)
    friction: AbstractFriction = Coulomb()

    def __check_init__(self):
        if not (isinstance(self.dt, (int, float)) and self.dt > 0):
            raise ValueError(f"SymplecticEuler.dt = {self.dt!r} is invalid: expected a float > 0.")

    def step(self, model, q, v, a, t, h):
        v_cons = v + h * a
        v_new = v_cons - h * model.friction_acceleration(self.friction, v, t)
        lost = friction_work(model, v, v_cons, v_new)
        v = v_new
        q = q + h * v
        return q, v, model.acceleration(q, t + h), (lost, jnp.zeros_like(h))


class SplitLinearFriction(AbstractFixedStep):
    """Operator splitting: the exact flow of the linear elastic part over a step, then the
    exact Coulomb projection of the velocity.

    **This is a failure case, kept for comparison.** The elastic flow moves every point —
    including those that friction holds — before friction acts, and the projection zeroes
    only the velocity: a stuck point creeps by ≈ ½h²|a| per step. Under a load past the
    frictionless one (negative modal stiffness) the creep grows exponentially and turns rods
    that are stable (and that [`jaxrod.ProjectedVerlet`][] keeps exactly still) into buckled
    ones. Unconditionally stable for the linear part; needs the model's `linear_flow`.
    Use [`jaxrod.ProjectedVerlet`][] instead.

    **Arguments:** `dt` [s] (static); `friction` (default [`jaxrod.Coulomb`][]).
    """

    dt: float = eqx.field(static=True)
    friction: AbstractFriction = Coulomb()

    def __check_init__(self):
        if not (isinstance(self.dt, (int, float)) and self.dt > 0):
            raise ValueError(
                f"SplitLinearFriction.dt = {self.dt!r} is invalid: expected a float > 0."
            )

    def step_limit(self, model):
        return jnp.inf

    def step(self, model, q, v, a, t, h):
        q1, v_lin = model.linear_flow(q, v, t, h)
        v1 = model.friction_update(self.friction, v_lin, v, h, t + h)
        lost = friction_work(model, v, v_lin, v1)
        return q1, v1, a, (lost, jnp.zeros_like(h))
