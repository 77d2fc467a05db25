"""The 3D rod's state as pytrees: coordinates, velocities (with the friction law's memory) and
the forces a kick needs."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from .._numerics import float_leaf, safe_norm
from .._trig import atan2


__all__ = ["axial_preload", "static_sag", "held_pattern", "Rod3DPosition", "Rod3DVelocity", "Rod3DForces", "at_rest", "straight_state", "wall_angle", "sine_velocity"]


class Rod3DPosition(eqx.Module):
    """The rod's coordinates `q`: node positions `x` (n+1, 3) [m] and segment directors `Q`
    (n, 3, 3) (rows d₁, d₂, d₃ in the lab frame: lab → material)."""

    x: Float[Array, "n1 3"]
    Q: Float[Array, "n 3 3"]


class Rod3DVelocity(eqx.Module):
    """The rod's velocities `v`: node velocities `v` (n+1, 3) [m/s], segment angular
    velocities `w` (n, 3) in the material frame [rad/s], and the friction pass's memory:
    `stuck` (n+1,), whether each contact was held by static friction at the last impulse (it
    then keeps the static coefficient); `force` (n+1, 2), the tangential wall friction force of
    the last impulse [N] (axial, lateral), which starts the next pass (warm start); `residual`,
    the largest change of a contact impulse in the last sweep of that pass relative to the
    largest friction bound (0 when no contact is active); `sweeps`, the Gauss–Seidel sweeps that
    pass took (its cost; 0 before the first pass; a float, like every leaf of a state)."""

    v: Float[Array, "n1 3"]
    w: Float[Array, "n 3"]
    stuck: Bool[Array, " n1"]
    force: Float[Array, "n1 2"]
    residual: Float[Array, ""]
    sweeps: Float[Array, ""]


class Rod3DForces(eqx.Module):
    """What a kick and a friction pass need at a position (the integrators' `a`): node forces
    `f` [N] (elastic, contact, gravity, body, damping), material torques `tau` [N·m], wall
    normal forces `N` [N], the non-conservative (damping) part `fd` of the node forces [N], and
    `table`, the friction pass's fields of every contact there
    (`jaxrod.rod3d.contact.friction_table`: computed once per position for every pass there)."""

    f: Float[Array, "n1 3"]
    tau: Float[Array, "n 3"]
    N: Float[Array, " n1"]
    fd: Float[Array, "n1 3"]
    table: tuple[Float[Array, "fields m"], Float[Array, "fields m"]]


def held_pattern(model) -> tuple[np.ndarray, np.ndarray]:
    """Which node velocity components (n+1, 3) are prescribed and which segment spin components
    (n, 3, material frame) are held at zero, as NumPy arrays (static: they follow from the
    model's `ends` and `control`)."""
    nodes = np.zeros((model.n + 1, 3), bool)
    segs = np.zeros((model.n, 3), bool)
    if model.ends != "free":
        nodes[[0, -1]] = True
        if model.control == "load":
            nodes[-1, 0] = False
        if model.far_loaded:  # the far end slides against `far_load`
            nodes[0, 0] = False
    if model.ends == "clamped":
        segs[[0, -1]] = True
    elif model.ends == "fork":
        segs[[0, -1], 2] = True  # the spin about d₃
    return nodes, segs


def at_rest(q: Rod3DPosition) -> Rod3DVelocity:
    """Velocities of a rod at rest at `q`: no motion, no contact held, no friction memory."""
    x = q.x
    return Rod3DVelocity(jnp.zeros_like(x), jnp.zeros(q.Q.shape[:-1], x.dtype), jnp.zeros(x.shape[:1], bool),
                         jnp.zeros(x.shape[:1] + (2,), x.dtype), jnp.zeros((), x.dtype), jnp.zeros((), x.dtype))


@eqx.filter_jit
def axial_preload(model) -> Float[Array, ""]:
    """The straight rod's axial force [N]: `end_load`, `preload` (held ends) or 0 (displacement)."""
    if model.control == "load":
        return model.end_load
    return model.preload if model.control == "force" else jnp.zeros_like(model.preload)


def static_sag(model):
    """Penetration of a rod resting on the bottom under its own weight [m]."""
    sag = (model.rod.rho * model.rod.g / model.contact_stiffness) ** (2.0 / 3.0)
    return sag if model.channel and model.gravity else 0.0 * sag


def wrinkling_load(model):
    """The axial force [N] past which the straight rod resting on the wall is unstable to
    wrinkling into it: F_w = 2√(EI k_w), the compressed beam on an elastic foundation, with k_w =
    1.5 k √δ the Hertz wall's stiffness per length at the static sag δ (`static_sag`; 1.5 w/δ at
    the default k, ≈ 50 N for the reference rod). The wrinkle (wavelength 2π√(2EI/F)) needs the
    segments to turn about the lateral axis, which the friction at the contact point resists:
    the explicit scheme holds it, the implicit scheme's local friction pass does not
    (docs/rod3d.md). `inf` without a channel or gravity."""
    k_w = 1.5 * model.contact_stiffness * jnp.sqrt(static_sag(model))
    F_w = 2.0 * jnp.sqrt(model.rod.EI * k_w)
    return F_w if model.channel and model.gravity else jnp.full_like(F_w, jnp.inf)


def past_wrinkling(model) -> bool:
    """Whether the straight rod's axial force (`axial_preload`) is past `wrinkling_load`, for
    concrete numbers; `False` for traced ones (a run of the implicit scheme there then ends with
    the result code `inadequate`, `implicit_inadequate`)."""
    try:
        return bool(_past_wrinkling(model))
    except jax.errors.ConcretizationTypeError:
        return False


def _past_wrinkling(model):
    return axial_preload(model) > wrinkling_load(model)


def implicit_inadequate(model, coupled: bool):
    """Whether [`jaxrod.ImplicitLeapfrog`][] is outside its measured range on this rod (a traced
    bool): with the local friction pass (`coupled=False`), friction at the contact point and the
    straight rod's axial force past `wrinkling_load`, where at the default step every amplitude
    buckled (docs/rod3d.md); its runs end with the result code `inadequate`."""
    if coupled or model.friction_at != "surface":
        return jnp.array(False)
    return _past_wrinkling(model)


def straight_state(model, F: ArrayLike | None = None, lateral_velocity=None, lateral_offset=None):
    """A straight rod along x on the channel bottom (or on the x axis without a channel),
    compressed to the uniform axial force `F` [N] (length L(1 − F/EA); default
    `axial_preload()`), at rest except for an optional lateral (y) velocity [m/s] and
    lateral offset [m] per node: `Rod3D.initial_state`, one compiled program.

    **Returns:** `(q0, v0)`, a [`Rod3DPosition`][] and a [`Rod3DVelocity`][] (every
    contact at rest starts held by static friction)."""
    n = model.n
    F = float_leaf(axial_preload(model) if F is None else F)
    dtype = F.dtype
    l = model.l0 * (1.0 - F / model.rod.EA)
    xs = jnp.arange(n + 1, dtype=dtype) * l
    z = -(model.rod.R + model.static_sag()) if model.channel else 0.0 * model.rod.R
    x = jnp.stack([xs, jnp.zeros_like(xs), jnp.zeros_like(xs) + z], -1)
    if lateral_offset is not None:
        # move along the wall: θ = offset/R on the circle of radius R + sag
        if model.channel:
            rr = model.rod.R + model.static_sag()
            th = jnp.asarray(lateral_offset, dtype) / model.rod.R
            x = x.at[:, 1].set(rr * jnp.sin(th)).at[:, 2].set(-rr * jnp.cos(th))
        else:
            x = x.at[:, 1].set(jnp.asarray(lateral_offset, dtype))
    v = jnp.zeros_like(x)
    if lateral_velocity is not None:
        lv = jnp.asarray(lateral_velocity, dtype)
        if model.channel:
            _, e_r = model.penetration(x)
            tang = jnp.stack([jnp.zeros_like(e_r[:, 0]), -e_r[:, 2], e_r[:, 1]], -1)
            v = lv[:, None] * tang
        else:
            v = v.at[:, 1].set(lv)
    # directors: d3 along each segment, d1 as close to y as possible (no twist)
    e = x[1:] - x[:-1]
    d3 = e / safe_norm(e)[:, None]
    y = jnp.array([0.0, 1.0, 0.0], dtype)
    d1 = y[None, :] - (d3 @ y)[:, None] * d3
    d1 = d1 / safe_norm(d1)[:, None]
    d2 = jnp.cross(d3, d1)
    Q = jnp.stack([d1, d2, d3], -2)
    v, w = model.constrain(v, jnp.zeros((n, 3), dtype))
    at_rest = jnp.all(v == 0, -1)  # a contact at rest starts under the static coefficient
    return Rod3DPosition(x, Q), Rod3DVelocity(v, w, at_rest, jnp.zeros((n + 1, 2), dtype), jnp.zeros((), dtype),
                                              jnp.zeros((), dtype))


def wall_angle(x: Float[Array, "... n1 3"]) -> Float[Array, "... n1"]:
    """Angle of each node from the channel bottom [rad], θ = atan2(y, −z) (as in the field
    model); `x` may carry leading batch or time axes (`jaxrod._trig.atan2`)."""
    return atan2(x[..., 1], -x[..., 2])


def sine_velocity(model, v0, mode: int = 6):
    """Lateral speed v₀ sin(mπs/L) at the n + 1 nodes of `model` [m/s] (the sine perturbation)."""
    s = jnp.arange(model.n + 1) / model.n
    return jnp.asarray(v0) * jnp.sin(mode * jnp.pi * s)
