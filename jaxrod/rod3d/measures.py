"""What a run of the 3D rod records and how it is judged: the amplitude, the stick test, the
buckling threshold of each control, and the observables at a save. Functions of the model
(`jaxrod.rod3d.Rod3D` calls them as methods)."""

from __future__ import annotations

import jax.numpy as jnp

from .. import theory
from . import contact

__all__ = ["amplitude", "stop_measures", "is_stuck", "buckle_threshold", "observables"]


def amplitude(model, q):
    """max |θ| over the interior nodes [rad] (0 without a channel: θ is an angle on its wall).

    θ = atan2(y, −z) has |tan(θ/2)| = |y|/(r − z) = (r + z)/|y| (r = √(y² + z²); the first
    form below the axis, the second above, each without cancellation), so |θ| grows with that
    ratio: the largest |θ| is that of the largest ratio, one arctangent per rod instead of one
    per node (the run tests the amplitude after every step)."""
    if not model.channel:
        return jnp.zeros((), q.x.dtype)
    y, z = jnp.abs(q.x[1:-1, 1]), q.x[1:-1, 2]
    r = jnp.sqrt(y * y + z * z)
    below = z <= 0
    num, den = jnp.where(below, y, r + z), jnp.where(below, r - z, y)
    # den = 0: on the axis (θ = 0 here) or on the ray above it (θ = π)
    ratio = jnp.where(den > 0, num / jnp.where(den > 0, den, 1.0), jnp.where(num > 0, jnp.inf, 0.0))
    return 2.0 * jnp.arctan(jnp.max(ratio))


def stop_measures(model, q, v, a):
    """The amplitude, and whether the rod is stuck after a step: every node and spin that may
    move at rest, and every node with a free translation held by static friction in the step's
    friction pass. That pass saw the forces: it cancelled the step's trial velocity with
    impulses inside the static cones (the coupled solve, friction couples included), and the
    velocity left is exactly zero only if the radial forces and the torques balance too — a
    static equilibrium, which under a constant load nothing can release. (A state no pass has
    seen is judged by `is_stuck`.) Cheap: it runs after every step."""
    held_n, held_s = model.held()
    at_rest = jnp.all(jnp.where(held_n, True, v.v == 0)) & jnp.all(jnp.where(held_s, True, v.w == 0))
    free = ~jnp.all(held_n, -1)
    return amplitude(model, q), at_rest & jnp.all(v.stuck | ~free)


def is_stuck(model, q, v, a):
    """Whether the rod at (q, v) is stuck before any friction pass has seen it (the start of a
    run: the stick flags of a contact at rest only say that it starts under the static
    coefficient): `stop_measures`'s test, and the forces `a` at `q` in static equilibrium with
    friction inside the static cones (`jaxrod.rod3d.contact.static_equilibrium`). A rod released
    from rest is stuck only if its forces are held; before this test every one was declared stuck
    at step 0."""
    _, stuck = stop_measures(model, q, v, a)
    nodes, segments = contact.static_equilibrium(model, q.x, q.Q, a.f, a.tau, a.N)
    return stuck & jnp.all(nodes) & jnp.all(segments)


def buckle_threshold(model):
    """The amplitude max|θ| [rad] past which a run counts as buckled: 0.5 rad, as the reduced
    models, under a dead load (`"load"`: a buckled rod grows without bound) and displacement
    control; with the ends held after a pre-compression (`"force"`) a buckled rod relieves its
    load and settles near the amplitude A_held whose end shortening takes up ΔF = `preload` − F⁰
    (`jaxrod.theory.held_end_amplitude` of the critical mode: 0.38 rad at ΔF = 5 N for the
    reference rod), so it counts as buckled at min(0.5, ½A_held); a rod that is stable there
    sticks well below (0.04 rad at ΔF = 5 N, the stick line)."""
    half = jnp.asarray(0.5, model.rod.L.dtype)
    if model.control != "force" or not model.channel:
        return half
    dF = model.preload - theory.reference_load(model.rod)
    held = 0.5 * theory.held_end_amplitude(model.rod, dF, theory.critical_mode(model.rod))
    return jnp.where(dF > 0, jnp.minimum(half, held), half)


def observables(model, q, v, a) -> dict:
    """Recorded at every save: `theta` (n+1,) angle of every node from the channel bottom [rad],
    directly comparable with the field model's θ(s, t); `reaction` (2,) compressive support
    forces along x at node 0 and node n [N]; `end_x` position of the pushed end along x [m];
    `normal_force` (n+1,) wall force per length [N/m]; `axial_force` (n,) compressive force of
    every segment [N]; `height` largest height of the centre line above the channel bottom [m];
    `gap` largest distance of a node inside the clearance circle, R − r [m] (> 0 where the rod
    has lifted off the wall); `friction_residual` the relative residual of the last friction
    pass (see `Rod3D.friction_tol`) and `friction_sweeps` the sweeps it took; `stuck_fraction`
    the fraction of the nodes held by static friction in that pass."""
    x = q.x
    return dict(
        theta=model.theta(x),
        reaction=jnp.stack([-a.f[0, 0], a.f[-1, 0]]),
        end_x=x[-1, 0],
        normal_force=model.contact_normal(x, v.v)[0] / model.voronoi,
        axial_force=model.axial_force(x, q.Q),
        height=jnp.max(x[:, 2]) + model.rod.R + model.static_sag(),
        gap=jnp.max(-model.penetration(x)[0]) if model.channel else jnp.zeros((), x.dtype),
        friction_residual=v.residual,
        friction_sweeps=v.sweeps,
        stuck_fraction=jnp.mean(v.stuck.astype(x.dtype)),
    )
