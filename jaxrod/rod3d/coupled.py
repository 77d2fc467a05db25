r"""The implicit kick and the wall friction solved together, on the operator the step applies
(Moreau–Jean time stepping): the friction impulses p of a step satisfy the Coulomb law at the
velocities they produce *through the coupled system*,

    (M + βh²H + γh²H_d) Δv = hk (f, τ − ω × Jω) − γ h hk H_d v + Gᵀp,
    u = G (v + Δv):  ‖pᵢ‖ ≤ bᵢ where uᵢ = 0 (stick),  pᵢ = −bᵢ uᵢ/‖uᵢ‖ where uᵢ ≠ 0 (slip),

with bᵢ = hk μ_s Nᵢ for a contact that was stuck and hk μ_d Nᵢ otherwise, and G the contacts'
tangent Jacobian: the slip of node i's contact point is t_a·vᵢ + Σ_seg c r (Q û_a)·w_seg over
its two segments (the arms of `jaxrod.rod3d.contact`). The local friction pass
(`jaxrod.rod3d.contact.friction_pass`) instead sizes each impulse with the contact's own mass
and applies it through M⁻¹ after the kick: near a contact whose neighbours are held by the stiff
springs, it holds forces far above μ_s N, and at large steps the impulses it applies excite the
stiff axial and bending modes that the next kick does not damp.

The velocity form is the convex problem  min_v ½‖v − v*‖²_A + Σ bᵢ ‖Gᵢ v‖. `coupled_kick` solves
it by semismooth Newton on Alart–Curnier's equations (`_newton`, the default: each iteration one
block-tridiagonal system, A + Σ GᵢᵀKᵢGᵢ, since a contact couples node i with segments i − 1 and
i; 2–7 iterations a step on E3's runs) or by ADMM on zᵢ = Gᵢ v (`_admm`: one factorisation, a
solve an iteration, 100 and more iterations there; benchmarks/README.md). The multipliers are the
impulses (p = −λ), warm-started from the last step's forces; stick is exact to `friction_tol`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._banded import block_tridiagonal_factor, block_tridiagonal_factor_solve, block_tridiagonal_solve
from . import components as c3
from .contact import _arm, node_weights
from .energy import _penetration
from .hessian import damping_impulse, kick_system
from .state import Rod3DVelocity

__all__ = ["coupled_kick"]


def _contact_rows(model, q, s):
    """Each node's contact rows in the scaled block coordinates: `a` (n + 1, 2, 6) on its own
    block (translation, spin of its right segment) and `b` (n + 1, 2, 3) on the spin of its left
    segment (block i − 1), and the unscaled rows `T`, `R`, `L` to read a slip from velocities."""
    dtype = q.x.dtype
    _, (_, e1, e2) = _penetration(model, c3.unpack(q.x))
    zero, one = jnp.zeros_like(e1), jnp.ones_like(e1)
    T = jnp.stack([jnp.stack([one, zero, zero], -1), jnp.stack([zero, -e2, e1], -1)], 1)  # t₁ = x̂, t₂ = x̂ × e_r
    Uh = jnp.stack([jnp.stack([zero, e2, -e1], -1), jnp.stack([one, zero, zero], -1)], 1)  # û₁ = e_r × x̂, û₂ = x̂
    r = _arm(model, dtype)
    cl, cr = (c.astype(dtype) for c in node_weights(model))
    pad = jnp.zeros((1, 3, 3), dtype)
    Q_right = jnp.concatenate([q.Q, pad])  # node i's right segment i
    Q_left = jnp.concatenate([pad, q.Q])  # node i's left segment i − 1
    R = (cr * r)[:, None, None] * jnp.einsum("kij,kaj->kai", Q_right, Uh)
    L = (cl * r)[:, None, None] * jnp.einsum("kij,kaj->kai", Q_left, Uh)
    s_left = jnp.concatenate([jnp.zeros((1, 3), dtype), s[:-1, 3:]])
    a = jnp.concatenate([T * s[:, None, :3], R * s[:, None, 3:]], -1)
    b = L * s_left[:, None, :]
    return a, b, T, R, L


def _apply_rows_t(a, b, g):
    """Gᵀg by blocks (n + 1, 6) for per-contact values g (n + 1, 2)."""
    own = jnp.einsum("kai,ka->ki", a, g)
    left = jnp.einsum("kai,ka->ki", b, g)  # onto block i − 1's spin
    return own.at[:-1, 3:].add(left[1:])


def _apply_rows(a, b, y):
    """G y (n + 1, 2) for a block vector y (n + 1, 6)."""
    y_left = jnp.concatenate([jnp.zeros((1, 3), y.dtype), y[:-1, 3:]])
    return jnp.einsum("kai,ki->ka", a, y) + jnp.einsum("kai,ki->ka", b, y_left)


def _shrink(w, radius):
    """The proximal map of radius·‖·‖ at w (n + 1, 2): w (1 − radius/‖w‖)⁺, exactly 0 inside."""
    norm = jnp.sqrt(jnp.sum(w * w, -1))
    k = jnp.where(norm > radius, 1.0 - radius / jnp.where(norm > 0, norm, 1.0), 0.0)
    return w * k[:, None]


def coupled_kick(model, q, v: Rod3DVelocity, a, hk, h, beta, gamma=0.0, max_iter: int = 200, tol=None, relax: float = 1.6,
                 method: str = "newton"):
    """The implicit kick of `hk` [s] in a step of `h` [s] with the wall friction solved on the
    coupled operator (module docstring), by `method` (`"newton"` or `"admm"`) to `tol` (default
    the model's `friction_tol`) in at most `max_iter` iterations (`relax`: the ADMM's
    over-relaxation). **Returns:** `(v_new, v_trial, impulse)`: the velocity after kick and
    friction (its `stuck`, `force` [N], `residual` and `sweeps`: the solve's last relative
    residual and iterations), `v_trial` = v_new − M⁻¹Gᵀp (what `impulse_work` reads the friction
    impulse from) and the damping's impulse by blocks (as `implicit_kick`'s)."""
    dtype = v.v.dtype
    tol = model.friction_tol.astype(dtype) if tol is None else tol
    system = kick_system(model, q, v, a, hk, h, beta, gamma)
    A_D, A_U, rhs, s = system.A_D, system.A_U, system.rhs, system.s

    # the contacts
    ga, gb, T, R, L = _contact_rows(model, q, s)
    w_left = jnp.concatenate([jnp.zeros((1, 3), dtype), v.w])
    w_right = jnp.concatenate([v.w, jnp.zeros((1, 3), dtype)])
    u0 = jnp.einsum("kai,ki->ka", T, v.v) + jnp.einsum("kai,ki->ka", R, w_right) + jnp.einsum("kai,ki->ka", L, w_left)
    reach = jnp.sum(ga * ga, (1, 2)) + jnp.sum(gb * gb, (1, 2))  # tr(G M⁻¹ Gᵀ)
    diagA = jnp.diagonal(A_D, axis1=-2, axis2=-1)
    diag_left = jnp.concatenate([jnp.ones((1, 3), dtype), diagA[:-1, 3:]])
    reach_A = jnp.sum(ga * ga / diagA[:, None, :], (1, 2)) + jnp.sum(gb * gb / diag_left[:, None, :], (1, 2))
    N = a.N
    active = (N > 0) & (reach > 0) & bool(model.channel)
    rho = jnp.where(active, 2.0 / jnp.sqrt(jnp.where(active, reach * reach_A, 1.0)), 0.0)
    bound = hk * jnp.where(v.stuck, model.rod.mu_s, model.rod.mu_d) * N
    bound = jnp.where(active, bound, 0.0)

    safe_rho = jnp.where(active, rho, 1.0)
    lam0 = jnp.where(active[:, None], -v.force * hk, 0.0)
    norm0 = jnp.sqrt(jnp.sum(lam0 * lam0, -1))
    lam0 = lam0 * jnp.where(norm0 > bound, bound / jnp.where(norm0 > 0, norm0, 1.0), 1.0)[:, None]
    scale = jnp.maximum(jnp.max(bound), jnp.finfo(dtype).tiny)
    solve = _newton if method == "newton" else _admm
    y, lam, stuck, k, res = solve(A_D, A_U, rhs, ga, gb, u0, rho, safe_rho, bound, active, lam0, v.stuck, scale,
                                  max_iter, tol, relax)
    step = s * y
    moved = hk > 0
    vn, w = model.constrain(v.v + step[:, :3], v.w + step[:-1, 3:])
    force = -lam / jnp.where(moved, hk, 1.0)
    out = Rod3DVelocity(vn, w, jnp.where(moved, stuck, v.stuck), jnp.where(moved, force, v.force),
                        jnp.where(moved, jnp.where(jnp.any(active), res, 0.0), v.residual),
                        jnp.where(moved, k.astype(dtype), v.sweeps))
    # M⁻¹Gᵀλ = S (G̃ᵀλ): the trial velocity the friction impulse p = −λ took to v_new
    back = s * _apply_rows_t(ga, gb, lam)
    trial = Rod3DVelocity(out.v + back[:, :3], out.w + back[:-1, 3:], out.stuck, out.force, out.residual, out.sweeps)
    return out, trial, damping_impulse(system, gamma, hk, h, step)


def _with_contacts(A_D, A_U, ga, gb, K):
    """The blocks of A + Σ G̃ᵢᵀ Kᵢ G̃ᵢ for per-contact 2×2 matrices K (n + 1, 2, 2)."""
    own = jnp.einsum("kai,kab,kbj->kij", ga, K, ga)
    left = jnp.einsum("kai,kab,kbj->kij", gb, K, gb)
    cross = jnp.einsum("kai,kab,kbj->kij", gb, K, ga)  # (left spin of block i − 1) × block i
    return (A_D + own).at[:-1, 3:, 3:].add(left[1:]), A_U.at[:, 3:, :].add(cross[1:])


def _admm(A_D, A_U, rhs, ga, gb, u0, rho, safe_rho, bound, active, lam0, was_stuck, scale, max_iter, tol, relax):
    """ADMM on zᵢ = G̃ᵢ y + u0ᵢ: one factorisation of A + Σρᵢ G̃ᵢᵀG̃ᵢ, a solve an iteration.
    **Returns:** `(y, λ, stuck, iterations, residual)`."""
    eye = jnp.eye(2, dtype=rhs.dtype)[None]
    A_D, A_U = _with_contacts(A_D, A_U, ga, gb, rho[:, None, None] * eye)
    factor = block_tridiagonal_factor(A_D, A_U)

    def body(carry):
        y, z, lam, k, _ = carry
        g = rho[:, None] * (z - u0) - lam
        y = block_tridiagonal_factor_solve(factor, A_U, rhs + _apply_rows_t(ga, gb, g))
        slip = _apply_rows(ga, gb, y) + u0
        relaxed = relax * slip + (1.0 - relax) * z  # over-relaxation (Boyd et al. §3.4.3)
        z_new = jnp.where(active[:, None], _shrink(relaxed + lam / safe_rho[:, None], bound / safe_rho), 0.0)
        lam = jnp.where(active[:, None], lam + rho[:, None] * (relaxed - z_new), 0.0)
        primal = rho[:, None] * (slip - z_new)
        dual = rho[:, None] * (z_new - z)
        change = jnp.maximum(jnp.max(jnp.sqrt(jnp.sum(primal**2, -1))), jnp.max(jnp.sqrt(jnp.sum(dual**2, -1))))
        return y, z_new, lam, k + 1, change / scale

    def more(carry):
        return (carry[3] == 0) | ((carry[3] < max_iter) & (carry[4] > tol))

    y0 = jnp.zeros_like(rhs)
    z0 = jnp.where((active & ~was_stuck)[:, None], u0, 0.0)  # a sliding contact starts at its slip
    y, z, lam, k, res = jax.lax.while_loop(more, body, (y0, z0, lam0, jnp.array(0), jnp.asarray(jnp.inf, rhs.dtype)))
    return y, lam, active & (jnp.sum(z * z, -1) == 0), k, res


NEWTON_RHO = 0.03
"""`_newton`'s ρ as a fraction of the ADMM's (the geometric mean of a contact's own-mass and
stiffness-diagonal effective masses): at 0.3 and above the stick–slip classification of a kick
at 100× the explicit limit cycles between two active sets; at 0.01–0.1 it converges in 3–5
iterations (tests/test_rod3d_coupled.py's first case)."""

STICK_EPS = 1e-4
"""The stick rows' regularisation in `_newton`: stick is P = (1 − ε) I, so a Newton step takes a
stuck contact's slip down by about a factor ε (the next steps take it to the tolerance)."""


def _newton(A_D, A_U, rhs, ga, gb, u0, rho, safe_rho, bound, active, lam0, was_stuck, scale, max_iter, tol, relax):
    """Semismooth Newton on Alart–Curnier's equations  Ã y + G̃ᵀλ = b̃,  λᵢ = proj_{bᵢ}(λᵢ + ρᵢ uᵢ)
    (uᵢ = G̃ᵢ y + u0ᵢ): at each iterate a contact sticks where ‖σᵢ‖ ≤ bᵢ (σ = λ + ρu, proj' = I,
    regularised to (1 − ε) I) and slips elsewhere (proj' = (bᵢ/‖σᵢ‖)(I − ŝŝᵀ)); eliminating dλ
    leaves (Ã + Σ G̃ᵢᵀ ρᵢ(I − Pᵢ)⁻¹Pᵢ G̃ᵢ) dy = −F_y + Σ G̃ᵢᵀ (I − Pᵢ)⁻¹ F_λ,ᵢ, block tridiagonal: one
    factorisation and solve an iteration. The y equation holds after every step; the iteration
    stops when max ‖λ − proj(σ)‖ ≤ `tol` × the largest bound. **Returns:** as `_admm`."""
    dtype = rhs.dtype
    eye = jnp.eye(2, dtype=dtype)[None]
    r = NEWTON_RHO * rho[:, None]

    def linearised(y, lam):
        u = _apply_rows(ga, gb, y) + u0
        sigma = lam + r * u
        norm = jnp.sqrt(jnp.sum(sigma * sigma, -1))
        stick = active & (norm <= bound)
        shat = sigma / jnp.where(norm > 0, norm, 1.0)[:, None]
        proj = jnp.where(stick[:, None], sigma, bound[:, None] * shat)
        F_lam = jnp.where(active[:, None], lam - proj, lam)
        beta_ = jnp.where(stick, 1.0 - STICK_EPS, bound / jnp.where(norm > 0, norm, 1.0))
        perp = jnp.stack([-shat[:, 1], shat[:, 0]], -1)
        Pm = jnp.where(stick[:, None, None], (1.0 - STICK_EPS) * eye,
                       beta_[:, None, None] * perp[:, :, None] * perp[:, None, :])
        # (I − P)⁻¹: on the stick rows 1/ε; on the slip rows 1 along ŝ, 1/(1 − β) across it
        inv = jnp.where(stick[:, None, None], eye / STICK_EPS,
                        eye + (beta_ / (1.0 - beta_))[:, None, None] * perp[:, :, None] * perp[:, None, :])
        inv = jnp.where(active[:, None, None], inv, eye)
        Pm = jnp.where(active[:, None, None], Pm, 0.0)
        return u, stick, F_lam, Pm, inv

    def residual(F_lam):
        return jnp.max(jnp.sqrt(jnp.sum(F_lam * F_lam, -1))) / scale

    def body(carry):
        y, lam, k, _, lin = carry
        _, _, F_lam, Pm, inv = lin
        K = r[:, :, None] * jnp.einsum("kab,kbc->kac", inv, Pm)
        AD, AU = _with_contacts(A_D, A_U, ga, gb, K)
        # the y equation holds at every iterate (the start solves it, each step keeps it): F_y = 0
        g = jnp.einsum("kab,kb->ka", inv, F_lam)
        dy = block_tridiagonal_solve(AD, AU, _apply_rows_t(ga, gb, g))  # one matrix, one right-hand side
        dlam = jnp.einsum("kab,kb->ka", inv, r * jnp.einsum("kab,kb->ka", Pm, _apply_rows(ga, gb, dy)) - F_lam)
        y, lam = y + dy, jnp.where(active[:, None], lam + dlam, 0.0)
        lin = linearised(y, lam)
        return y, lam, k + 1, residual(lin[2]), lin

    def more(carry):
        return (carry[2] == 0) | ((carry[2] < max_iter) & (carry[3] > tol))

    # the start: λ from the last step, y solving its y equation
    y0 = block_tridiagonal_solve(A_D, A_U, rhs - _apply_rows_t(ga, gb, lam0))
    lin0 = linearised(y0, lam0)
    y, lam, k, res, lin = jax.lax.while_loop(more, body, (y0, lam0, jnp.array(0), residual(lin0[2]), lin0))
    return y, lam, lin[1], k, res
