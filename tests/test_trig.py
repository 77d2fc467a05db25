"""`jaxrod._trig`: the vectorised sine, cosine and arctangent agree with the C library to 2 units
in the last place over the ranges the rod uses and beyond (float64; other dtypes go to `jnp`,
checked as well), keep the library's special values, and differentiate to the exact
derivatives."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod._trig import atan2, sincos


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
