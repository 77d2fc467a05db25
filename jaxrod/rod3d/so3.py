"""Rotations for the discrete rod: skew matrices, the exponential and the logarithm of SO(3),
written so that values and gradients are finite at the identity."""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._numerics import safe_norm as safe_norm

__all__ = ["skew", "vee", "exp_so3", "log_so3", "safe_norm"]


def skew(a: Float[Array, "... 3"]) -> Float[Array, "... 3 3"]:
    """[a]×: the matrix with [a]× b = a × b."""
    z = jnp.zeros_like(a[..., 0])
    return jnp.stack(
        [
            jnp.stack([z, -a[..., 2], a[..., 1]], -1),
            jnp.stack([a[..., 2], z, -a[..., 0]], -1),
            jnp.stack([-a[..., 1], a[..., 0], z], -1),
        ],
        -2,
    )


def vee(m: Float[Array, "... 3 3"]) -> Float[Array, "... 3"]:
    """The inverse of `skew` applied to the skew part of `m`."""
    return 0.5 * jnp.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]], -1
    )


def exp_so3(phi: Float[Array, "... 3"]) -> Float[Array, "... 3 3"]:
    """exp([φ]×) by Rodrigues' formula, with Taylor series below |φ| = 1e-4 rad."""
    th2 = jnp.sum(phi * phi, -1)
    small = th2 < 1e-8
    ths = jnp.sqrt(jnp.where(small, 1.0, th2))
    a = jnp.where(small, 1.0 - th2 / 6.0, jnp.sin(ths) / ths)
    b = jnp.where(small, 0.5 - th2 / 24.0, (1.0 - jnp.cos(ths)) / ths**2)
    K = skew(phi)
    eye = jnp.broadcast_to(jnp.eye(3, dtype=phi.dtype), K.shape)
    return eye + a[..., None, None] * K + b[..., None, None] * (K @ K)


def log_so3(R: Float[Array, "... 3 3"]) -> Float[Array, "... 3"]:
    """The rotation vector ψ with exp([ψ]×) = R, for rotation angles below π.

    ψ = (θ/sin θ)·vee(R − Rᵀ)/2 with θ = atan2(|vee|, (tr R − 1)/2); the factor θ/sin θ uses
    its series 1 + s²/6 + 3s⁴/40 (s = sin θ) near the identity, where adjacent segments of a
    rod always are.
    """
    s = vee(R)
    c = 0.5 * (jnp.trace(R, axis1=-2, axis2=-1) - 1.0)
    s2 = jnp.sum(s * s, -1)
    small = s2 < 1e-6
    sns = jnp.sqrt(jnp.where(small, 1.0, s2))
    factor = jnp.where(small, 1.0 + s2 / 6.0 + 3.0 * s2**2 / 40.0, jnp.arctan2(sns, c) / sns)
    return factor[..., None] * s
