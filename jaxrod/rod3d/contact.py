"""The wall friction pass of the 3D rod: contact frames at the contact points, each node's share
of its segments' spin, and the red–black projected impulses (the law's `impulse_2d`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._numerics import safe_norm
from .so3 import skew

__all__ = ["contact_frames", "node_weights", "friction_pass"]


def contact_frames(model, x):
    _, e_r = model.penetration(x)
    t1 = jnp.broadcast_to(jnp.array([1.0, 0.0, 0.0], x.dtype), e_r.shape)
    t2 = jnp.stack([jnp.zeros_like(e_r[:, 0]), -e_r[:, 2], e_r[:, 1]], -1)  # x̂ × e_r
    T = jnp.stack([t1, t2], -2)  # (n1, 2, 3)
    rc = (0.5 * model.rod.d if model.friction_at == "surface" else 0.0) * e_r
    return T, rc

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
    free_n = (~held_n).astype(dtype)
    T, rc = contact_frames(model, x)
    cl, cr = node_weights(model)
    Jinv = 1.0 / model.inertia
    m = model.mass
    Jfree = Jinv[None, :] * (~held_s).astype(dtype)  # held spin components do not turn
    Jlab_inv = jnp.einsum("jba,jb,jbc->jac", Q, Jfree, Q)  # Qᵀ diag(1/J) Q
    pad = jnp.zeros((1, 3, 3), dtype)
    Jl = jnp.concatenate([pad, Jlab_inv], 0)  # segment i−1 of node i
    Jr = jnp.concatenate([Jlab_inv, pad], 0)  # segment i of node i
    Rx = skew(rc)
    K = (free_n[:, :, None] * jnp.eye(3, dtype=dtype)[None] / m[:, None, None]
         - (cl**2)[:, None, None] * Rx @ Jl @ Rx
         - (cr**2)[:, None, None] * Rx @ Jr @ Rx)
    W = jnp.einsum("iab,ibc,idc->iad", T, K, T)
    # a point that nothing can move (a clamped end) takes no impulse
    movable = (W[:, 0, 0] * W[:, 1, 1] - W[:, 0, 1] * W[:, 1, 0]) > 0
    W = jnp.where(movable[:, None, None], W, jnp.eye(2, dtype=dtype)[None])
    mu_s, mu_d = model.rod.mu_s, model.rod.mu_d
    in_contact = (N > 0) & movable
    idx = jnp.arange(model.n + 1)
    bound_s, bound_d = mu_s * N * h, mu_d * N * h
    scale = jnp.maximum(jnp.max(jnp.where(in_contact, bound_s, 0.0)), jnp.finfo(dtype).tiny)

    def apply(v, w, dp):
        """Node and segment velocities after the contact impulses `dp` (n+1, 2)."""
        P = jnp.einsum("iab,ia->ib", T, dp)  # lab impulse on the node
        v = v + free_n * P / m[:, None]
        torque = jnp.cross(rc, P)  # lab torque impulse at the node
        tseg = cr[:-1, None] * torque[:-1] + cl[1:, None] * torque[1:]
        w = w + Jfree * jnp.einsum("jab,jb->ja", Q, tseg)
        return v, w

    # warm start: last pass's forces, within this pass's bounds
    p0 = jnp.where(in_contact[:, None], force * h, 0.0)
    cap = jnp.where(stuck, bound_s, bound_d)
    norm = safe_norm(p0)
    p0 = p0 * jnp.where(norm > cap, cap / jnp.where(norm > 0, norm, 1.0), 1.0)[:, None]  # no 0·∞ in a jvp
    v, w = apply(v, w, p0)

    def sweep(carry):
        v, w, stuck, p_acc, _, k = carry
        change = jnp.zeros((), dtype)
        for colour in (0, 1):
            mine = idx % 2 == colour
            active = in_contact & mine
            wlab = jnp.einsum("jba,jb->ja", Q, w)
            zero = jnp.zeros((1, 3), dtype)
            wbar = cl[:, None] * jnp.concatenate([zero, wlab], 0) + cr[:, None] * jnp.concatenate([wlab, zero], 0)
            u = jnp.einsum("iab,ib->ia", T, v + jnp.cross(wbar, rc))
            u = u - jnp.einsum("iab,ib->ia", W, p_acc)  # without the node's own impulse
            p, sticks = friction.impulse_2d(u, W, jnp.where(stuck, bound_s, bound_d), bound_d)
            p, sticks = jnp.where(active[:, None], p, 0.0), active & sticks
            dp = jnp.where(mine[:, None], p - p_acc, 0.0)
            change = jnp.maximum(change, jnp.max(safe_norm(dp)))
            p_acc = jnp.where(mine[:, None], p, p_acc)
            v, w = apply(v, w, dp)
            stuck = jnp.where(mine, active & sticks, stuck)
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
    force = p_acc / jnp.where(h > 0, h, 1.0)
    return v, w, stuck, force, jnp.where(jnp.any(in_contact), residual, 0.0)
