"""The wall friction pass of the 3D rod: contact frames at the contact points, each node's share
of its segments' spin, and the red–black projected impulses (the law's `impulse_2d`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._numerics import safe_hypot, safe_norm
from . import components as c3
from .energy import _penetration, _shift

__all__ = ["contact_frames", "node_weights", "friction_pass"]


def contact_frames(model, x):
    """The tangent frame of every contact, t₁ = x̂ (axial) and t₂ = x̂ × e_r (lateral, along the
    wall), as (n+1, 2, 3), and the contact point's offset r_c = (d/2) e_r from the centre line
    (zero with `friction_at="axis"`)."""
    _, e_r = model.penetration(x)
    t1 = jnp.broadcast_to(jnp.array([1.0, 0.0, 0.0], x.dtype), e_r.shape)
    t2 = jnp.stack([jnp.zeros_like(e_r[:, 0]), -e_r[:, 2], e_r[:, 1]], -1)  # x̂ × e_r
    T = jnp.stack([t1, t2], -2)  # (n1, 2, 3)
    rc = _arm(model, x.dtype) * e_r
    return T, rc


def _arm(model, dtype):
    return jnp.asarray(0.5 * model.rod.d if model.friction_at == "surface" else 0.0, dtype)


def node_weights(model):
    """c_left[i] (segment i−1) and c_right[i] (segment i): each node's share of its
    adjacent segments' spin and of the friction torque it applies to them."""
    n = model.n
    left = np.r_[0.0, np.ones(n)]
    right = np.r_[np.ones(n), 0.0]
    count = left + right
    return jnp.asarray(left / count), jnp.asarray(right / count)


def friction_pass(model, friction, x, v, Q, w, N, stuck, force, h):
    """The friction impulses of a (half) step `h` [s] under the law `friction`
    ([`jaxrod.Coulomb`][] or [`jaxrod.Tanh`][]): projected Gauss–Seidel sweeps, even nodes then
    odd nodes, started from the impulses `force`·h of the last pass (clipped to this pass's
    bounds), repeated until no impulse changes by more than `model.friction_tol` × the largest
    friction bound, or `model.friction_sweeps` sweeps.

    An impulse p = p₁t₁ + p₂t₂ at node i's contact point moves the node by p/m and, through
    the arm r_c, spins the node's two segments by their shares c of the torque r_c × p. With
    u₁ = r_c × t₁ = −r t₂ and u₂ = r_c × t₂ = r t₁ (r = |r_c|), and gₐ = Q uₐ those arms in a
    segment's material frame, everything is per node and per component: the slip velocity
    t_a·v + Σ_seg c w·gₐ, the tangent inverse mass W_ab = δ_ab/m (free components) + Σ_seg c²
    Σ_k gₐₖ g_bₖ / J_k, and the spin change J⁻¹ c Σₐ pₐ gₐ (written out instead of batches of
    3×3 products, which do not fuse on CPU).

    **Returns:** the new `(v, w, stuck, force, residual)`: `force` the tangential friction force
    of each contact [N], `residual` the largest change of an impulse in the last sweep over the
    largest bound."""
    dtype = x.dtype
    if not model.channel:  # no wall, no contact, no friction
        return v, w, stuck, jnp.zeros_like(force), jnp.zeros((), dtype)
    # a held node still touches the wall: its translation is prescribed (the support takes the
    # friction force) but the friction at its contact point still acts on its segments' spin, so
    # the end of the rod cannot roll freely (without it the interior rolls sideways as one body,
    # the end segments tilting, and a loaded rod buckles through that roll: issue [rod3d])
    held_n, held_s = model.held()
    free_n = c3.unpack((~held_n).astype(dtype))
    _, e_r = _penetration(model, c3.unpack(x))
    r = _arm(model, dtype)
    zero = jnp.zeros_like(e_r[0])
    t1, t2 = (zero + 1.0, zero, zero), (zero, -e_r[2], e_r[1])  # x̂ and x̂ × e_r
    u1, u2 = c3.scale(-r, t2), c3.scale(r, t1)  # r_c × t_a
    cl, cr = node_weights(model)
    Jf = (1.0 / model.inertia)[None, :] * (~held_s).astype(dtype)  # held spin components do not turn
    m = model.mass
    Qr = c3.unpack_matrix(Q)
    # each node's two segments: share c, inverse inertia and the arms gₐ in that segment's frame
    # (zero where there is no segment)
    sides = []
    for side, c in (("left", cl), ("right", cr)):
        Qs = tuple(tuple(_shift(q, side) for q in row) for row in Qr)
        sides.append((side, c, c3.unpack(_shift(Jf, side)), c3.matvec(Qs, u1), c3.matvec(Qs, u2)))
    W11 = free_n[0] / m
    W22 = (free_n[1] * e_r[2] ** 2 + free_n[2] * e_r[1] ** 2) / m
    W12 = jnp.zeros_like(W11)
    for _, c, Js, g1, g2 in sides:
        W11 = W11 + c**2 * c3.dot(Js, (g1[0] * g1[0], g1[1] * g1[1], g1[2] * g1[2]))
        W22 = W22 + c**2 * c3.dot(Js, (g2[0] * g2[0], g2[1] * g2[1], g2[2] * g2[2]))
        W12 = W12 + c**2 * c3.dot(Js, (g1[0] * g2[0], g1[1] * g2[1], g1[2] * g2[2]))
    # a point that nothing can move (a clamped end) takes no impulse
    movable = (W11 * W22 - W12 * W12) > 0
    W11, W22, W12 = jnp.where(movable, W11, 1.0), jnp.where(movable, W22, 1.0), jnp.where(movable, W12, 0.0)
    W = (W11, W12, W22)
    mu_s, mu_d = model.rod.mu_s, model.rod.mu_d
    in_contact = (N > 0) & movable
    idx = jnp.arange(model.n + 1)
    bound_s, bound_d = mu_s * N * h, mu_d * N * h
    scale = jnp.maximum(jnp.max(jnp.where(in_contact, bound_s, 0.0)), jnp.finfo(dtype).tiny)
    fm = tuple(f / m for f in free_n)
    Jc = c3.unpack(Jf)
    (_, cl_, _, g1l, g2l), (_, cr_, _, g1r, g2r) = sides

    def apply(v, w, dp):
        """Node and segment velocities (component tuples) after the contact impulses
        `dp` = (p₁, p₂) per node."""
        p1, p2 = dp
        v = tuple(v[k] + fm[k] * (p1 * t1[k] + p2 * t2[k]) for k in range(3))
        tl = tuple(cl_ * (p1 * g1l[k] + p2 * g2l[k]) for k in range(3))  # on segment i − 1
        tr = tuple(cr_ * (p1 * g1r[k] + p2 * g2r[k]) for k in range(3))  # on segment i
        return v, tuple(w[k] + Jc[k] * (tr[k][:-1] + tl[k][1:]) for k in range(3))

    def slip(v, w):
        """Tangential velocities (u₁, u₂) of the contact points."""
        wl = tuple(_shift(a, "left") for a in w)
        wr = tuple(_shift(a, "right") for a in w)
        return (c3.dot(t1, v) + cl_ * c3.dot(wl, g1l) + cr_ * c3.dot(wr, g1r),
                c3.dot(t2, v) + cl_ * c3.dot(wl, g2l) + cr_ * c3.dot(wr, g2r))

    v, w = c3.unpack(v), c3.unpack(w)
    # warm start: last pass's forces, within this pass's bounds
    p0 = jnp.where(in_contact[:, None], force * h, 0.0)
    cap = jnp.where(stuck, bound_s, bound_d)
    norm = safe_norm(p0)
    p0 = p0 * jnp.where(norm > cap, cap / jnp.where(norm > 0, norm, 1.0), 1.0)[:, None]  # no 0·∞ in a jvp
    p0 = (p0[:, 0], p0[:, 1])
    v, w = apply(v, w, p0)

    def sweep(carry):
        v, w, stuck, p_acc, _, k = carry
        change = jnp.zeros((), dtype)
        for colour in (0, 1):
            mine = idx % 2 == colour
            active = in_contact & mine
            s1, s2 = slip(v, w)
            u = (s1 - (W11 * p_acc[0] + W12 * p_acc[1]), s2 - (W12 * p_acc[0] + W22 * p_acc[1]))  # without own impulse
            p, sticks = friction.impulse_2d(u, W, jnp.where(stuck, bound_s, bound_d), bound_d)
            p = (jnp.where(active, p[0], 0.0), jnp.where(active, p[1], 0.0))
            sticks = active & sticks
            dp = (jnp.where(mine, p[0] - p_acc[0], 0.0), jnp.where(mine, p[1] - p_acc[1], 0.0))
            change = jnp.maximum(change, jnp.max(safe_hypot(*dp)))
            p_acc = (jnp.where(mine, p[0], p_acc[0]), jnp.where(mine, p[1], p_acc[1]))
            v, w = apply(v, w, dp)
            stuck = jnp.where(mine, sticks, stuck)
        return v, w, stuck, p_acc, change / scale, k + 1

    def more(carry):
        k = carry[-1]
        return (k == 0) | ((k < model.friction_sweeps) & (carry[-2] > model.friction_tol))

    def body(carry):
        # a member that has converged keeps its impulses while others of a vmapped batch sweep
        # on, so a batch member equals its single run
        new = sweep(carry)
        done = ~more(carry)
        return jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), carry, new)

    carry = (v, w, stuck, p0, jnp.zeros((), dtype), 0)
    if model.friction_sweeps == 1:  # no loop: reverse-mode differentiable
        carry = sweep(carry)
    else:  # one compiled copy of the sweep, in the loop (compile time)
        carry = jax.lax.while_loop(more, body, carry)
    v, w, stuck, p_acc, residual, _ = carry
    force = jnp.stack(p_acc, -1) / jnp.where(h > 0, h, 1.0)
    return c3.pack(v), c3.pack(w), stuck, force, jnp.where(jnp.any(in_contact), residual, 0.0)
