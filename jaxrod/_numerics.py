"""Numerical helpers shared across layers."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

__all__ = ["safe_norm", "float_leaf"]


def safe_norm(v: Float[Array, "... 3"], axis: int = -1) -> Float[Array, "..."]:
    """|v| with a zero (not NaN) gradient at v = 0."""
    sq = jnp.sum(v * v, axis=axis)
    pos = sq > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, sq, 1.0)), 0.0)


def safe_hypot(a: Float[Array, "..."], b: Float[Array, "..."]) -> Float[Array, "..."]:
    """√(a² + b²) of a 2-vector given as its components, with a zero (not NaN) gradient at 0."""
    sq = a * a + b * b
    pos = sq > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, sq, 1.0)), 0.0)


def float_leaf(x, dtype=None):
    """`x` as an array of `dtype` (default: the default float dtype): a model's physical number."""
    return jnp.asarray(x, dtype=jnp.result_type(float) if dtype is None else dtype)
