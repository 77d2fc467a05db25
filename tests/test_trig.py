"""`jaxrod._trig`: the vectorised sine, cosine and arctangent agree with the C library to 2 units
in the last place over the ranges the rod uses and beyond (float64; other dtypes go to `jnp`,
checked as well), keep the library's special values, and differentiate to the exact
derivatives; Rodrigues' coefficients and the logarithm's half-angle coefficients agree with an
extended-precision reference."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod._trig import atan2, atan_sqrt, rodrigues, sincos


def _ulps(got, ref, dtype):
    """|got − ref| in units of the last place of ref (of 1 below |ref| = 1: absolute near zeros)."""
    got, ref = np.asarray(got, np.float64), np.asarray(ref, np.float64)
    return np.abs(got - ref) / np.spacing(np.maximum(np.abs(ref), 1.0).astype(dtype)).astype(np.float64)


def _angles(rng, dtype):
    x = np.concatenate([rng.uniform(-10, 10, 20000), rng.uniform(-1e5, 1e5, 5000),
                        10.0 ** rng.uniform(-20, 0, 5000) * rng.choice([-1, 1], 5000),
                        np.arange(-400, 401) * np.pi / 4, [0.0, -0.0]])
    return x.astype(dtype)


def test_sincos_matches_the_library():
    rng = np.random.default_rng(0)
    for dtype in (np.float64, np.float32):
        x = _angles(rng, dtype)
        s, c = jax.jit(sincos)(jnp.asarray(x))
        assert s.dtype == c.dtype == dtype
        assert _ulps(s, np.sin(x), dtype).max() <= 2.0 and _ulps(c, np.cos(x), dtype).max() <= 2.0
        # tiny angles: sin x = x and cos x = 1 exactly, as the library gives
        tiny = np.abs(x) < 1e-9
        assert (np.asarray(s)[tiny] == x[tiny]).all() and (np.asarray(c)[tiny] == 1.0).all()


def test_atan2_matches_the_library_with_its_special_values():
    rng = np.random.default_rng(1)
    for dtype in (np.float64, np.float32):
        y, x = (rng.normal(size=40000) * 10.0 ** rng.uniform(-10, 5, 40000) for _ in range(2))
        special = np.array([0.0, -0.0, 1.0, -1.0, 3.0, -2.0, 1e-300, np.inf])
        y = np.concatenate([y, np.repeat(special, 8)]).astype(dtype)
        x = np.concatenate([x, np.tile(special, 8)]).astype(dtype)
        got = np.asarray(jax.jit(atan2)(jnp.asarray(y), jnp.asarray(x)))
        ref = np.arctan2(y, x)
        finite = np.isfinite(y) & np.isfinite(x)
        assert _ulps(got[finite], ref[finite], dtype).max() <= 2.0
        # signed zeros and axes exactly as the library: ±0, ±π/2, ±π
        axes = finite & ((y == 0) | (x == 0))
        np.testing.assert_array_equal(got[axes], ref[axes])
        assert (np.signbit(got[axes]) == np.signbit(ref[axes])).all()


def test_derivatives_are_the_exact_ones():
    t = jnp.linspace(-7.0, 7.0, 101)
    ds = jax.vmap(jax.grad(lambda a: sincos(a)[0]))(t)
    dc = jax.vmap(jax.grad(lambda a: sincos(a)[1]))(t)
    np.testing.assert_allclose(ds, jnp.cos(t), atol=1e-15)
    np.testing.assert_allclose(dc, -jnp.sin(t), atol=1e-15)
    y, x = jnp.sin(t) * 2.0, jnp.cos(t) * 0.5
    gy, gx = jax.vmap(jax.grad(atan2, argnums=(0, 1)))(y, x)
    r2 = x * x + y * y
    np.testing.assert_allclose(gy, x / r2, rtol=1e-14)
    np.testing.assert_allclose(gx, -y / r2, rtol=1e-14)


def test_rodrigues_coefficients_match_extended_precision():
    """sin θ/θ and (1 − cos θ)/θ² = 2 sin²(θ/2)/θ² from θ², against numpy's long double (64-bit
    mantissa on x86; no cancellation in either form): within 4 units in the last place of 1
    for θ ≤ π in float64 and float32, within 5e-11 up to 2π (outside the kernels' range)."""
    rng = np.random.default_rng(3)
    theta = np.concatenate([rng.uniform(0, np.pi, 20000), 10.0 ** rng.uniform(-12, 0, 5000), [0.0, np.pi]])
    th = theta.astype(np.longdouble)
    safe = np.where(th > 0, th, 1)
    a_ref = np.where(th > 0, np.sin(th) / safe, 1)
    b_ref = np.where(th > 0, 2 * np.sin(th / 2) ** 2 / safe**2, 0.5)
    for dtype in (np.float64, np.float32):
        a, b = jax.jit(rodrigues)(jnp.asarray((theta * theta).astype(dtype)))
        assert a.dtype == b.dtype == dtype
        assert _ulps(a, a_ref.astype(np.float64), dtype).max() <= 4.0
        assert _ulps(b, b_ref.astype(np.float64), dtype).max() <= 4.0
    wide = np.linspace(np.pi, 2 * np.pi, 1001)
    a, b = rodrigues(jnp.asarray(wide**2))
    np.testing.assert_allclose(a, np.sin(wide) / wide, rtol=0, atol=5e-11)
    np.testing.assert_allclose(b, (1 - np.cos(wide)) / wide**2, rtol=0, atol=5e-11)
    # smooth through θ = 0: d(sin θ/θ)/d(θ²) = −1/6, d((1 − cos θ)/θ²)/d(θ²) = −1/24
    da, db = (jax.grad(lambda t, k=k: rodrigues(t)[k])(0.0) for k in (0, 1))
    np.testing.assert_allclose([da, db], [-1 / 6, -1 / 24], rtol=1e-14)


def test_half_angle_coefficients_match_extended_precision():
    """A = atan(t)/t and C = (1 − A)/(t²A²) from z = t², against numpy's long double, through
    all three of Cephes' ranges (t ≤ 0.66, ≤ 1 + √2, beyond) and their borders: A within 4 units
    in the last place, C within 8 (its long-double reference takes (1 − A)/t² from its series
    Σ (−t²)ᵏ/(2k + 3) below t = 0.1, where 1 − A cancels); C → 1/3 at z = 0 with finite
    derivatives there."""
    rng = np.random.default_rng(4)
    borders = np.array([0.66, np.sqrt(2) + 1])
    t = np.concatenate([rng.uniform(0, 3, 20000), 10.0 ** rng.uniform(-12, 6, 5000),
                        np.outer(borders, 1 + np.linspace(-1e-12, 1e-12, 41)).ravel(), [0.0]])
    z = (t * t).astype(np.float64)
    tl = np.sqrt(z.astype(np.longdouble))
    safe = np.where(tl > 0, tl, 1)
    a_ref = np.where(tl > 0, np.arctan(safe) / safe, 1)
    c_big = (1 - a_ref) / (safe**2 * a_ref**2)
    c_series = sum((-tl * tl) ** k / (2 * k + 3) for k in range(16)) / a_ref**2
    c_ref = np.where(tl < 0.1, c_series, c_big)
    A, C = jax.jit(atan_sqrt)(jnp.asarray(z))
    assert _ulps(A, a_ref.astype(np.float64), np.float64).max() <= 4.0
    assert _ulps(C, c_ref.astype(np.float64), np.float64).max() <= 8.0
    dA, dC = (jax.grad(lambda x, k=k: atan_sqrt(x)[k])(0.0) for k in (0, 1))
    # A = 1 − z/3 + z²/5 − …, C = (1/3 − z/5 + …)(1 + 2z/3 + …) = 1/3 + (2/9 − 1/5) z + …
    # (the rational approximation's z² coefficient is Cephes' fit: 7e-12 off 1/5 in dC)
    np.testing.assert_allclose([dA, dC], [-1 / 3, 2 / 9 - 1 / 5], rtol=1e-10)
