"""Numerical helpers shared across layers."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

__all__ = ["safe_norm", "safe_hypot", "float_leaf", "concrete_value", "format_value", "computed_once"]


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


def float_leaf(x):
    """`x` as a floating array leaf: a physical number of a model, load, perturbation or formula.

    A Python number, or an array of integers or booleans, becomes an array of the default float
    dtype (strongly typed, so that it does not follow another operand's precision); a floating
    array keeps its dtype. The one converter every module uses."""
    if isinstance(x, (int, float)):
        return jnp.asarray(x, dtype=jnp.result_type(float))
    x = jnp.asarray(x)
    return x if jnp.issubdtype(x.dtype, jnp.floating) else x.astype(jnp.result_type(float))


def concrete_value(x) -> np.ndarray | None:
    """The value of `x` on the host, or `None` while it is being traced (no check possible): what
    an argument check reads."""
    if isinstance(x, jax.core.Tracer):
        return None
    try:
        return np.asarray(x)
    except Exception:  # pragma: no cover - abstract values of exotic transforms
        return None


def format_value(v: np.ndarray) -> str:
    """A concrete value for an error message: the number, or a short array."""
    return repr(v.item()) if v.ndim == 0 else np.array2string(v, threshold=6)


def computed_once(values, ref: Float[Array, "..."]):
    """`values` (an array or a tuple of arrays of `ref`'s shape) unchanged, but computed once.

    XLA on CPU fuses a chain of cheap elementwise operations into every kernel that reads its
    result: a value read by k kernels is recomputed k times (in the 3D rod's friction pass a
    slip impulse was recomputed in every kernel that updates a velocity, several times the unique
    arithmetic). It never duplicates a division, so dividing by a 1 it cannot prove to be 1
    (NaN where `ref` is NaN, 1 elsewhere; `ref` any array of the state of the values' own shape,
    not a constant and not a broadcast, which XLA would turn into a multiplication) makes
    the value one kernel's output that the others read. x/1 is exact: the values and their
    derivatives are unchanged (but for the compiler's choice of fused multiply-adds around the
    new kernel boundary, a rounding)."""
    one = jnp.where(jnp.isnan(ref), jnp.nan, 1.0).astype(ref.dtype)
    if isinstance(values, tuple):
        return tuple(v / one for v in values)
    return values / one
