"""The numerical helpers: `computed_once` changes no value and no derivative, and makes XLA
compute a shared value in one kernel."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod._numerics import computed_once


def _chain(a, b):
    """A chain of cheap elementwise operations with two results read by four consumers."""
    lam = jnp.clip(a * b - 0.3 * a, -1.0, 1.0)
    for _ in range(4):
        lam = jnp.minimum(jnp.maximum(lam - 0.1 * a * lam, -b), b)
    return lam * a, lam * b


def test_computed_once_is_exact_in_value_and_derivative():
    rng = np.random.default_rng(0)
    a, b = (jnp.asarray(rng.normal(size=257)) for _ in range(2))

    def plain(a, b):
        p, q = _chain(a, b)
        return jnp.sum(jnp.sin(p) * q + p**2)

    def once(a, b):
        p, q = computed_once(_chain(a, b), a)
        return jnp.sum(jnp.sin(p) * q + p**2)

    np.testing.assert_array_equal(np.asarray(computed_once(_chain(a, b), a)), np.asarray(_chain(a, b)))
    assert jax.jit(plain)(a, b) == jax.jit(once)(a, b)
    for argnum in (0, 1):
        np.testing.assert_array_equal(jax.grad(plain, argnum)(a, b), jax.grad(once, argnum)(a, b))
    single = computed_once(a * 2.0, a)
    np.testing.assert_array_equal(single, a * 2.0)
    # a NaN in the reference is passed on, never hidden
    bad = a.at[3].set(jnp.nan)
    assert np.isnan(np.asarray(computed_once(b, bad))[3])


def test_computed_once_stops_xla_duplicating_the_chain():
    """Four consumers of the chain: without the helper XLA recomputes it in each of their
    kernels, with it the chain is computed once (counted in the optimised HLO)."""
    a, b = jnp.linspace(-1.0, 1.0, 64), jnp.linspace(0.5, 2.0, 64)

    def consumers(p, q):
        return p + q, p * q, p - 2.0 * q, jnp.exp(p) + q  # read separately, each its own output

    def count_min(f):
        return f.lower(a, b).compile().as_text().count(" minimum(")

    plain = jax.jit(lambda a, b: consumers(*_chain(a, b)))
    once = jax.jit(lambda a, b: consumers(*computed_once(_chain(a, b), a)))
    for got, want in zip(once(a, b), plain(a, b)):  # equal but for the compiler's fused multiply-adds
        np.testing.assert_allclose(got, want, rtol=1e-15, atol=1e-15)
    assert count_min(once) < count_min(plain)
    assert count_min(once) <= 2 * 5  # the chain's 5 minima, once in each of p's and q's kernels
