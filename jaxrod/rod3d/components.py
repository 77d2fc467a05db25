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
from .._trig import atan_sqrt, rodrigues

__all__ = ["unpack", "pack", "unpack_matrix", "pack_matrix", "dot", "cross", "add", "sub", "scale",
           "matvec", "rmatvec", "gyroscopic", "rotate", "log_rotation", "left_jacobian_inv_t", "relative_rotation"]


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


def gyroscopic(J, W):
    """ω × Jω for a diagonal inertia J (material frame), both as component tuples."""
    return cross(W, (J[0] * W[0], J[1] * W[1], J[2] * W[2]))


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


def log_rotation(R, with_jacobian: bool = False):
    """The rotation vector ψ of R (as rows), as `jaxrod.rod3d.so3.log_so3`, for angles θ < π;
    with `with_jacobian`, also the coefficient c(θ) of `left_jacobian_inv_t`.

    From the half angle: with s = vee(R) = sin θ·n and cos θ = (tr R − 1)/2, t = tan(θ/2) =
    |s|/(1 + cos θ), so z = t² needs no square root; then ψ = 2 atan(t)·n = 2A/(1 + cos θ)·s
    and c(θ) = 1/θ² − (1 + cos θ)/(2θ sin θ) = (1 − A)/(4zA²) = C/4 with (A, C) =
    `jaxrod._trig.atan_sqrt(z)`: no sine, cosine, arctangent or division by θ, and finite
    derivatives at the identity. To rounding up to θ ≈ 3 rad; nearer π, 1 + cos θ loses digits
    (1e-14 relative at 3.1 rad), far beyond any joint of a rod that resolves its shape."""
    s = (0.5 * (R[2][1] - R[1][2]), 0.5 * (R[0][2] - R[2][0]), 0.5 * (R[1][0] - R[0][1]))
    u = 2.0 / (R[0][0] + R[1][1] + R[2][2] + 1.0)  # 1/(1 + cos θ), as tr R = 1 + 2 cos θ
    A, C = atan_sqrt(dot(s, s) * u * u)
    psi = scale(2.0 * u * A, s)
    return (psi, 0.25 * C) if with_jacobian else psi


def left_jacobian_inv_t(psi, m, c):
    """J_l(ψ)⁻ᵀ m = m + ½ ψ × m + c ψ × (ψ × m), c = c(θ) = 1/θ² − (1 + cos θ)/(2θ sin θ) for
    θ = |ψ| (from `log_rotation(R, with_jacobian=True)`): the gradient of m · log(exp([δ]×) R)
    with respect to δ at δ = 0, for ψ = log R (a left perturbation of R)."""
    pm = computed_once(cross(psi, m), psi[0])  # read by every component of the result
    return add(m, add(scale(0.5, pm), scale(c, cross(psi, pm))))
