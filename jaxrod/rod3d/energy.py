"""The 3D rod's energy and the forces it gives: stretch, shear, bend and twist of the discrete
Cosserat rod, gravity and body forces, the dead end load, Hertz–Hunt–Crossley wall contact, and
the node forces and material torques, the exact gradient of that energy written in closed form
(docs/physics.md §7; tests check it against reverse-mode AD of `potential`). Functions of the
model (`jaxrod.rod3d.Rod3D` calls them as methods)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._numerics import computed_once
from . import components as c3

__all__ = ['strains', 'elastic_terms', 'penetration', 'contact_energy', 'external_energy', 'potential', 'kinetic_terms', 'generalized_forces', 'contact_normal', 'forces', 'impulse_work']

E3 = np.array([0.0, 0.0, 1.0])


def strains(model, x, Q):
    """Shear/stretch strains σ (n, 3) and curvatures κ (n−1, 3), material frame."""
    sigma, psi = _strains(model, c3.unpack(x), c3.unpack_matrix(Q))
    return c3.pack(sigma), c3.pack(psi) / model.l0


def axial_force(model, x, Q):
    """Compressive axial force of each segment, −EA σ₃ [N]."""
    return -model.rod.EA * strains(model, x, Q)[0][:, 2]


def _strains(model, X, Qr):
    """σ and ψ = log(Qⱼ₊₁Qⱼᵀ) = l̂κ as component tuples, with the pieces the forces reuse."""
    e = tuple(X[k][1:] - X[k][:-1] for k in range(3))
    Qe = c3.matvec(Qr, e)
    sigma = (Qe[0] / model.l0, Qe[1] / model.l0, Qe[2] / model.l0 - 1.0)
    upper = tuple(tuple(q[1:] for q in row) for row in Qr)
    lower = tuple(tuple(q[:-1] for q in row) for row in Qr)
    return sigma, c3.log_rotation(c3.relative_rotation(upper, lower))


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
    delta, e_r = _penetration(model, c3.unpack(x))
    return delta, c3.pack(e_r)


def _penetration(model, X):
    y, z = X[1], X[2]
    r2 = y * y + z * z
    pos = r2 > 0
    r = jnp.where(pos, jnp.sqrt(jnp.where(pos, r2, 1.0)), 0.0)
    rs = jnp.where(pos, r, 1.0)
    delta, e_r1, e_r2 = computed_once((r - model.rod.R, jnp.where(pos, y / rs, 0.0), jnp.where(pos, z / rs, -1.0)), y)
    return delta, (jnp.zeros_like(r), e_r1, e_r2)


def contact_energy(model, x):
    if not model.channel:
        return jnp.zeros((), x.dtype)
    delta, _ = model.penetration(x)
    pen = jnp.maximum(delta, 0.0)
    return jnp.sum(model.voronoi * model.contact_stiffness * 0.4 * pen**2.5)


def external_energy(model, x):
    """Gravity (zero on the channel bottom, z = −R) and body-force potentials [J]."""
    grav = -jnp.sum(model.mass * (x[:, 2] + model.rod.R)) * model.g_vec[2]
    body = -jnp.sum(model.voronoi[:, None] * x * _body_force(model))
    if model.control == "load":
        body = body + model.end_load * x[-1, 0]
    if model.far_loaded:
        body = body - model.far_load * x[0, 0]
    return grav + body


def _body_force(model):
    """The body force per length at each node (n+1, 3) [N/m]: `body_force` is one 3-vector or one per node."""
    return jnp.broadcast_to(model.body_force, (model.n + 1, 3))


def potential(model, x, Q):
    return sum(model.elastic_terms(x, Q).values()) + model.contact_energy(x) + model.external_energy(x)


def kinetic_terms(model, v, w):
    return dict(
        kinetic=0.5 * jnp.sum(model.mass[:, None] * v**2),
        rotational=0.5 * jnp.sum(model.inertia[None, :] * w**2),
    )


def generalized_forces(model, x, Q):
    """Conservative node forces (n+1, 3) [N] and material torques (n, 3) [N·m]: minus the
    gradient of `potential` with respect to the node positions and to the rotations φ of
    Q → (I − [φ]×) Q, in closed form (see `_conservative`)."""
    return _conservative(model, c3.unpack(x), c3.unpack_matrix(Q))


def _pen_three_halves(delta):
    """max(δ, 0)^{3/2} as δ√δ (a power costs many square roots on the CPU), with a zero (not
    NaN) derivative where there is no penetration."""
    pos = delta > 0
    pen = jnp.where(pos, delta, 0.0)
    return jnp.where(pos, pen * jnp.sqrt(jnp.where(pos, pen, 1.0)), 0.0)


def _conservative(model, X, Qr):
    """Node forces (n+1, 3) and material torques (n, 3) from positions and directors as
    component tuples.

    Stretch and shear: with the material stress n = S σ (S = diag(κGA, κGA, EA)), segment j
    pulls node j + 1 back and node j on by Qⱼᵀ nⱼ, and turns by (Qⱼ eⱼ) × nⱼ. Bend and twist:
    with ψ = log Rⱼ (Rⱼ = Qⱼ₊₁ Qⱼᵀ) and m = Bψ/l̂, rotating Qⱼ₊₁ by φ and Qⱼ by φ' perturbs Rⱼ
    on the left by δ = Rⱼ φ' − φ, so the couple g = J_l(ψ)⁻ᵀ m acts on segment j + 1 and −Rⱼᵀ g
    on segment j. Wall contact pushes along −e_r by k l̄ δ^{3/2}; gravity, body forces and the
    dead end load are constant."""
    rod, l0 = model.rod, model.l0
    dtype = X[0].dtype
    e = tuple(X[k][1:] - X[k][:-1] for k in range(3))
    Qe = c3.matvec(Qr, e)
    kGA = model.shear_coefficient * rod.GA
    stress = (kGA * Qe[0] / l0, kGA * Qe[1] / l0, rod.EA * (Qe[2] / l0 - 1.0))
    # segment values to nodes and joint values to segments as differences of one padded (·, 3)
    # array: shifts by concatenation inside a fused kernel are evaluated element by element
    Fp = jnp.pad(c3.pack(c3.rmatvec(Qr, stress)), ((1, 1), (0, 0)))  # lab, zero beyond the ends
    f = Fp[1:] - Fp[:-1]
    tau = c3.cross(Qe, stress)
    upper = tuple(tuple(q[1:] for q in row) for row in Qr)
    lower = tuple(tuple(q[:-1] for q in row) for row in Qr)
    R = c3.relative_rotation(upper, lower)
    psi, cj = c3.log_rotation(R, with_jacobian=True)
    *psi, cj = computed_once((*psi, cj), R[0][0])  # read by the couple's three components and Rᵀg
    g = c3.left_jacobian_inv_t(psi, (rod.EI * psi[0] / l0, rod.EI * psi[1] / l0, rod.GJ * psi[2] / l0), cj)
    g = computed_once(g, psi[0])  # read by the torques of both segments of a joint
    Rg = c3.rmatvec(R, g)
    tau = (c3.pack(tau) + jnp.pad(c3.pack(g), ((1, 0), (0, 0)))) - jnp.pad(c3.pack(Rg), ((0, 1), (0, 0)))
    if model.channel:
        delta, e_r = _penetration(model, X)
        el = model.voronoi * model.contact_stiffness * _pen_three_halves(delta)
        f = f - el[:, None] * c3.pack(e_r)
    ext = model.mass[:, None] * model.g_vec[None, :] + model.voronoi[:, None] * _body_force(model)
    if model.control == "load":
        ext = ext.at[-1, 0].add(-model.end_load)
    if model.far_loaded:
        ext = ext.at[0, 0].add(model.far_load)
    return f + ext.astype(dtype), tau


def contact_normal(model, x, v):
    """Normal force per node [N] (elastic + Hunt–Crossley, ≥ 0), its damping part [N] and
    the outward radius e_r."""
    N, N_damp, e_r = _contact_normal(model, c3.unpack(x), c3.unpack(v))
    return N, N_damp, c3.pack(e_r)


def _contact_normal(model, X, V):
    delta, e_r = _penetration(model, X)
    if not model.channel:
        z = jnp.zeros_like(delta)
        return z, z, e_r
    el = model.voronoi * model.contact_stiffness * _pen_three_halves(delta)
    total = jnp.maximum(el * (1.0 + model.contact_damping * c3.dot(V, e_r)), 0.0)
    return total, total - el, e_r


def forces(model, x, Q, v):
    """Everything a kick needs at (x, Q) with velocities v: node forces [N] (elastic,
    contact, gravity, body, damping), material torques [N·m], normal forces [N] and the
    non-conservative part of the node forces [N] (contact and viscous damping)."""
    X, V = c3.unpack(x), c3.unpack(v)
    f, tau = _conservative(model, X, c3.unpack_matrix(Q))
    N, N_damp, e_r = _contact_normal(model, X, V)
    cm = model.damping * model.mass
    f_damp = c3.pack(tuple(-N_damp * e_r[k] - cm * V[k] for k in range(3)))
    return f + f_damp, tau, N, f_damp


def impulse_work(model, v_prev, v_trial, v_after, a, h):
    """`(lost, work_in)` over a half step `h`: the energy removed by the friction impulse
    (impulse · mean velocity, the reduced models' midpoint rule) and by damping, per node and
    component and per segment and axis (`(n+1, 3)` and `(n, 3)` arrays [J], whose sum is the
    total: the run accumulates them elementwise and sums at its saves, so a step has no
    reduction), and the work of the pushed end (its support force times its prescribed
    velocity) [J]."""
    mean_v = 0.5 * (v_prev.v + v_after.v)
    lost = (model.mass[:, None] * (v_trial.v - v_after.v) * mean_v - h * a.fd * mean_v,
            model.inertia[None, :] * (v_trial.w - v_after.w) * 0.5 * (v_prev.w + v_after.w))
    if model.control == "displacement":
        work_in = -h * a.f[-1, 0] * v_after.v[-1, 0]
    else:
        work_in = jnp.zeros((), v_prev.v.dtype)
    return lost, work_in
