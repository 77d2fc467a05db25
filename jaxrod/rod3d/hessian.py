r"""The 3D rod's stiffness: the Hessian of its potential in the coordinates of a step, block
tridiagonal, and the implicit kick that solves with it.

**Coordinates.** A step moves node k by h vₖ and turns segment k by φₖ = h ωₖ (material frame,
Q → exp(−[φ]×) Q, `Rod3D.drift`). Ordered as blocks (xₖ, φₖ), k = 0 … n (the last block's φ a
placeholder with unit mass and no stiffness), the Hessian H of the potential is block
tridiagonal with 6×6 blocks: the stretch and shear of segment k couple xₖ, φₖ and xₖ₊₁; the
bend and twist of joint k couple φₖ and φₖ₊₁; the Hertz wall is a 3×3 block per node; gravity,
body forces and dead loads are linear and add nothing. Every block is in closed form
(`hessian_blocks`); `hessian_blocks_ad`, forward-over-reverse AD of each element's energy (the
same energies as `jaxrod.rod3d.energy`, written per element), is the tests' reference.

**The implicit kick** (`implicit_kick`) is the kick of Newmark's average-acceleration scheme
written as a leapfrog: with Δv = v_{n+½} − v_{n−½},

    (M + β h² H(qₙ)) Δv = h F(qₙ),     q_{n+1} = qₙ + h v_{n+½},

which for a linear system is x_{n+1} − 2xₙ + x_{n−1} = −h² M⁻¹K (β x_{n+1} + (1 − 2β) xₙ + β x_{n−1}):
β = 0 is the explicit leapfrog, β = ¼ the trapezoidal rule, unconditionally stable and
without numerical dissipation (every mode keeps its amplitude; its frequency is lowered, by
(ωh)²/12 relative for ωh ≪ 1, and the modes far above 1/h alias to ≈ π/h). The half kicks
(the first step, the velocity at a save) are half of Δv: (h/2) (M + β h² H)⁻¹ F with the full
step's matrix. With the numerical damping γ (stiffness-proportional, implicit), on the shear,
bending and twist strains (H_d: the Hessian of their energies, `hessian_blocks(..., damped=True)`;
the kick assembles β H + γ H_d in one pass, every piece being linear in the stiffnesses):

    (M + β h² H + γ h² H_d) Δv = h F(qₙ) − γ h² H_d v_{n−½},

a damping ratio γhω/2 in a mode of frequency ω: the stiff shear and twist modes and the bending
modes near the segment scale, which ωh ≫ 1 aliases and the friction pass excites at every
stick–slip event, are damped within a few steps. Stretch and the wall are not damped: damping
the whole H moved the lock-up scene's entry force (stretch: the axial vibrations of stick–slip;
the steady slide's force comes through the axial springs), and leaving bending out as well moved
E3's v₀* at 500 segments (its segment-scale bending modes alias): docs/rod3d.md, "The implicit
step", gives both measurements. The gyroscopic couple ω × Jω, contact and viscous damping stay explicit. Held
degrees of freedom are taken out of the system (their rows and columns), and the friction pass
follows the kick as in the explicit scheme.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._banded import block_tridiagonal_solve
from . import components as c3
from .energy import _penetration
from .so3 import skew
from .state import Rod3DVelocity, held_pattern

__all__ = ["IMPLICIT_DT", "KickSystem", "damping_impulse", "damping_loss", "hessian_blocks", "hessian_blocks_ad",
           "implicit_kick", "kick_system"]

IMPLICIT_DT = 5e-5
"""The implicit leapfrog's default step for the 3D rod [s] (`Rod3D.implicit_step`): set by
accuracy, not stability. E3's v₀* at 500 segments moves with the step at first order (the friction
pass sees each contact's own mass, not the stiffness that couples it within the step); this is the
largest step measured to keep it within 1 % of the explicit scheme's at ΔF = 5 and 20 N
(docs/rod3d.md, "The implicit step"; benchmarks/results/rod3d_implicit_vstar.csv)."""

_E3 = np.array([0.0, 0.0, 1.0])  # NumPy: no JAX computation at import (jax.distributed needs that)


def _turned(p, Q):
    """exp(−[p]×) Q to second order in p (all a Hessian at p = 0 reads)."""
    K = skew(p)
    return Q - K @ Q + 0.5 * K @ (K @ Q)


def _segment_energy(z, Q, kGA, EA, l0):
    """Stretch and shear energy of one segment [J] as a function of z = (x_a, φ, x_b)."""
    Qp = _turned(z[3:6], Q)
    s = Qp @ (z[6:9] - z[0:3]) / l0 - jnp.asarray(_E3, z.dtype)
    return 0.5 * l0 * (kGA * (s[0] ** 2 + s[1] ** 2) + EA * s[2] ** 2)


def _joint_energy(z, Qa, Qb, EI, GJ, l0):
    """Bend and twist energy of one joint [J] as a function of z = (φ_a, φ_b)."""
    R = _turned(z[3:6], Qb) @ _turned(z[0:3], Qa).T
    psi = c3.log_rotation(c3.unpack_matrix(R))
    return 0.5 * (EI * (psi[0] ** 2 + psi[1] ** 2) + GJ * psi[2] ** 2) / l0


def _wall_blocks(model, x):
    """The Hertz wall's Hessian per node (n + 1, 3, 3) [N/m]: k l̄ (3/2 √δ e_r e_rᵀ + δ^{3/2}/r
    (P − e_r e_rᵀ)), P the projector on the channel's cross-section, where δ = r − R > 0."""
    delta, (_, e1, e2) = _penetration(model, c3.unpack(x))
    pos = delta > 0
    pen = jnp.where(pos, delta, 0.0)
    root = jnp.sqrt(pen)
    r = model.rod.R + pen
    kl = model.voronoi * model.contact_stiffness
    radial = jnp.where(pos, 1.5 * kl * root, 0.0)
    hoop = jnp.where(pos, kl * pen * root / r, 0.0)
    e = jnp.stack([jnp.zeros_like(e1), e1, e2], -1)
    P = jnp.diag(jnp.array([0.0, 1.0, 1.0], x.dtype))
    ee = e[:, :, None] * e[:, None, :]
    return radial[:, None, None] * ee + hoop[:, None, None] * (P[None] - ee)


def _sym_products(P, W, Q):
    """Σₖ Wₖ P[k][a] Q[k][b] for matrices as rows of components: entry (a, b) as a tuple."""
    return tuple(tuple(sum(W[k] * P[k][a] * Q[k][b] for k in range(3)) for b in range(3)) for a in range(3))


def _skew(u):
    z = jnp.zeros_like(u[0])
    return ((z, -u[2], u[1]), (u[2], z, -u[0]), (-u[1], u[0], z))


def _pad(a, front: int, back: int):
    """A component array padded with zeros along its first axis."""
    return jnp.pad(a, (front, back))


ALL, DAMPED = (1.0, 1.0, 1.0, 1.0), (0.0, 1.0, 1.0, 1.0)  # weights of (stretch, shear, bend, twist)


def element_blocks(model, x, Q, weights=ALL):
    """The stiffness's pieces per segment and joint, as tuples of component arrays (`hessian_blocks`
    assembles them): Hee (n) [N/m], Hep (n) [N], Hpp (n) [N·m], and for the joints (n − 1) RᵀKR,
    K and KR [N·m]. Each piece is linear in the stiffnesses, so `weights` (of stretch, shear,
    bend and twist: `ALL`, or `DAMPED`: shear, bend and twist) gives any combination of the
    energies' Hessians in one pass."""
    rod, l0 = model.rod, model.l0
    X = c3.unpack(x)
    Qr = c3.unpack_matrix(Q)
    stretch, shear, bend, twist = weights
    kGA = shear * model.shear_coefficient * rod.GA
    S = (kGA, kGA, stretch * rod.EA)
    B = (bend * rod.EI, bend * rod.EI, twist * rod.GJ)
    e = tuple(X[k][1:] - X[k][:-1] for k in range(3))
    u = c3.matvec(Qr, e)
    nv = (S[0] * u[0] / l0, S[1] * u[1] / l0, S[2] * (u[2] / l0 - 1.0))
    Hee = _sym_products(Qr, tuple(Sk / l0 for Sk in S), Qr)
    ux, nx = _skew(u), _skew(nv)
    M = tuple(tuple(S[a] * ux[a][b] / l0 - nx[a][b] for b in range(3)) for a in range(3))
    Hep = tuple(tuple(sum(Qr[a][c] * M[a][b] for a in range(3)) for b in range(3)) for c in range(3))
    nu = c3.dot(nv, u)
    Hpp = tuple(tuple(sum(S[k] * ux[k][a] * ux[k][b] for k in range(3)) / l0 + 0.5 * (nv[a] * u[b] + u[a] * nv[b])
                      - (nu if a == b else 0.0) for b in range(3)) for a in range(3))
    upper = tuple(tuple(q[1:] for q in row) for row in Qr)
    lower = tuple(tuple(q[:-1] for q in row) for row in Qr)
    R = c3.relative_rotation(upper, lower)
    psi, cj = c3.log_rotation(R, with_jacobian=True)
    pp = c3.dot(psi, psi)
    px = _skew(psi)
    A = tuple(tuple((1.0 if a == b else 0.0) - 0.5 * px[a][b] + cj * (psi[a] * psi[b] - (pp if a == b else 0.0))
                    for b in range(3)) for a in range(3))
    K = _sym_products(A, tuple(Bk / l0 for Bk in B), A)
    KR = tuple(tuple(sum(K[a][k] * R[k][b] for k in range(3)) for b in range(3)) for a in range(3))
    RKR = tuple(tuple(sum(R[k][a] * KR[k][b] for k in range(3)) for b in range(3)) for a in range(3))
    return Hee, Hep, Hpp, RKR, K, KR


def _wall_components(model, x):
    """The Hertz wall's Hessian per node as components (yy, yz, zz) (`_wall_blocks`)."""
    delta, (_, e1, e2) = _penetration(model, c3.unpack(x))
    pos = delta > 0
    pen = jnp.where(pos, delta, 0.0)
    root = jnp.sqrt(pen)
    kl = model.voronoi * model.contact_stiffness
    radial = jnp.where(pos, 1.5 * kl * root, 0.0)
    hoop = jnp.where(pos, kl * pen * root / (model.rod.R + pen), 0.0)
    return radial * e1 * e1 + hoop * (1.0 - e1 * e1), (radial - hoop) * e1 * e2, radial * e2 * e2 + hoop * (1.0 - e2 * e2)


def hessian_blocks(model, x, Q, damped: bool = False):
    """The stiffness at (x, Q) in the step's coordinates (module docstring): diagonal blocks D
    (n + 1, 6, 6) and blocks above the diagonal U (n, 6, 6), each ordered (x, y, z, φ₁, φ₂, φ₃)
    [N/m, N, N·m], in closed form.

    Stretch and shear (exact): with u = Q e the segment vector in the material frame, σ = u/l̂ − e₃,
    n = Sσ (S = diag(κGA, κGA, EA)): ∂²/∂e² = QᵀSQ/l̂, ∂²/∂e∂φ = Qᵀ(S[u]×/l̂ − [n]×), ∂²/∂φ² =
    [u]×ᵀS[u]×/l̂ + ½(nuᵀ + unᵀ) − (n·u) I. Bend and twist (Gauss–Newton): ψ = log(Qₖ₊₁Qₖᵀ) moves
    by A(Rφₖ − φₖ₊₁) with A = J_l(ψ)⁻¹, so the blocks are K = AᵀBA/l̂ (B = diag(EI, EI, GJ)) on
    φₖ₊₁, RᵀKR on φₖ and −RᵀK between them; the terms of the couple's size that it leaves out
    are |ψ| (the turn of one joint) relative to these. The Hertz wall: `_wall_blocks`. Checked
    against forward-over-reverse AD of the potential (`hessian_blocks_ad`). Computed on
    component arrays (one per entry, as the forces are: `jaxrod.rod3d.components`) and stacked
    once. `damped`: the Hessian of the shear, bend and twist energies alone (`DAMPED`)."""
    return _stacked(*_assembled(model, x, Q, DAMPED if damped else ALL, 0.0 if damped else 1.0))


def _assembled(model, x, Q, weights=ALL, wall_weight=1.0):
    """The entries of D (n + 1 blocks) and U (n blocks) as 6×6 tuples of component arrays, of the
    energies weighted by `weights` (`element_blocks`) and the wall by `wall_weight`."""
    Hee, Hep, Hpp, RKR, K, KR = element_blocks(model, x, Q, weights)
    zn1 = jnp.zeros_like(x[:, 0])
    wall = _wall_components(model, x) if model.channel and wall_weight else (zn1, zn1, zn1)
    wall = tuple(wall_weight * w for w in wall)
    W = ((zn1, zn1, zn1), (zn1, wall[0], wall[1]), (zn1, wall[1], wall[2]))
    D = [[None] * 6 for _ in range(6)]
    U = [[None] * 6 for _ in range(6)]
    zn = jnp.zeros_like(Hee[0][0])
    for a in range(3):
        for b in range(3):
            D[a][b] = _pad(Hee[a][b], 1, 0) + _pad(Hee[a][b], 0, 1) + W[a][b]
            D[a][3 + b] = _pad(-Hep[a][b], 0, 1)
            D[3 + b][a] = D[a][3 + b]
            D[3 + a][3 + b] = _pad(Hpp[a][b], 0, 1) + _pad(RKR[a][b], 0, 2) + _pad(K[a][b], 1, 1)
            U[a][b] = -Hee[a][b]
            U[a][3 + b] = zn
            U[3 + b][a] = Hep[a][b]
            U[3 + a][3 + b] = _pad(-KR[b][a], 0, 1)
    return D, U


def hessian_blocks_ad(model, x, Q, damped: bool = False):
    """The exact Hessian of the potential in the blocks of `hessian_blocks`, by forward-over-
    reverse AD of each element's energy (the bend and twist terms that the Gauss–Newton blocks
    leave out included): the reference the tests hold `hessian_blocks` to; several times slower.
    `damped`: of the energies `DAMPED` weights (no stretch, no wall)."""
    rod, n, l0 = model.rod, model.n, model.l0
    dtype = x.dtype
    stretch, shear, bend, twist = DAMPED if damped else ALL
    kGA = shear * model.shear_coefficient * rod.GA
    EA, EI, GJ = stretch * rod.EA, bend * rod.EI, twist * rod.GJ
    zero3 = jnp.zeros((n, 3), dtype)
    zs = jnp.concatenate([x[:-1], zero3, x[1:]], -1)
    Hs = jax.vmap(jax.hessian(_segment_energy), in_axes=(0, 0, None, None, None))(zs, Q, kGA, EA, l0)
    zj = jnp.zeros((n - 1, 6), dtype)
    Hb = jax.vmap(jax.hessian(_joint_energy), in_axes=(0, 0, 0, None, None, None))(zj, Q[:-1], Q[1:], EI, GJ, l0)
    D = jnp.zeros((n + 1, 6, 6), dtype)
    D = D.at[:-1, :6, :6].add(Hs[:, :6, :6])
    D = D.at[1:, :3, :3].add(Hs[:, 6:, 6:])
    D = D.at[:-2, 3:, 3:].add(Hb[:, :3, :3])
    D = D.at[1:-1, 3:, 3:].add(Hb[:, 3:, 3:])
    U = jnp.zeros((n, 6, 6), dtype)
    U = U.at[:, :6, :3].add(Hs[:, :6, 6:])
    U = U.at[:-1, 3:, 3:].add(Hb[:, :3, 3:])
    if model.channel and not damped:
        D = D.at[:, :3, :3].add(_wall_blocks(model, x))
    return D, U


def _stacked(D, U):
    """The 6×6 tuples of component arrays of `_assembled` as arrays (n + 1, 6, 6) and (n, 6, 6)."""
    return (jnp.stack([jnp.stack(row, -1) for row in D], -2), jnp.stack([jnp.stack(row, -1) for row in U], -2))


def _component_matvec(D, U, x):
    """A x (n + 1, 6) for the block-tridiagonal A given as 6×6 tuples of component arrays (`_assembled`),
    without stacking them."""
    cols = [x[:, b] for b in range(6)]
    out = []
    for a in range(6):
        own = sum(D[a][b] * cols[b] for b in range(6))
        up = sum(U[a][b] * cols[b][1:] for b in range(6))  # block (k, k + 1)
        down = sum(U[b][a] * cols[b][:-1] for b in range(6))  # block (k + 1, k) = U_kᵀ
        out.append(own + jnp.pad(up, (0, 1)) + jnp.pad(down, (1, 0)))
    return jnp.stack(out, -1)


def _blocks_of(u: Rod3DVelocity):
    """A velocity by blocks (n + 1, 6): (vₖ, wₖ), the last block's spin a zero placeholder."""
    return jnp.concatenate([u.v, jnp.concatenate([u.w, jnp.zeros((1, 3), u.w.dtype)])], -1)


def _block_masses(model, dtype):
    """The diagonal of the mass matrix per block (n + 1, 6) [kg, kg·m²] (1 for the placeholder)."""
    m = jnp.broadcast_to(model.mass.astype(dtype)[:, None], (model.n + 1, 3))
    J = jnp.broadcast_to(model.inertia.astype(dtype)[None, :], (model.n, 3))
    return jnp.concatenate([m, jnp.concatenate([J, jnp.ones((1, 3), dtype)])], -1)


def _free(model, dtype):
    """1 where a block's unknown is free, 0 where it is held or a placeholder (n + 1, 6)."""
    held_n, held_s = held_pattern(model)
    free_s = jnp.concatenate([jnp.asarray(~held_s, dtype), jnp.zeros((1, 3), dtype)])
    return jnp.concatenate([jnp.asarray(~held_n, dtype), free_s], -1)


class KickSystem(NamedTuple):
    """Newmark's system of one kick in units scaled by M^{−½} (`kick_system`): the blocks `A_D`,
    `A_U` of I + h² S(βH + γH_d)S, the right-hand side `rhs`, the scaling `s` (M^{−½} on the free
    unknowns, 0 elsewhere), the carried velocity by blocks `vel` (0 where held) and the damped
    stiffness `Hd` (`None` with γ = 0)."""

    A_D: Array
    A_U: Array
    rhs: Array
    s: Array
    vel: Array
    Hd: tuple | None


def kick_system(model, q, v: Rod3DVelocity, a, hk, h, beta, gamma=0.0) -> KickSystem:
    """The system of the kick of `hk` [s] in a step of `h` [s] (module docstring):
    (M + β h² H(q) + γ h² H_d(q)) Δ = hk (f, τ − ω × Jω) − γ h hk H_d v on the free degrees of
    freedom (H_d: shear, bend and twist), scaled by M^{−½} (Δ = s·y for the solution y)."""
    dtype = v.v.dtype
    # β H + γ H_d in one pass (each piece is linear in the stiffnesses), H_d for the damping force
    D, U = _stacked(*_assembled(model, q.x, q.Q, tuple(beta + gamma * d for d in DAMPED), beta))
    free = _free(model, dtype)
    s = free / jnp.sqrt(_block_masses(model, dtype))  # M^{-1/2} on the free unknowns, 0 elsewhere
    Ds = s[:, :, None] * D * s[:, None, :]
    Us = s[:-1, :, None] * U * s[1:, None, :]
    c = h * h
    gyro = c3.pack(c3.gyroscopic(c3.unpack(model.inertia), c3.unpack(v.w)))
    torque = jnp.concatenate([a.tau - gyro, jnp.zeros((1, 3), dtype)])
    rhs = hk * s * jnp.concatenate([a.f, torque], -1)
    A_D, A_U = c * Ds + jnp.eye(6, dtype=dtype)[None], c * Us
    vel = jnp.where(s > 0, _blocks_of(v), 0.0)
    Hd = None
    if gamma:  # the damping γ h H_d v of the shear, bend and twist strains, implicit (its matrix is in A)
        Hd = _assembled(model, q.x, q.Q, DAMPED, 0.0)
        rhs = rhs - gamma * h * hk * s * _component_matvec(*Hd, vel)
    return KickSystem(A_D, A_U, rhs, s, vel, Hd)


def damping_impulse(system: KickSystem, gamma, hk, h, step):
    """The damping's impulse P = −γ h H_d (hk v + h Δ) by blocks (n + 1, 6) [N·s, N·m·s] of a kick
    whose change is `step` (`damping_loss`; zeros with γ = 0)."""
    if not gamma:
        return jnp.zeros_like(system.vel)
    return jnp.where(system.s > 0, -gamma * h * _component_matvec(*system.Hd, hk * system.vel + h * step), 0.0)


def implicit_kick(model, q, v: Rod3DVelocity, a, hk, h, beta, gamma=0.0, with_impulse: bool = False):
    """The kick of `hk` [s] of the implicit leapfrog of step `h` [s] (module docstring):
    Δ = (M + β h² H(q) + γ h² H_d(q))⁻¹ (hk (f, τ − ω × Jω) − γ h hk H_d v) on the free degrees of
    freedom (`kick_system`). Held degrees of freedom keep their
    prescribed values. A matrix that is not positive definite (a step far past what the
    compressed rod allows) gives a non-finite state, which the run reports. With `with_impulse`,
    also the damping's impulse (`damping_impulse`)."""
    system = kick_system(model, q, v, a, hk, h, beta, gamma)
    step = system.s * block_tridiagonal_solve(system.A_D, system.A_U, system.rhs)
    vn, w = model.constrain(v.v + step[:, :3], v.w + step[:-1, 3:])
    out = Rod3DVelocity(vn, w, v.stuck, v.force, v.residual, v.sweeps)
    if not with_impulse:
        return out
    return out, damping_impulse(system, gamma, hk, h, step)


def damping_loss(model, v_prev: Rod3DVelocity, v_after: Rod3DVelocity, impulse):
    """The energy the implicit kick's numerical damping removes: its impulse P (`implicit_kick`
    with `with_impulse`: −γ h H_d (hk v_{n−½} + h Δv) on the free degrees of freedom, H_d the shear,
    bend and twist stiffness) times the mean velocity ½(v_{n−½} + v_{n+½}), per node and component
    and per segment and axis (`(n+1, 3)` and `(n, 3)` [J], as `energy.impulse_work`'s `lost`)."""
    lost = -impulse * 0.5 * (_blocks_of(v_prev) + _blocks_of(v_after))
    return lost[:, :3], lost[:-1, 3:]
