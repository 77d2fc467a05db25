"""The interface every model implements."""

from __future__ import annotations

import abc

import equinox as eqx
from jaxtyping import Array, Float

__all__ = ["AbstractModel"]


class AbstractModel(eqx.Module):
    """A mechanical system `q̈ = a(q, t) − friction(q̇)` with friction acting per degree of
    freedom as a bounded acceleration.

    Integrators only use these methods, so any model that implements them runs with every
    integrator. The coordinates are scaled so that the mass matrix is the identity.
    """

    @abc.abstractmethod
    def acceleration(self, q: Float[Array, "..."], t) -> Float[Array, "..."]:
        """The conservative (elastic + load + gravity) acceleration at `q`, time `t`."""

    @abc.abstractmethod
    def friction_bounds(self, t) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
        """Static and dynamic friction bounds per degree of freedom, as accelerations."""

    @abc.abstractmethod
    def potential_energy(self, q: Float[Array, "..."], t) -> Float[Array, ""]:
        """Potential energy (per unit of the model's mass scaling) at `q`."""

    @abc.abstractmethod
    def max_frequency(self) -> Float[Array, ""]:
        """The highest angular frequency of the conservative part [rad/s]; a fixed-step
        explicit integrator is stable for `dt · max_frequency < 2`."""

    def kinetic_energy(self, v: Float[Array, "..."]) -> Float[Array, ""]:
        """Kinetic energy ½|v|² in the model's mass scaling."""
        return 0.5 * (v * v).sum()

    def is_stuck(self, q, v, t):
        """Whether the whole system is at rest and held by static friction."""
        f_s, _ = self.friction_bounds(t)
        a = self.acceleration(q, t)
        return (v == 0).all() & (abs(a) <= f_s).all()

    def check(self):
        """Boolean scalar: whether the model's parameters are valid (for result codes)."""
        return True
