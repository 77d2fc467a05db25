"""Bracketing search on a buckled/stable label: `bisect`, deprecated in favour of
[`jaxrod.boundary.roots.bisection`][] (the same search, with a result code, an evaluation count
and a tolerance)."""

from __future__ import annotations

import warnings
from collections.abc import Callable

import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

__all__ = ["bisect"]


def bisect(
    buckles: Callable[[Float[Array, ""]], Bool[Array, ""]],
    lo: Float[Array, ""],
    hi: Float[Array, ""],
    n_iter: int = 30,
    geometric: bool = True,
) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Bisection on a monotone label: `buckles(x)` is False at `lo` and True at `hi`.
    Deprecated: use [`jaxrod.boundary.roots.bisection`][] (it warns once per call).

    Pure and vmappable (vmap over `lo`, `hi` and whatever `buckles` closes over). The label is
    evaluated once per iteration; the bracket shrinks by 2 each time (in log space when
    `geometric`, for positive brackets spanning decades).

    **Returns:** the final bracket `(lo, hi)`; the boundary lies between them if the label is
    monotone. Check the initial bracket with the label yourself if unsure.
    """

    warnings.warn("jaxrod.search.bisect is deprecated: use jaxrod.boundary.roots.bisection.", DeprecationWarning,
                  stacklevel=2)

    def body(_, bracket):
        lo, hi = bracket
        mid = jnp.sqrt(lo * hi) if geometric else 0.5 * (lo + hi)
        b = buckles(mid)
        return jnp.where(b, lo, mid), jnp.where(b, mid, hi)

    return jax.lax.fori_loop(0, n_iter, body, (jnp.asarray(lo), jnp.asarray(hi)))
