"""The wall friction pass of the 3D rod: the contact points' tangent frames and inverse masses,
each node's share of its segments' spin (`friction_table`, once per position), and the
red–black projected impulses (the law's `impulse_2d`, `friction_pass`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._numerics import computed_once, safe_hypot
from . import components as c3
from .energy import _penetration

__all__ = ["node_weights", "FIELDS", "friction_table", "friction_pass"]

# the friction pass's fields of each contact, rows of `friction_table` (components k = 0, 1, 2)
FIELDS = (("cl", "cr", "W11", "W12", "W22", "bound_s", "bound_d", "active")
          + tuple(f"{name}{k}" for name in ("t2", "fm", "g1l", "g2l", "g1r", "g2r", "J") for k in range(3)))


def _arm(model, dtype):
    """|r_c|: the contact point's distance from the centre line (d/2, or 0 with friction at the
    axis)."""
    return jnp.asarray(0.5 * model.rod.d if model.friction_at == "surface" else 0.0, dtype)


def node_weights(model):
    """c_left[i] (segment i−1) and c_right[i] (segment i): each node's share of its
    adjacent segments' spin and of the friction torque it applies to them."""
    n = model.n
    left = np.r_[0.0, np.ones(n)]
    right = np.r_[np.ones(n), 0.0]
    count = left + right
    return jnp.asarray(left / count), jnp.asarray(right / count)


def _shift(a, side):
    """`a` padded with one zero at the start ("left": entry i is a[i − 1]) or at the end
    ("right": entry i is a[i]): segment values seen from the nodes, joint values from the
    segments."""
    zero = jnp.zeros((1,) + a.shape[1:], a.dtype)
    return jnp.concatenate([zero, a]) if side == "left" else jnp.concatenate([a, zero])


def colours(n: int) -> int:
    """M = ⌈(n + 2)/2⌉: the entries of each colour of the red–black split of n + 1 nodes."""
    return (n + 2) // 2


def friction_table(model, x, Q, N):
    """The fields of the friction pass at the position (x, Q) under the normal forces `N` [N]:
    for each contact, the tangent direction t₂ = x̂ × e_r, the arms gₐ of its impulse in its two
    segments' frames, the shares c of their spin, the tangent inverse mass W [1/kg], the
    friction bounds per unit time μ_s N and μ_d N [N] and whether it is active (N > 0 and
    movable). Every pass at a position uses them (projected leapfrog: the one pass of the next
    step and the pass of a save; projected Verlet: the second pass of a step and the first of the
    next), so `Rod3D.accelerations` computes this once per position and the forces carry it. An
    array (len(FIELDS), M, 2): field, entry k, colour c for node 2k + c (padded nodes inert).
    The pass itself is `friction_pass`."""
    dtype = x.dtype
    M = colours(model.n)
    if not model.channel:  # no wall, no contact: an inert table
        return jnp.zeros((len(FIELDS), M, 2), dtype)
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
        sides.append((c, c3.unpack(_shift(Jf, side)), c3.matvec(Qs, u1), c3.matvec(Qs, u2)))
    W11 = free_n[0] / m
    W22 = (free_n[1] * e_r[2] ** 2 + free_n[2] * e_r[1] ** 2) / m
    W12 = jnp.zeros_like(W11)
    for c, Js, g1, g2 in sides:
        W11 = W11 + c**2 * c3.dot(Js, (g1[0] * g1[0], g1[1] * g1[1], g1[2] * g1[2]))
        W22 = W22 + c**2 * c3.dot(Js, (g2[0] * g2[0], g2[1] * g2[1], g2[2] * g2[2]))
        W12 = W12 + c**2 * c3.dot(Js, (g1[0] * g2[0], g1[1] * g2[1], g1[2] * g2[2]))
    # each of these is read by several kernels below (the table, movable)
    W11, W22, W12 = computed_once((W11, W22, W12), N)
    # a point that nothing can move (a clamped end) takes no impulse
    movable = (W11 * W22 - W12 * W12) > 0
    W11, W22, W12 = jnp.where(movable, W11, 1.0), jnp.where(movable, W22, 1.0), jnp.where(movable, W12, 0.0)
    in_contact = (N > 0) & movable
    (_, _, g1l, g2l), (_, _, g1r, g2r) = sides
    fields = dict(cl=cl, cr=cr, W11=W11, W12=W12, W22=W22, bound_s=model.rod.mu_s * N,
                  bound_d=model.rod.mu_d * N, active=in_contact.astype(dtype))
    for name, value in (("t2", t2), ("fm", tuple(f / m for f in free_n)), ("g1l", g1l), ("g2l", g2l),
                        ("g1r", g1r), ("g2r", g2r)):
        fields.update({f"{name}{k}": value[k] for k in range(3)})
    fields.update({f"J{k}": jnp.concatenate([Jf[:, k], jnp.zeros((1,), dtype)]) for k in range(3)})
    # red–black, each colour in arrays of its own: node 2k + c is entry k of colour c, and so is
    # segment 2k + c (a padded node or segment is inert: W = 1, everything else 0)
    table = jnp.stack([jnp.broadcast_to(fields[k], W11.shape) for k in FIELDS])  # (fields, n + 1)
    pad = jnp.asarray([1.0 if k in ("W11", "W22") else 0.0 for k in FIELDS], dtype)
    table = jnp.concatenate([table, jnp.broadcast_to(pad[:, None], (len(FIELDS), 2 * M - table.shape[1]))], 1)
    return table.reshape(len(FIELDS), M, 2)


def friction_pass(model, friction, table, v, w, stuck, force, h):
    """The friction impulses of a (half) step `h` [s] under the law `friction`
    ([`jaxrod.Coulomb`][] or [`jaxrod.Tanh`][]) with the contacts' fields `table`
    (`friction_table` at this position): projected Gauss–Seidel sweeps, even nodes then odd
    nodes, started from the impulses `force`·h of the last pass (clipped to this pass's bounds),
    repeated until no impulse changes by more than `model.friction_tol` × the largest friction
    bound, or `model.friction_sweeps` sweeps.

    An impulse p = p₁t₁ + p₂t₂ at node i's contact point moves the node by p/m and, through
    the arm r_c, spins the node's two segments by their shares c of the torque r_c × p. With
    u₁ = r_c × t₁ = −r t₂ and u₂ = r_c × t₂ = r t₁ (r = |r_c|), and gₐ = Q uₐ those arms in a
    segment's material frame, everything is per node and per component: the slip velocity
    t_a·v + Σ_seg c w·gₐ, the tangent inverse mass W_ab = δ_ab/m (free components) + Σ_seg c²
    Σ_k gₐₖ g_bₖ / J_k, and the spin change J⁻¹ c Σₐ pₐ gₐ (written out instead of batches of
    3×3 products, which do not fuse on CPU).

    **Returns:** the new `(v, w, stuck, force, residual, sweeps)`: `force` the tangential friction
    force of each contact [N], `residual` the largest change of an impulse in the last sweep over
    the largest bound, `sweeps` the sweeps taken."""
    dtype = v.dtype
    if not model.channel:  # no wall, no contact, no friction
        return v, w, stuck, jnp.zeros_like(force), jnp.zeros((), dtype), jnp.zeros((), dtype)
    # node 2k + c is entry k of colour c, and so is segment 2k + c. Even node k has segments
    # 2k − 1 (odd k − 1) and 2k (even k) on its left and right, odd node k has segments 2k (even
    # k) and 2k + 1 (odd k): a half sweep solves only its own contacts.
    M = table.shape[1]

    def split(a, fill=0):
        a = jnp.concatenate([a, jnp.full((2 * M - a.shape[0],) + a.shape[1:], fill, a.dtype)])
        a = a.reshape((M, 2) + a.shape[1:])
        return a[:, 0], a[:, 1]

    def split3(t, fill=0):
        parts = [split(c, fill) for c in t]
        return tuple(p[0] for p in parts), tuple(p[1] for p in parts)

    def merge(even, odd, size):
        return jnp.stack([even, odd], 1).reshape((2 * M,) + even.shape[1:])[:size]

    rows = table[:, :, 0], table[:, :, 1]  # each (fields, M): a field is a contiguous row

    def fields_of(c):
        """The colour-`c` fields by name, bounds for this step (read where they are used: inside
        the sweep loop, as a while loop's inputs are buffers, one kernel each per pass)."""
        K = {k: rows[c][i] for i, k in enumerate(FIELDS)}
        K["active"] = K["active"] > 0
        K["bound_s"], K["bound_d"] = h * K["bound_s"], h * K["bound_d"]
        for name in ("t2", "fm", "g1l", "g2l", "g1r", "g2r", "J"):
            K[name] = tuple(K.pop(f"{name}{k}") for k in range(3))
        return K

    def neighbours(c, w):
        """The spins of the left and right segments of the colour-`c` nodes."""
        if c == 1:
            return w[0], w[1]
        return tuple(jnp.concatenate([jnp.zeros((1,), dtype), a[:-1]]) for a in w[1]), w[0]

    def slip(node, c, v, w):
        """Tangential velocities (u₁, u₂) of the colour-`c` contact points."""
        K = node[c]
        wl, wr = neighbours(c, w)
        return (v[0] + K["cl"] * c3.dot(wl, K["g1l"]) + K["cr"] * c3.dot(wr, K["g1r"]),
                c3.dot(K["t2"], v) + K["cl"] * c3.dot(wl, K["g2l"]) + K["cr"] * c3.dot(wr, K["g2r"]))

    def apply(node, c, v, w, dp):
        """Velocities of the colour-`c` nodes and of all segments after their impulses `dp`."""
        K, Jseg = node[c], (node[0]["J"], node[1]["J"])
        p1, p2 = dp
        v = (v[0] + K["fm"][0] * p1, v[1] + K["fm"][1] * p2 * K["t2"][1], v[2] + K["fm"][2] * p2 * K["t2"][2])
        tl = tuple(K["cl"] * (p1 * K["g1l"][k] + p2 * K["g2l"][k]) for k in range(3))  # left segment
        tr = tuple(K["cr"] * (p1 * K["g1r"][k] + p2 * K["g2r"][k]) for k in range(3))  # right segment
        if c == 0:  # left: odd segment k − 1, right: even segment k
            tl = tuple(jnp.concatenate([a[1:], jnp.zeros((1,), dtype)]) for a in tl)
            we = tuple(w[0][k] + Jseg[0][k] * tr[k] for k in range(3))
            wo = tuple(w[1][k] + Jseg[1][k] * tl[k] for k in range(3))
        else:  # left: even segment k, right: odd segment k
            we = tuple(w[0][k] + Jseg[0][k] * tl[k] for k in range(3))
            wo = tuple(w[1][k] + Jseg[1][k] * tr[k] for k in range(3))
        return v, (we, wo)

    node = (fields_of(0), fields_of(1))
    scale = jnp.maximum(jnp.maximum(*(jnp.max(jnp.where(K["active"], K["bound_s"], 0.0)) for K in node)),
                        jnp.finfo(dtype).tiny)
    # warm start: last pass's forces, within this pass's bounds
    stucks = split(stuck, False)
    p0 = split3((force[:, 0] * h, force[:, 1] * h))
    p0 = list(p0)
    for c in (0, 1):
        K = node[c]
        cap = jnp.where(stucks[c], K["bound_s"], K["bound_d"])
        norm = safe_hypot(*p0[c])
        k = jnp.where(K["active"] & (norm > cap), cap / jnp.where(norm > 0, norm, 1.0), 1.0)  # no 0·∞ in a jvp
        p0[c] = tuple(jnp.where(K["active"], k * p, 0.0) for p in p0[c])
    vs = list(split3(c3.unpack(v)))
    w = split3(c3.unpack(w))
    for c in (0, 1):
        vs[c], w = apply(node, c, vs[c], w, p0[c])

    def sweep(carry):
        vs, w, stucks, p_acc, _, k = carry
        vs, stucks, p_acc = list(vs), list(stucks), list(p_acc)
        change = jnp.zeros((), dtype)
        node = (fields_of(0), fields_of(1))
        for c in (0, 1):
            K = node[c]
            s1, s2 = slip(node, c, vs[c], w)
            pa = p_acc[c]
            u = (s1 - (K["W11"] * pa[0] + K["W12"] * pa[1]), s2 - (K["W12"] * pa[0] + K["W22"] * pa[1]))  # without own
            p, sticks = friction.impulse_2d(u, (K["W11"], K["W12"], K["W22"]),
                                            jnp.where(stucks[c], K["bound_s"], K["bound_d"]), K["bound_d"], pa)
            p = computed_once(p, K["W11"])  # read by every velocity it changes
            p = (jnp.where(K["active"], p[0], 0.0), jnp.where(K["active"], p[1], 0.0))
            dp = (p[0] - pa[0], p[1] - pa[1])
            change = jnp.maximum(change, jnp.max(safe_hypot(*dp)))
            vs[c], w = apply(node, c, vs[c], w, dp)
            p_acc[c], stucks[c] = p, K["active"] & sticks
        return tuple(vs), w, tuple(stucks), tuple(p_acc), change / scale, k + 1

    def more(carry):
        k = carry[-1]
        return (k == 0) | ((k < model.friction_sweeps) & (carry[-2] > model.friction_tol))

    carry = (tuple(vs), w, stucks, tuple(p0), jnp.zeros((), dtype), 0)
    if model.friction_sweeps == 1:  # no loop: reverse-mode differentiable
        carry = sweep(carry)
    else:  # one compiled copy of the sweep, in the loop (compile time)
        # (under vmap, the loop's batching keeps a converged member's carry while the others
        # sweep on, so a batch member equals its single run)
        carry = jax.lax.while_loop(more, sweep, carry)
    vs, w, stucks, p_acc, residual, sweeps = carry
    n1 = model.n + 1
    v = jnp.stack([merge(vs[0][k], vs[1][k], n1) for k in range(3)], -1)
    w = jnp.stack([merge(w[0][k], w[1][k], model.n) for k in range(3)], -1)
    force = jnp.stack([merge(p_acc[0][a], p_acc[1][a], n1) for a in range(2)], -1) / jnp.where(h > 0, h, 1.0)
    any_contact = jnp.any(node[0]["active"]) | jnp.any(node[1]["active"])
    return (v, w, merge(*stucks, n1), force, jnp.where(any_contact, residual, 0.0),
            jnp.asarray(sweeps, dtype))
