r"""The 3D rod's highest frequency ω_max, which sets the explicit step limit 2/ω_max: in closed
form (`frequency_bound`, what the step limit uses), and measured by power iteration on M⁻¹H with
Hessian-vector products (`power_max_frequency`, the reference the tests hold the bound to).

**The closed form.** At a straight (or nearly straight) state along x the linearised dynamics
splits into four blocks that do not couple: the axial translations, the twist rotations, and two
lateral blocks, each a node translation u across the axis and the segment rotation φ that bends
in that plane. With segment length l̂, node mass m = ρl̂, rotary inertias J_t = α ρ_v l̂ I
(bending, scaled by α, `rotary_scale`) and J_a = 2 ρ_v l̂ I (twist), the highest mode of each block
is the alternating one (wavenumber π per segment), where

- axial chain (springs EA/l̂): ω² = 4 EA / (l̂ m);
- twist chain (springs GJ/l̂): ω² = 4 GJ / (l̂ J_a);
- lateral: shear springs k_s = κGA/l̂ acting on Δu − l̂φ and bending springs k_b = EI/l̂ on Δφ
  give, per unit mass, the 2×2 matrix [[4k_s/m + c, 2k_s l̂/√(mJ_t)], [2k_s l̂/√(mJ_t),
  (k_s l̂² + 4k_b + |N| l̂)/J_t]], whose larger eigenvalue is ω². c = 4|N|/(l̂ m) + k_c is what the
  axial force |N| (largest over the segments) and the wall add: a node pressed δ into the wall
  (Hertz, k l̄ δ^{3/2}) has the radial stiffness 1.5 k √δ l̄ and, along the wall, the curvature
  term k δ^{3/2} l̄ / R; per node mass k_c = (1.5 k √δ + k δ^{3/2}/R)/ρ with δ the deepest
  penetration of the state.

Each entry only grows with the wavenumber, so the alternating mode is the block's highest; the
axial force enters as |N| although compression lowers the lateral frequencies, and the ends'
half masses are not stiffer than the interior (the axial chain with half-mass ends has exactly
4EA/(l̂m)). `tests/test_rod3d_step_limit.py` holds it above a power iteration's largest frequency, and
close to it, for 30–500 segments, with and without the channel, in tension and compression. It costs no
compilation: a concrete model is evaluated in NumPy, a traced one in a few `jnp` operations.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .so3 import skew

__all__ = ["frequency_bound", "power_max_frequency", "step_limit"]


def _traced(*trees) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(trees))


def frequency_bound(model, q=None) -> Float[Array, ""]:
    """ω_max [rad/s] of the rod `model` at the straight or nearly straight state `q` (default:
    straight under its axial preload, resting on the channel bottom), in closed form (module
    docstring): never below the highest frequency of the linearised conservative dynamics there,
    and close to it (`tests/test_rod3d_step_limit.py`)."""
    xp = jnp if _traced(model, q) else np
    f = lambda a: xp.asarray(a, dtype=xp.float64 if xp is np else None)
    rod, n = model.rod, model.n
    l0 = f(rod.L) / n
    m = f(rod.rho) * l0
    J_t = f(model.rotary_scale) * f(rod.rho_v) * l0 * f(rod.I)
    J_a = 2.0 * f(rod.rho_v) * l0 * f(rod.I)
    k_s, k_b = f(model.shear_coefficient) * f(rod.GA) / l0, f(rod.EI) / l0
    k = f(model.contact_stiffness)
    if q is None:
        N = xp.abs(f(model.axial_preload()))
        delta = (f(rod.rho) * f(rod.g) / k) ** (2.0 / 3.0) if model.gravity else 0.0 * k  # `Rod3D.static_sag`
    else:
        x = xp.asarray(q.x)
        N = f(rod.EA) * xp.max(xp.abs(xp.linalg.norm(x[1:] - x[:-1], axis=-1) / l0 - 1.0))
        delta = xp.maximum(xp.max(xp.hypot(x[:, 1], x[:, 2])) - f(rod.R), 0.0)
    delta = delta if model.channel else 0.0 * delta
    k_c = (1.5 * k * xp.sqrt(delta) + k * delta**1.5 / f(rod.R)) / f(rod.rho)
    a = 4.0 * k_s / m + 4.0 * N / (l0 * m) + k_c
    d = (k_s * l0**2 + 4.0 * k_b + N * l0) / J_t
    b2 = 4.0 * k_s**2 * l0**2 / (m * J_t)
    lateral = 0.5 * (a + d) + xp.sqrt(0.25 * (a - d) ** 2 + b2)
    axial, twist = 4.0 * f(rod.EA) / (l0 * m), 4.0 * f(rod.GJ) / (l0 * J_a)
    return xp.sqrt(xp.maximum(xp.maximum(axial, twist), lateral))


def power_max_frequency(model, q, iters: int = 80) -> Float[Array, ""]:
    """ω_max [rad/s] of the linearised conservative dynamics at `q`, measured by power iteration
    on M⁻¹H (Hessian-vector products by forward-over-reverse AD of `model.potential`, on the
    degrees of freedom the ends leave free): the reference for `frequency_bound`. Compiles for
    seconds; jit it for repeated use."""
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


def step_limit(model, q=None) -> float:
    """The explicit step limit 2/ω_max [s] of the rod `model` at `q` (default: straight, under its
    axial preload), ω_max from `frequency_bound`: the stiffest of the axial, shear, bending,
    twist and contact vibrations."""
    return float(2.0 / frequency_bound(model, q))
