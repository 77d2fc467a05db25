"""Axial loads: constant, or ramped in time."""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._numerics import float_leaf

__all__ = ["AbstractLoad", "ConstantLoad", "RampLoad", "as_load"]


class AbstractLoad(eqx.Module):
    """A compressive axial force F(t) [N], uniform along the rod."""

    @abc.abstractmethod
    def __call__(self, t) -> Float[Array, ""]:
        """The load at time `t` [s]."""

    @property
    @abc.abstractmethod
    def constant(self) -> bool:
        """Whether F does not depend on time (static)."""

    @abc.abstractmethod
    def extremes(self) -> tuple[Float[Array, ""], Float[Array, ""]]:
        """The smallest and largest load over all time."""


class ConstantLoad(AbstractLoad):
    """F(t) = `F` [N] (a dynamic leaf)."""

    F: Float[Array, ""] = eqx.field(converter=float_leaf)

    def __call__(self, t):
        return self.F

    @property
    def constant(self) -> bool:
        return True

    def extremes(self):
        return self.F, self.F


class RampLoad(AbstractLoad):
    """F rises linearly from `F_start` at `t_start` to `F_end` at `t_end` and is held constant
    outside [`t_start`, `t_end`] (all [N] or [s], dynamic leaves)."""

    F_start: Float[Array, ""] = eqx.field(converter=float_leaf)
    F_end: Float[Array, ""] = eqx.field(converter=float_leaf)
    t_start: Float[Array, ""] = eqx.field(converter=float_leaf)
    t_end: Float[Array, ""] = eqx.field(converter=float_leaf)

    def __call__(self, t):
        span = jnp.maximum(self.t_end - self.t_start, jnp.finfo(jnp.result_type(float)).tiny)
        x = jnp.clip((t - self.t_start) / span, 0.0, 1.0)
        return self.F_start + (self.F_end - self.F_start) * x

    @property
    def constant(self) -> bool:
        return False

    def extremes(self):
        return jnp.minimum(self.F_start, self.F_end), jnp.maximum(self.F_start, self.F_end)


def as_load(F: ArrayLike | AbstractLoad) -> AbstractLoad:
    """A load object from a number (constant load) or a load."""
    return F if isinstance(F, AbstractLoad) else ConstantLoad(F)
