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
from .state import held_pattern

__all__ = ["node_weights", "FIELDS", "pass_dtype", "friction_table", "friction_pass", "static_equilibrium"]

# the friction pass's fields of each contact, rows of `friction_table`: the outward radius
# e_r = (0, e1, e2), the tangent inverse mass W, the bounds per unit time, whether it is active,
# and for its left (l) and right (r) segment the arms δ_a = d₃·ûₐ and the vector D of its spin
# along the segment's axis (`friction_table`)
FIELDS = ("e1", "e2", "W11", "W12", "W22", "bound_s", "bound_d", "active", "dl1", "dl2", "dr1", "dr2",
          "Dlx", "Dly", "Dlz", "Drx", "Dry", "Drz")


def pass_dtype(model, dtype):
    """The dtype the friction pass computes in, for a state of `dtype`: float32 with
    `model.friction_precision == "float32"` (its arrays half as wide: the pass is bound by the
    arrays its kernels write and read), else the state's."""
    return jnp.float32 if model.friction_precision == "float32" else dtype


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
    """M = ⌈(n + 1)/2⌉: the entries of the larger colour (the even nodes) of the red–black split of
    n + 1 nodes, the length both halves are padded to."""
    return (n + 2) // 2


def _split(a, M: int, fill=0):
    """The red–black halves of `a` along its first axis: entries 0, 2, 4, … and 1, 3, 5, …,
    each padded with `fill` to M (strided slices, which the kernels that read them fuse)."""
    def pad(b):
        extra = M - b.shape[0]
        return b if extra == 0 else jnp.concatenate([b, jnp.full((extra,) + b.shape[1:], fill, a.dtype)])
    return pad(a[0::2]), pad(a[1::2])


def _node_constants(model, dtype):
    """What the friction pass needs of each node that does not depend on the position, as
    arrays (n + 1,): the inverse mass of its free translations `fm` (x, y, z) [1/kg], and for its
    left and right segment ρ = c r (its share of the segment's spin times the arm) [m] and
    k = ρ A (A = 1/J_⊥, the segment's inverse inertia about a transverse axis, 0 where its
    rotation is held) [1/(kg·m)], and B − A (B = 1/J_∥ about its axis, 0 where its spin is held)
    [1/(kg·m²)]."""
    held_n, held_s = held_pattern(model)
    if not np.array_equal(held_s[:, 0], held_s[:, 1]):
        raise ValueError("Rod3D.held: a segment's two transverse spin components must be held together "
                         "(the friction pass's lab-frame inverse inertia assumes it).")
    inv_m = 1.0 / model.mass.astype(dtype)
    fm = tuple(jnp.asarray(~held_n[:, k], dtype) * inv_m for k in range(3))
    r = _arm(model, dtype)
    J = model.inertia.astype(dtype)
    A = jnp.asarray(~held_s[:, 0], dtype) / J[0]
    BA = jnp.asarray(~held_s[:, 2], dtype) / J[2] - A
    cl, cr = node_weights(model)
    sides = {}
    for side, shift, c in (("l", "left", cl), ("r", "right", cr)):
        rho = c.astype(dtype) * r
        sides[side] = (rho, rho * _shift(A, shift), _shift(BA, shift))
    return fm, sides


def friction_table(model, x, Q, N):
    """The fields of the friction pass at the position (x, Q) under the normal forces `N` [N]
    (`FIELDS`), for each contact: its outward radius e_r = (0, e₁, e₂) (the tangents are t₁ = x̂
    and t₂ = x̂ × e_r); the tangent inverse mass W [1/kg]; the friction bounds per unit time
    μ_s N and μ_d N [N]; whether it is active (N > 0 and movable); and for each of its two
    segments the arms δₐ = d₃·ûₐ of the unit torques û₁ = (0, e₂, −e₁), û₂ = x̂ about the
    segment's axis d₃, and D = c r (B − A) d₃ [1/(kg·m)] (`friction_pass` gives every symbol).
    Every pass at a position uses them (projected leapfrog: the one pass of the next step and
    the pass of a save; projected Verlet: the second pass of a step and the first of the next),
    so `Rod3D.accelerations` computes this once per position and the forces carry it. Two arrays
    (len(FIELDS), M), one per colour of the pass's red–black split: field, entry k for node
    2k + c (padded nodes inert), in the pass's dtype (`pass_dtype`)."""
    dtype = pass_dtype(model, x.dtype)
    if not model.channel:  # no wall, no contact: an inert table
        return (jnp.zeros((len(FIELDS), colours(model.n)), dtype),) * 2
    # a held node still touches the wall: its translation is prescribed (the support takes the
    # friction force) but the friction at its contact point still acts on its segments' spin, so
    # the end of the rod cannot roll freely (without it the interior rolls sideways as one body,
    # the end segments tilting, and a loaded rod buckles through that roll: issue [rod3d])
    fm, sides = _node_constants(model, dtype)
    _, (_, e1, e2) = _penetration(model, c3.unpack(x))
    e1, e2, N = e1.astype(dtype), e2.astype(dtype), N.astype(dtype)
    d3 = c3.unpack(Q[:, 2, :].astype(dtype))  # each segment's axis in the lab frame
    W11 = fm[0]
    W22 = fm[1] * e2**2 + fm[2] * e1**2
    W12 = jnp.zeros_like(W11)
    fields = {}
    for side, shift in (("l", "left"), ("r", "right")):
        rho, k, BA = sides[side]
        d = tuple(_shift(a, shift) for a in d3)
        delta1, delta2 = d[1] * e2 - d[2] * e1, d[0]  # d₃·û₁, d₃·û₂
        rho2BA = rho * rho * BA
        W11 = W11 + rho * k + rho2BA * delta1**2
        W22 = W22 + rho * k + rho2BA * delta2**2
        W12 = W12 + rho2BA * delta1 * delta2
        fields.update({f"d{side}1": delta1, f"d{side}2": delta2})
        fields.update({f"D{side}{a}": rho * BA * d[i] for i, a in enumerate("xyz")})
    # each of these is read by several kernels below (the table, movable)
    W11, W22, W12 = computed_once((W11, W22, W12), N)
    # a point that nothing can move (a clamped end) takes no impulse
    movable = (W11 * W22 - W12 * W12) > 0
    W11, W22, W12 = jnp.where(movable, W11, 1.0), jnp.where(movable, W22, 1.0), jnp.where(movable, W12, 0.0)
    in_contact = (N > 0) & movable
    fields.update(e1=e1, e2=e2, W11=W11, W12=W12, W22=W22, bound_s=model.rod.mu_s.astype(dtype) * N,
                  bound_d=model.rod.mu_d.astype(dtype) * N, active=in_contact.astype(dtype))
    # red–black, each colour an array of its own: node 2k + c is entry k of colour c (a padded
    # node is inert: W = 1, everything else 0)
    M = colours(model.n)
    columns = []
    for k in FIELDS:
        a = jnp.broadcast_to(fields[k], W11.shape)
        a = jnp.concatenate([a, jnp.full((2 * M - a.shape[0],), 1.0 if k in ("W11", "W22") else 0.0, dtype)])
        columns.append(a.reshape(M, 2))
    return tuple(jnp.stack([a[:, c] for a in columns]) for c in (0, 1))


def friction_pass(model, friction, table, Q, v, w, stuck, force, h):
    """The friction impulses of a (half) step `h` [s] under the law `friction`
    ([`jaxrod.Coulomb`][] or [`jaxrod.Tanh`][]) with the contacts' fields `table`
    (`friction_table` at this position, whose directors are `Q`): projected Gauss–Seidel
    sweeps, even nodes then odd nodes, started from the impulses `force`·h of the last pass
    (clipped to this pass's bounds), repeated until no impulse changes by more than
    `model.friction_tol` × the largest friction bound, or `model.friction_sweeps` sweeps.

    An impulse p = p₁t₁ + p₂t₂ at node i's contact point moves the node by p/m and, through
    the arm r_c = r e_r, spins each of the node's two segments by its share c of the torque
    r_c × p = r (p₁û₁ + p₂û₂), û₁ = e_r × x̂ = (0, e₂, −e₁) and û₂ = x̂. The pass works with the
    segments' spins in the lab frame, ω = Qᵀw, where a segment's inverse inertia is
    A 1 + (B − A) d₃d₃ᵀ (A = 1/J_⊥, B = 1/J_∥ about its axis d₃): the slip velocity is
    t_a·v + Σ_seg c r ω·ûₐ, the spin change of impulse p is c r (A (p₁û₁ + p₂û₂) + (B − A) d₃
    (p₁δ₁ + p₂δ₂)) with δₐ = d₃·ûₐ, and the tangent inverse mass W_ab = δ_ab/m (free
    components) + Σ_seg (c r)² (A δ_ab + (B − A) δₐ δ_b). The pass returns w + Q Δω.

    **Returns:** the new `(v, w, stuck, force, residual, sweeps)`: `force` the tangential friction
    force of each contact [N], `residual` the largest change of an impulse in the last sweep over
    the largest bound, `sweeps` the sweeps taken.

    The pass computes in `pass_dtype` (the table's): it casts the velocities, spins, directors,
    forces and h in, and adds its changes of v and w to the state's arrays (a node without
    contact keeps its velocity exactly)."""
    state_dtype = v.dtype
    if not model.channel:  # no wall, no contact, no friction
        return v, w, stuck, jnp.zeros_like(force), jnp.zeros((), state_dtype), jnp.zeros((), state_dtype)
    dtype = table[0].dtype
    h = jnp.asarray(h).astype(dtype)
    # node 2k + c is entry k of colour c, and so is segment 2k + c. Even node k has segments
    # 2k − 1 (odd k − 1) and 2k (even k) on its left and right, odd node k has segments 2k (even
    # k) and 2k + 1 (odd k): a half sweep solves only its own contacts.
    M = colours(model.n)

    def split(a, fill=0):
        return _split(a, M, fill)

    def split3(t, fill=0):
        parts = [split(c, fill) for c in t]
        return tuple(p[0] for p in parts), tuple(p[1] for p in parts)

    def merge(even, odd, size):
        return jnp.stack([even, odd], 1).reshape((2 * M,) + even.shape[1:])[:size]

    fm, sides = _node_constants(model, dtype)
    const = [{}, {}]
    for name, value in (("fm", fm), ("rl", sides["l"][0]), ("rr", sides["r"][0]), ("kl", sides["l"][1]),
                        ("kr", sides["r"][1])):
        parts = split3(value) if isinstance(value, tuple) else split(value)
        const[0][name], const[1][name] = parts

    def fields_of(c):
        """The colour-`c` fields by name, bounds for this step (read where they are used: inside
        the sweep loop, as a while loop's inputs are buffers, one kernel each per pass)."""
        K = {k: table[c][i] for i, k in enumerate(FIELDS)}  # a field is a contiguous row
        K["active"] = K["active"] > 0
        K["bound_s"], K["bound_d"] = h * K["bound_s"], h * K["bound_d"]
        for side in "lr":
            K[f"D{side}"] = tuple(K.pop(f"D{side}{a}") for a in "xyz")
        K.update(const[c])
        return K

    def neighbours(c, om):
        """The spins of the left and right segments of the colour-`c` nodes."""
        if c == 1:
            return om[0], om[1]
        return tuple(jnp.concatenate([jnp.zeros((1,), dtype), a[:-1]]) for a in om[1]), om[0]

    def slip(node, c, v, om):
        """Tangential velocities (u₁, u₂) of the colour-`c` contact points."""
        K = node[c]
        ol, orr = neighbours(c, om)
        sx, sy, sz = (K["rl"] * ol[k] + K["rr"] * orr[k] for k in range(3))  # Σ c r ω
        return v[0] + K["e2"] * sy - K["e1"] * sz, K["e1"] * v[2] - K["e2"] * v[1] + sx

    def apply(node, c, v, om, dp):
        """Velocities of the colour-`c` nodes and spins of all segments after their impulses `dp`."""
        K = node[c]
        p1, p2 = dp
        fm = K["fm"]
        v = (v[0] + fm[0] * p1, v[1] - fm[1] * p2 * K["e2"], v[2] + fm[2] * p2 * K["e1"])
        torque = (p2, p1 * K["e2"], -p1 * K["e1"])  # p₁û₁ + p₂û₂
        ql, qr = p1 * K["dl1"] + p2 * K["dl2"], p1 * K["dr1"] + p2 * K["dr2"]
        tl = tuple(K["kl"] * torque[k] + K["Dl"][k] * ql for k in range(3))  # left segment
        tr = tuple(K["kr"] * torque[k] + K["Dr"][k] * qr for k in range(3))  # right segment
        if c == 0:  # left: odd segment k − 1, right: even segment k
            tl = tuple(jnp.concatenate([a[1:], jnp.zeros((1,), dtype)]) for a in tl)
            oe = tuple(om[0][k] + tr[k] for k in range(3))
            oo = tuple(om[1][k] + tl[k] for k in range(3))
        else:  # left: even segment k, right: odd segment k
            oe = tuple(om[0][k] + tl[k] for k in range(3))
            oo = tuple(om[1][k] + tr[k] for k in range(3))
        return v, (oe, oo)

    node = (fields_of(0), fields_of(1))
    scale = jnp.maximum(jnp.maximum(*(jnp.max(jnp.where(K["active"], K["bound_s"], 0.0)) for K in node)),
                        jnp.finfo(dtype).tiny)
    # warm start: last pass's forces, within this pass's bounds
    stucks = split(stuck, False)
    p0 = split3((force[:, 0].astype(dtype) * h, force[:, 1].astype(dtype) * h))
    p0 = list(p0)
    for c in (0, 1):
        K = node[c]
        cap = jnp.where(stucks[c], K["bound_s"], K["bound_d"])
        norm = safe_hypot(*p0[c])
        k = jnp.where(K["active"] & (norm > cap), cap / jnp.where(norm > 0, norm, 1.0), 1.0)  # no 0·∞ in a jvp
        p0[c] = tuple(jnp.where(K["active"], k * p, 0.0) for p in p0[c])
    v_in = split3(tuple(a.astype(dtype) for a in c3.unpack(v)))
    vs = list(v_in)
    Qr = c3.unpack_matrix(Q.astype(dtype))
    om0 = c3.rmatvec(Qr, tuple(a.astype(dtype) for a in c3.unpack(w)))  # the spins in the lab frame, ω = Qᵀw
    om = split3(om0)
    for c in (0, 1):
        vs[c], om = apply(node, c, vs[c], om, p0[c])

    def sweep(carry):
        vs, om, stucks, p_acc, _, k = carry
        vs, stucks, p_acc = list(vs), list(stucks), list(p_acc)
        change = jnp.zeros((), dtype)
        node = (fields_of(0), fields_of(1))
        for c in (0, 1):
            K = node[c]
            s1, s2 = slip(node, c, vs[c], om)
            pa = p_acc[c]
            u = (s1 - (K["W11"] * pa[0] + K["W12"] * pa[1]), s2 - (K["W12"] * pa[0] + K["W22"] * pa[1]))  # without own
            p, sticks = friction.impulse_2d(u, (K["W11"], K["W12"], K["W22"]),
                                            jnp.where(stucks[c], K["bound_s"], K["bound_d"]), K["bound_d"], pa)
            p = computed_once(p, K["W11"])  # read by every velocity it changes
            p = (jnp.where(K["active"], p[0], 0.0), jnp.where(K["active"], p[1], 0.0))
            dp = (p[0] - pa[0], p[1] - pa[1])
            change = jnp.maximum(change, jnp.max(safe_hypot(*dp)))
            vs[c], om = apply(node, c, vs[c], om, dp)
            p_acc[c], stucks[c] = p, K["active"] & sticks
        return tuple(vs), om, tuple(stucks), tuple(p_acc), change / scale, k + 1

    tol = model.friction_tol.astype(dtype)

    def more(carry):
        k = carry[-1]
        return (k == 0) | ((k < model.friction_sweeps) & (carry[-2] > tol))

    carry = (tuple(vs), om, stucks, tuple(p0), jnp.zeros((), dtype), 0)
    if model.friction_sweeps == 1:  # no loop: reverse-mode differentiable
        carry = sweep(carry)
    else:  # one compiled copy of the sweep, in the loop (compile time)
        # (under vmap, the loop's batching keeps a converged member's carry while the others
        # sweep on, so a batch member equals its single run)
        carry = jax.lax.while_loop(more, sweep, carry)
    vs, om, stucks, p_acc, residual, sweeps = carry
    n1 = model.n + 1
    d_v = tuple(merge(vs[0][k] - v_in[0][k], vs[1][k] - v_in[1][k], n1) for k in range(3))
    v = v + c3.pack(d_v).astype(state_dtype)
    d_om = tuple(merge(om[0][k], om[1][k], model.n) - om0[k] for k in range(3))
    w = w + c3.pack(c3.matvec(Qr, d_om)).astype(state_dtype)  # back to the material frame: w + Q Δω
    force = jnp.stack([merge(p_acc[0][a], p_acc[1][a], n1) for a in range(2)], -1) / jnp.where(h > 0, h, 1.0)
    any_contact = jnp.any(node[0]["active"]) | jnp.any(node[1]["active"])
    return (v, w, merge(*stucks, n1), force.astype(state_dtype), jnp.where(any_contact, residual, 0.0).astype(state_dtype),
            jnp.asarray(sweeps, state_dtype))



def static_equilibrium(model, x, Q, f, tau, N):
    """Whether the rod at rest at (x, Q) is held there by static friction: the forces `f`
    (n + 1, 3) [N] (everything but wall friction), material torques `tau` (n, 3) [N·m] and wall
    forces `N` (n + 1,) [N] balance with friction forces inside the static cones.

    Each node's free translation fixes its friction force: F = −(t₁·f, t₂·f) on the free
    components (t₁ = x̂, t₂ = x̂ × e_r), and it must lie within μ_s N (a node with a free
    translation must touch the wall, and the wall must take its radial force). The friction at
    the contact point (arm r, `friction_at`) adds the couples c r (F₁û₁ + F₂û₂) to the node's two
    segments, which must balance their free torque components. The radial and torque balances
    are tested to the friction pass's own tolerance (`model.friction_tol` of the largest wall
    force, and of the largest torque or friction couple): a rod at an equilibrium of the
    discrete model passes, a rod whose forces ask more than μ_s N of a contact, or that the
    friction couples would roll, does not.

    **Returns:** a boolean per node (n + 1,): node i is held (free translations balanced inside
    its cone), and `all` of it with `segments_held` (n,) is the whole test: `(nodes, segments)`."""
    held_n, held_s = (jnp.asarray(a) for a in held_pattern(model))
    dtype = f.dtype
    if not model.channel:  # nothing holds a free rod in space
        return jnp.zeros(held_n.shape[:1], bool) | jnp.all(held_n, -1), jnp.all(held_s, -1)
    _, (_, e1, e2) = _penetration(model, c3.unpack(x))
    ff = jnp.where(held_n, 0.0, f)  # the supports take the held components
    F1, F2 = -ff[:, 0], -(e1 * ff[:, 2] - e2 * ff[:, 1])  # t₂ = (0, −e₂, e₁)
    radial = e1 * ff[:, 1] + e2 * ff[:, 2]
    tol = model.friction_tol.astype(dtype)
    free = ~jnp.all(held_n, -1)
    inside = safe_hypot(F1, F2) <= model.rod.mu_s * N
    nodes = ~free | ((N > 0) & inside & (jnp.abs(radial) <= tol * jnp.max(N)))
    # the friction couples on the segments (lab frame), each node's share c of its arm r
    r = _arm(model, dtype)
    cl, cr = node_weights(model)
    couple = (F2, F1 * e2, -F1 * e1)  # F₁û₁ + F₂û₂, û₁ = (0, e₂, −e₁), û₂ = x̂
    on_seg = tuple(r * (cr[:-1] * a[:-1] + cl[1:] * a[1:]) for a in couple)
    Qr = c3.unpack_matrix(Q)
    resid = jnp.stack(c3.matvec(Qr, on_seg), -1) + tau  # material frame
    resid = jnp.where(held_s, 0.0, resid)
    scale = jnp.maximum(jnp.max(jnp.abs(tau)), r * jnp.max(model.rod.mu_s * N))
    segments = jnp.all(jnp.abs(resid) <= tol * scale, -1)
    return nodes, segments
