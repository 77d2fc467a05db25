"""Sine-mode analysis of a pinned rod sampled at interior nodes (E6 B/C)."""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

__all__ = ["sine_basis", "modal_amplitudes", "modal_spectrum", "dominant_mode", "sine_shape"]


@functools.lru_cache(maxsize=32)
def _basis_np(n: int, n_modes: int) -> np.ndarray:
    j = np.arange(1, n + 1)[:, None]
    m = np.arange(1, n_modes + 1)[None, :]
    return np.sin(np.pi * j * m / (n + 1))


def sine_basis(n: int, n_modes: int | None = None) -> Float[Array, "n n_modes"]:
    """S[j, m] = sin(π (j+1)(m+1)/(n+1)): sine mode m+1 sampled at the n interior nodes
    s_j = (j+1)L/(n+1). Its columns are orthogonal with squared norm (n+1)/2 (the DST-I)."""
    return jnp.asarray(_basis_np(n, n if n_modes is None else n_modes), dtype=jnp.result_type(float))


def sine_shape(n: int, m, dtype=None) -> Float[Array, " n"]:
    """sin(mπs/L) at the n interior nodes (`m` may be traced)."""
    dtype = jnp.result_type(float) if dtype is None else dtype
    j = jnp.arange(1, n + 1, dtype=dtype)
    return jnp.sin(jnp.pi * j * jnp.asarray(m, dtype) / (n + 1))


def modal_amplitudes(theta: Float[Array, "... n"], n_modes: int | None = None) -> Float[Array, "... n_modes"]:
    """Amplitudes A_m of θ = Σ A_m sin(mπs/L) from nodal values (exact DST-I inversion for
    modes m ≤ n)."""
    n = theta.shape[-1]
    S = sine_basis(n, n_modes)
    return (2.0 / (n + 1)) * theta @ S


def modal_spectrum(theta: Float[Array, "... n"], n_modes: int | None = None) -> Float[Array, "... n_modes"]:
    """Modal power A_m² normalised to sum to one (all zero for θ ≡ 0)."""
    p = modal_amplitudes(theta, n_modes) ** 2
    tot = p.sum(-1, keepdims=True)
    return jnp.where(tot > 0, p / jnp.where(tot > 0, tot, 1.0), 0.0)


def dominant_mode(theta: Float[Array, "... n"], n_modes: int | None = None) -> Int[Array, "..."]:
    """The mode number (≥ 1) with the largest modal power."""
    return jnp.argmax(modal_amplitudes(theta, n_modes) ** 2, axis=-1) + 1
