"""Symplectic Euler with an explicit friction force: the documented failure case."""

from __future__ import annotations

import equinox as eqx

from ..friction import AbstractFriction, Coulomb
from .base import AbstractFixedStep

__all__ = ["SymplecticEuler"]


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

    def step(self, model, q, v, t, h):
        f_s, f_d = model.friction_bounds(t)
        v = v + h * (model.acceleration(q, t) - self.friction.acceleration(v, f_s, f_d))
        return q + h * v, v
