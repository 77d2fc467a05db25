"""The 3D rod's highest frequency, by power iteration on M⁻¹H with Hessian-vector products
(forward-over-reverse AD): it sets the explicit step limit 2/ω_max."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .so3 import skew

__all__ = ["max_frequency", "step_limit"]


def max_frequency(model, q, iters: int = 80) -> Float[Array, ""]:
    """ω_max [rad/s] of the linearised conservative dynamics at `q` (default: the straight
    rod under its end load), by power iteration on M⁻¹H (Hessian-vector products by
    forward-over-reverse AD). The explicit step limit is 2/ω_max."""
    state = q
    held_n, held_s = model.held()
    dtype = state.x.dtype
    free_n = jnp.where(held_n, 0.0, 1.0).astype(dtype)
    free_s = jnp.where(held_s, 0.0, 1.0).astype(dtype)
    mass = model.mass[:, None] * jnp.ones((1, 3), dtype)
    inert = model.inertia[None, :] * jnp.ones((model.n, 1), dtype)

    def U(x, phi):
        Qp = state.Q - jnp.einsum("jab,jbc->jac", skew(phi), state.Q)
        return model.potential(x, Qp)

    g = jax.grad(U, argnums=(0, 1))
    phi0 = jnp.zeros((model.n, 3), state.x.dtype)

    def hvp(dx, dphi):
        return jax.jvp(lambda a, b: g(a, b), (state.x, phi0), (dx, dphi))[1]

    key = jax.random.PRNGKey(0)
    k1, k2 = jax.random.split(key)
    dx = free_n * jax.random.normal(k1, state.x.shape, state.x.dtype) / jnp.sqrt(mass)
    dp = free_s * jax.random.normal(k2, phi0.shape, state.x.dtype) / jnp.sqrt(inert)

    def body(_, c):
        dx, dp, lam = c
        hx, hp = hvp(dx, dp)
        ax, ap = free_n * hx / mass, free_s * hp / inert  # M⁻¹ H d on the free DOFs
        nrm = jnp.sqrt(jnp.sum(mass * ax**2) + jnp.sum(inert * ap**2))
        cur = jnp.sqrt(jnp.sum(mass * dx**2) + jnp.sum(inert * dp**2))
        return ax / nrm, ap / nrm, nrm / cur

    dx, dp, lam = jax.lax.fori_loop(0, iters, body, (dx, dp, jnp.zeros((), state.x.dtype)))
    return jnp.sqrt(jnp.abs(lam))


# one compiled power iteration per model shape, for every caller: the step limit of a scene or a
# sweep, the check of `jaxrod.simulate`, `Rod3D.max_frequency` (written to the persistent
# compilation cache like every program: a later process only traces it)
max_frequency_jit = eqx.filter_jit(max_frequency)


def step_limit(model, q=None) -> float:
    """The explicit step limit 2/ω_max [s] of the rod `model` at `q` (default: straight, under its
    end load): the stiffest of the axial, shear, bending, twist and contact vibrations."""
    return float(2.0 / model.max_frequency(q))
