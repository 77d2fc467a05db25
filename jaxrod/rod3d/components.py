"""Vectors and rotations of the 3D rod as tuples of component arrays, for its step.

The rod's state keeps (n, 3) and (n, 3, 3) arrays; the step unpacks them once into one array
per component and packs its results once. On CPU this is what lets XLA fuse a step into few
kernels: a sum over a trailing axis of length 3 is a reduction (its own kernel), a `stack` a
concatenation (often its own kernel), an einsum over (n, 3, 3) batches n tiny matrix products;
the same arithmetic on separate component arrays is elementwise and fuses with its neighbours.
A vector is a tuple `(x, y, z)` of arrays of one shape, a matrix a tuple of three row vectors.
"""

from __future__ import annotations

import jax.numpy as jnp

from .._numerics import computed_once
from .._trig import atan2, rodrigues, sincos

__all__ = ["unpack", "pack", "unpack_matrix", "pack_matrix", "dot", "cross", "add", "sub", "scale",
           "matvec", "rmatvec", "rotate", "log_rotation", "left_jacobian_inv_t", "relative_rotation"]


def unpack(a):
    """(…, 3) array → tuple of three (…) arrays."""
    return a[..., 0], a[..., 1], a[..., 2]


def pack(v):
    """Tuple of three arrays → (…, 3) array."""
    return jnp.stack(v, -1)


def unpack_matrix(A):
    """(…, 3, 3) array → tuple of three row vectors."""
    return tuple((A[..., a, 0], A[..., a, 1], A[..., a, 2]) for a in range(3))


def pack_matrix(A):
    return jnp.stack([jnp.stack(row, -1) for row in A], -2)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


def matvec(A, b):
    """A b (A as rows)."""
    return (dot(A[0], b), dot(A[1], b), dot(A[2], b))


def rmatvec(A, b):
    """Aᵀ b (A as rows)."""
    return tuple(A[0][c] * b[0] + A[1][c] * b[1] + A[2][c] * b[2] for c in range(3))


def rotate(phi, A):
    """exp([φ]×) A, column by column (Rodrigues: A_c + a φ × A_c + b φ × (φ × A_c), a = sin θ/θ,
    b = (1 − cos θ)/θ², θ = |φ|: `jaxrod._trig.rodrigues`, to rounding for θ ≤ π: the drift's
    rotation of one step, θ = h|ω|)."""
    th2 = dot(phi, phi)
    a, b = computed_once(rodrigues(th2), th2)  # read by all nine entries
    cols = []
    for c in range(3):
        col = (A[0][c], A[1][c], A[2][c])
        k1 = cross(phi, col)
        cols.append(add(col, add(scale(a, k1), scale(b, cross(phi, k1)))))
    return tuple(tuple(cols[c][r] for c in range(3)) for r in range(3))


def relative_rotation(A, B):
    """A Bᵀ (both as rows): entry (a, c) is row a of A · row c of B."""
    return tuple(tuple(dot(A[a], B[c]) for c in range(3)) for a in range(3))


def log_rotation(R, with_trig: bool = False):
    """The rotation vector ψ of R (as rows), as `jaxrod.rod3d.so3.log_so3`; with `with_trig`,
    also (sin θ, cos θ) of its angle θ = |ψ| (from R itself: no sine or cosine evaluated)."""
    s = (0.5 * (R[2][1] - R[1][2]), 0.5 * (R[0][2] - R[2][0]), 0.5 * (R[1][0] - R[0][1]))
    c = 0.5 * (R[0][0] + R[1][1] + R[2][2] - 1.0)
    s2 = dot(s, s)
    small = s2 < 1e-6
    sns = jnp.sqrt(jnp.where(small, 1.0, s2))
    factor = jnp.where(small, 1.0 + s2 / 6.0 + 3.0 * s2**2 / 40.0, atan2(sns, c) / sns)
    if not with_trig:
        return scale(factor, s)
    r = jnp.sqrt(s2 + c * c)  # 1 for an exact rotation; normalise rounding away
    return scale(factor, s), (jnp.sqrt(s2) / r, c / r)


def left_jacobian_inv_t(psi, m, trig=None):
    """J_l(ψ)⁻ᵀ m = m + ½ ψ × m + c(θ) ψ × (ψ × m), c = 1/θ² − (1 + cos θ)/(2θ sin θ), θ = |ψ|
    (series 1/12 + θ²/720 + θ⁴/30240 below θ = 1e-2): the gradient of m · log(exp([δ]×) R)
    with respect to δ at δ = 0, for ψ = log R (a left perturbation of R). `trig`: (sin θ, cos θ)
    if known (`log_rotation(R, with_trig=True)`), else evaluated."""
    th2 = dot(psi, psi)
    small = th2 < 1e-4
    ths = jnp.sqrt(jnp.where(small, 1.0, th2))
    sin, cos = sincos(ths) if trig is None else trig
    c = jnp.where(small, 1.0 / 12.0 + th2 / 720.0 + th2**2 / 30240.0,
                  1.0 / ths**2 - (1.0 + cos) / (2.0 * ths * jnp.where(small, 1.0, sin)))
    pm = computed_once(cross(psi, m), th2)  # read by every component of the result
    return add(m, add(scale(0.5, pm), scale(c, cross(psi, pm))))
