"""The 3D rod's energy and the forces it gives: stretch, shear, bend and twist of the discrete
Cosserat rod, gravity and body forces, the dead end load, Hertz–Hunt–Crossley wall contact, and
forces and material torques as one reverse-mode gradient (docs/physics.md §7). Functions of the
model (`jaxrod.rod3d.Rod3D` calls them as methods)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._numerics import safe_norm
from .so3 import log_so3, skew

__all__ = ['strains', 'elastic_terms', 'penetration', 'contact_energy', 'external_energy', 'potential', 'kinetic_terms', 'generalized_forces', 'contact_normal', 'forces']

E3 = np.array([0.0, 0.0, 1.0])


def strains(model, x, Q):
    """Shear/stretch strains σ (n, 3) and curvatures κ (n−1, 3), material frame."""
    e = x[1:] - x[:-1]
    sigma = jnp.einsum("jab,jb->ja", Q, e) / model.l0 - jnp.asarray(E3, e.dtype)[None, :]
    R = jnp.einsum("jab,jcb->jac", Q[1:], Q[:-1])  # Qᵢ Q_{i−1}ᵀ
    kappa = log_so3(R) / model.l0
    return sigma, kappa


def elastic_terms(model, x, Q) -> dict[str, Float[Array, ""]]:
    rod = model.rod
    sigma, kappa = model.strains(x, Q)
    kGA = model.shear_coefficient * rod.GA
    l0 = model.l0
    return dict(
        stretch=0.5 * l0 * rod.EA * jnp.sum(sigma[:, 2] ** 2),
        shear=0.5 * l0 * kGA * jnp.sum(sigma[:, :2] ** 2),
        bend=0.5 * l0 * rod.EI * jnp.sum(kappa[:, :2] ** 2),
        twist=0.5 * l0 * rod.GJ * jnp.sum(kappa[:, 2] ** 2),
    )


def penetration(model, x) -> tuple[Float[Array, " n1"], Float[Array, "n1 3"]]:
    """Penetration δ = r − R of each node beyond the clearance (negative: a gap) and the
    outward radial unit e_r."""
    yz = x[:, 1:]
    r = safe_norm(yz)
    rs = jnp.where(r > 0, r, 1.0)
    down = jnp.broadcast_to(jnp.array([0.0, -1.0], x.dtype), yz.shape)
    e_r = jnp.concatenate([jnp.zeros_like(r)[:, None], jnp.where(r[:, None] > 0, yz / rs[:, None], down)], -1)
    return r - model.rod.R, e_r


def contact_energy(model, x):
    if not model.channel:
        return jnp.zeros((), x.dtype)
    delta, _ = model.penetration(x)
    pen = jnp.maximum(delta, 0.0)
    return jnp.sum(model.voronoi * model.contact_stiffness * 0.4 * pen**2.5)


def external_energy(model, x):
    """Gravity (zero on the channel bottom, z = −R) and body-force potentials [J]."""
    grav = -jnp.sum(model.mass * (x[:, 2] + model.rod.R)) * model.g_vec[2]
    body = -jnp.sum(model.voronoi * (x @ model.body_force))
    if model.control == "load":
        body = body + model.end_load * x[-1, 0]
    return grav + body


def potential(model, x, Q):
    return sum(model.elastic_terms(x, Q).values()) + model.contact_energy(x) + model.external_energy(x)


def kinetic_terms(model, v, w):
    return dict(
        kinetic=0.5 * jnp.sum(model.mass[:, None] * v**2),
        rotational=0.5 * jnp.sum(model.inertia[None, :] * w**2),
    )


def generalized_forces(model, x, Q):
    """Conservative node forces (n+1, 3) [N] and material torques (n, 3) [N·m]."""

    def U(x, phi):
        Qp = Q - jnp.einsum("jab,jbc->jac", skew(phi), Q)
        return model.potential(x, Qp)

    gx, gphi = jax.grad(U, argnums=(0, 1))(x, jnp.zeros((model.n, 3), x.dtype))
    return -gx, -gphi


def contact_normal(model, x, v):
    """Normal force per node [N] (elastic + Hunt–Crossley, ≥ 0), its damping part [N] and
    the outward radius e_r."""
    delta, e_r = model.penetration(x)
    if not model.channel:
        z = jnp.zeros_like(delta)
        return z, z, e_r
    pen = jnp.maximum(delta, 0.0)
    el = model.voronoi * model.contact_stiffness * pen**1.5
    ddot = jnp.sum(v * e_r, -1)
    total = jnp.maximum(el * (1.0 + model.contact_damping * ddot), 0.0)
    return total, total - el, e_r


def forces(model, x, Q, v):
    """Everything a kick needs at (x, Q) with velocities v: node forces [N] (elastic,
    contact, gravity, body, damping), material torques [N·m], normal forces [N] and the
    non-conservative part of the node forces [N] (contact and viscous damping)."""
    fx, tau = model.generalized_forces(x, Q)
    N, N_damp, e_r = model.contact_normal(x, v)
    f_damp = -N_damp[:, None] * e_r - model.damping * model.mass[:, None] * v
    return fx + f_damp, tau, N, f_damp
