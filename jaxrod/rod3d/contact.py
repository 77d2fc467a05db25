"""The wall friction pass of the 3D rod: contact frames at the contact points, each node's share
of its segments' spin, and the red–black projected impulses (the law's `impulse_2d`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

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

def friction_pass(model, friction, x, v, Q, w, N, stuck, h):
    """The friction impulses of a (half) step `h` [s] under the law `friction`
    ([`jaxrod.Coulomb`][] or [`jaxrod.Tanh`][]), even nodes then odd nodes.
    Returns the new (v, w, stuck)."""
    if not model.channel:  # no wall, no contact, no friction
        return v, w, stuck
    held, _ = model.held()
    T, rc = contact_frames(model, x)
    cl, cr = node_weights(model)
    Jinv = 1.0 / model.inertia
    m = model.mass
    Jlab_inv = jnp.einsum("jba,b,jbc->jac", Q, Jinv, Q)  # Qᵀ diag(1/J) Q
    pad = jnp.zeros((1, 3, 3), x.dtype)
    Jl = jnp.concatenate([pad, Jlab_inv], 0)  # segment i−1 of node i
    Jr = jnp.concatenate([Jlab_inv, pad], 0)  # segment i of node i
    Rx = skew(rc)
    K = (jnp.eye(3, dtype=x.dtype)[None] / m[:, None, None]
         - (cl**2)[:, None, None] * Rx @ Jl @ Rx
         - (cr**2)[:, None, None] * Rx @ Jr @ Rx)
    W = jnp.einsum("iab,ibc,idc->iad", T, K, T)
    mu_s, mu_d = model.rod.mu_s, model.rod.mu_d
    in_contact = (N > 0) & ~jnp.any(held, -1)
    idx = jnp.arange(model.n + 1)
    p_acc = jnp.zeros((model.n + 1, 2), x.dtype)  # each node's impulse so far (this half step)

    def sweep(carry):
        v, w, stuck, p_acc = carry
        for colour in (0, 1):
            active = in_contact & (idx % 2 == colour)
            wlab = jnp.einsum("jba,jb->ja", Q, w)
            zero = jnp.zeros((1, 3), x.dtype)
            wbar = cl[:, None] * jnp.concatenate([zero, wlab], 0) + cr[:, None] * jnp.concatenate([wlab, zero], 0)
            u = jnp.einsum("iab,ib->ia", T, v + jnp.cross(wbar, rc))
            u = u - jnp.einsum("iab,ib->ia", W, p_acc)  # without the node's own impulse
            bound_s = mu_s * N * h
            bound_d = mu_d * N * h
            p, sticks = friction.impulse_2d(u, W, jnp.where(stuck, bound_s, bound_d), bound_d)
            p, sticks = jnp.where(active[:, None], p, 0.0), active & sticks
            mine = (idx % 2 == colour)[:, None]
            dp = jnp.where(mine, p - p_acc, 0.0)
            p_acc = jnp.where(mine, p, p_acc)
            P = jnp.einsum("iab,ia->ib", T, dp)  # lab impulse on the node
            v = v + P / m[:, None]
            torque = jnp.cross(rc, P)  # lab torque impulse at the node
            tseg = cr[:-1, None] * torque[:-1] + cl[1:, None] * torque[1:]
            w = w + Jinv[None, :] * jnp.einsum("jab,jb->ja", Q, tseg)
            stuck = jnp.where(idx % 2 == colour, active & sticks, stuck)
        return v, w, stuck, p_acc

    carry = (v, w, stuck, p_acc)
    if model.friction_sweeps == 1:
        carry = sweep(carry)
    else:  # a loop, not an unrolled copy per sweep (compile time)
        carry = jax.lax.fori_loop(0, model.friction_sweeps, lambda _, c: sweep(c), carry)
    v, w, stuck, _ = carry
    return v, w, stuck
