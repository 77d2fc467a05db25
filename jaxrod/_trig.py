"""Sine, cosine and arctangents as polynomials that XLA vectorises on the CPU, and the
coefficients of a rotation's exponential (`rodrigues`) and logarithm (`atan_sqrt`) built on them.

XLA on the CPU evaluates `jnp.sin`, `jnp.cos` and `jnp.arctan2` in float64 one element at a
time through the C library, an order of magnitude slower than a multiplication, division or
square root in a fused kernel (benchmarks/README.md gives the measurement). The 3D rod's step
calls them for every segment (the drift's rotation, the curvature's logarithm, the amplitude). Here they are the classical
range-reduced polynomial approximations (sine and cosine: fdlibm's kernels on |r| ≤ π/4 after a
three-part Cody–Waite reduction by π/2, exact for |x| < 2²⁰·π/2; arctangent: Cephes' rational
approximation with its reduction to |t| ≤ 0.66), written with elementwise operations only, so
that they fuse with their neighbours and vectorise: within 2 units in the last place of the
library functions (tests/test_trig.py), differentiable (their derivatives are those of the
polynomials, within a few ulp of the exact ones). The constants are float64's: `sincos` and
`atan2` hand arrays of any other dtype to `jnp.sin`, `jnp.cos` and `jnp.arctan2` (XLA vectorises
float32 itself); `rodrigues` and `atan_sqrt` evaluate their polynomials in the input's dtype.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
from jaxtyping import Array, Float

__all__ = ["sincos", "atan2", "rodrigues", "atan_sqrt"]

# π/2 in three parts of 33 bits (fdlibm's pio2_1, pio2_2 and pio2_2t): k·part is exact for |k| < 2²⁰
_PIO2 = (1.57079632673412561417e00, 6.07710050630396597660e-11, 2.02226624879595063154e-21)
# fdlibm __kernel_sin and __kernel_cos on |r| ≤ π/4
_S = (-1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04,
      2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10)
_C = (4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05,
      -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11)
# Cephes atan: atan(t) = t + t·z·P(z)/Q(z), z = t², for |t| ≤ 0.66
_P = (-8.750608600031904122785e-01, -1.615753718733365076637e01, -7.500855792314704667340e01,
      -1.228866684490136173410e02, -6.485021904942025371773e01)
_Q = (2.485846490142306297962e01, 1.650270098316988542046e02, 4.328810604912902668951e02,
      4.853903996359136964868e02, 1.945506571482613964425e02)
_MOREBITS = 6.123233995736765886130e-17  # π/2 − fl(π/2)


def _horner(z, coefficients):
    """c₀zᵏ⁻¹ + … + cₖ₋₁ (highest power first)."""
    out = jnp.full_like(z, coefficients[0])
    for c in coefficients[1:]:
        out = out * z + c
    return out


def sincos(x: Float[Array, "..."]) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(sin x, cos x), elementwise, for |x| < 2²⁰·π/2 ≈ 1.6e6 (beyond it the reduction loses
    digits)."""
    x = jnp.asarray(x)
    if x.dtype != jnp.float64:
        return jnp.sin(x), jnp.cos(x)
    k = jnp.round(x * (2.0 / math.pi))
    r = ((x - k * _PIO2[0]) - k * _PIO2[1]) - k * _PIO2[2]
    z = r * r
    sin_r = r + r * z * _horner(z, _S[::-1])
    cos_r = (1.0 - 0.5 * z) + z * z * _horner(z, _C[::-1])
    quadrant = k - 4.0 * jnp.floor(0.25 * k)  # k mod 4, in 0..3
    swap = (quadrant == 1.0) | (quadrant == 3.0)
    s, c = jnp.where(swap, cos_r, sin_r), jnp.where(swap, sin_r, cos_r)
    return jnp.where(quadrant >= 2.0, -s, s), jnp.where((quadrant == 1.0) | (quadrant == 2.0), -c, c)


def rodrigues(theta2: Float[Array, "..."]) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(sin θ/θ, (1 − cos θ)/θ²) from θ² ≥ 0, elementwise: the coefficients of Rodrigues'
    formula for a rotation vector of angle θ, with no square root, division or range reduction.
    fdlibm's kernels give s = sin x/x and c = cos x at x = θ/4; twice the double angle then gives
    sin 2x/2x = s c, cos 2x = 1 − 2x²s², sin θ/θ = (sin 2x/2x) cos 2x and (1 − cos θ)/θ² =
    ½ (sin 2x/2x)². Within a few units in the last place for θ ≤ π, where x stays in the kernels'
    range |x| ≤ π/4 (tests/test_trig.py); beyond, they are polynomials outside it (error 2e-11 at
    θ = 2π): meant for the rotation of one time step, which turns a segment by far less."""
    x2 = jnp.asarray(theta2) / 16.0
    s = 1.0 + x2 * _horner(x2, _S[::-1])
    c = (1.0 - 0.5 * x2) + x2 * x2 * _horner(x2, _C[::-1])
    s2 = s * c
    return s2 * (1.0 - 2.0 * x2 * s * s), 0.5 * s2 * s2


def atan_sqrt(z: Float[Array, "..."]) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(A, C) from z = t² ≥ 0, elementwise: A = atan(t)/t and C = (1 − A)/(zA²) (1/3 at z = 0):
    the coefficients of a rotation's logarithm from the squared tangent of its half angle
    (`jaxrod.rod3d.components.log_rotation`). For t ≤ 0.66 (z ≤ 0.4356) Cephes' rational
    arctangent in z itself, A = 1 + z·r(z) and C = −r/A², with no square root and no
    cancellation; beyond, Cephes' reductions atan t = π/4 + atan((t − 1)/(t + 1)) (t ≤ 1 + √2)
    and π/2 − atan(1/t). Within a few units in the last place (tests/test_trig.py); finite with
    finite derivatives at z = 0. The polynomials are evaluated in z's own dtype."""
    z = jnp.asarray(z)
    near, far = z <= 0.66**2, z > 3.0 + 2.0 * math.sqrt(2.0)  # tan(3π/8)² = (1 + √2)²
    t = jnp.sqrt(jnp.where(near, 1.0, z))
    num, den = jnp.where(far, -1.0, t - 1.0), jnp.where(far, t, t + 1.0)
    x = num / den  # the reduced argument away from 0
    zx = jnp.where(near, z, x * x)
    r = _horner(zx, _P) / _horner(zx, (1.0,) + _Q)
    ax = 1.0 + zx * r  # atan(x)/x
    offset = jnp.where(far, math.pi / 2 + _MOREBITS, math.pi / 4 + 0.5 * _MOREBITS)
    A = jnp.where(near, ax, (offset + x * ax) / t)
    zs = jnp.where(z > 0, z, 1.0)
    return A, jnp.where(near, -r * zs, 1.0 - A) / (zs * A * A)


def atan2(y: Float[Array, "..."], x: Float[Array, "..."]) -> Float[Array, "..."]:
    """The angle of (x, y) in [−π, π], elementwise, as `jnp.arctan2` (its signed zeros too)."""
    if jnp.result_type(y, x) != jnp.float64:
        return jnp.arctan2(y, x)
    ax, ay = jnp.abs(x), jnp.abs(y)
    hi, lo = jnp.maximum(ax, ay), jnp.minimum(ax, ay)
    a = jnp.where(hi > 0, lo / jnp.where(hi > 0, hi, 1.0), 0.0)  # in [0, 1]
    upper = a > 0.66  # atan a = π/4 + atan((a − 1)/(a + 1))
    t = jnp.where(upper, (a - 1.0) / (a + 1.0), a)
    z = t * t
    atan_a = t + t * z * _horner(z, _P) / _horner(z, (1.0,) + _Q)
    atan_a = jnp.where(upper, (math.pi / 4 + 0.5 * _MOREBITS) + atan_a, atan_a)
    angle = jnp.where(ay > ax, (math.pi / 2 + _MOREBITS) - atan_a, atan_a)  # in [0, π/2]
    angle = jnp.where(jnp.signbit(x), (math.pi + 2.0 * _MOREBITS) - angle, angle)  # in [0, π]
    return jnp.where(jnp.signbit(y), -angle, angle)
