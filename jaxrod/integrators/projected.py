"""What the projected (proximal) schemes share: a fixed step and a friction law applied as an
exact proximal step, under which a held degree of freedom stays exactly still."""

from __future__ import annotations

import equinox as eqx

from ..friction import AbstractFriction, Coulomb
from .base import AbstractFixedStep

__all__ = ["AbstractProjected"]


class AbstractProjected(AbstractFixedStep):
    """A fixed-step scheme with the friction law `friction` applied as a proximal step:
    [`jaxrod.ProjectedVerlet`][] and [`jaxrod.ProjectedLeapfrog`][]. Fields `dt` [s] (static,
    > 0) and `friction` (default [`jaxrod.Coulomb`][])."""

    dt: float = eqx.field(static=True)
    friction: AbstractFriction = Coulomb()

    def __check_init__(self):
        if not (isinstance(self.dt, (int, float)) and self.dt > 0):
            raise ValueError(f"{type(self).__name__}.dt = {self.dt!r} is invalid: expected a float > 0.")

    def held_is_fixed(self, model):
        # with the sharp law a held DOF has exactly zero velocity after the prox
        return model.held_is_fixed and isinstance(self.friction, Coulomb)
