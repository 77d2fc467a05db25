r"""The full model: a 3D discrete Cosserat rod inside the channel, with wall contact and static
and dynamic Coulomb friction at the contact point.

n straight segments between n + 1 nodes (positions, segment directors); stretch, shear, bend
and twist energies whose reverse-mode gradient gives forces and torques; gravity; Hertz–Hunt–
Crossley wall contact on the clearance circle (the rod may lift off and climb the wall); the
vector Coulomb law at the contact point (it translates the node and spins its segments: the rod
can roll), applied red–black as an exact proximal step; the transverse rotary inertia scaled by
α so that an explicit step is not set by the shear–rotation frequency. Every equation, and the
effect of α, is in docs/physics.md §7.
"""

from __future__ import annotations

import copy
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from ..models.base import AbstractModel
from ..params import RodChannel
from ._checks import check_arguments
from .._numerics import computed_once, float_leaf
from . import components as c3, coupled, energy, hessian, measures, state, step_error as _error
from .contact import friction_pass, friction_table
from .state import held_pattern, Rod3DForces, Rod3DPosition, Rod3DVelocity, at_rest, straight_state, wall_angle
from .stiffness import frequency_bound

__all__ = ["Rod3D"]


class Rod3D(AbstractModel):
    """The discrete 3D rod in the channel. See the module docstring for every equation.

    A model like the others: it runs through [`jaxrod.simulate`][] with [`jaxrod.ImplicitLeapfrog`][]
    (its `scheme`, at `implicit_step`; it provides `implicit_kick`), [`jaxrod.ProjectedLeapfrog`][] or
    [`jaxrod.ProjectedVerlet`][] and a friction law ([`jaxrod.Coulomb`][], [`jaxrod.Tanh`][]),
    in sweeps and under `jit`/`vmap`; state: [`Rod3DPosition`][], [`Rod3DVelocity`][] (`initial_state`).

    **Arguments:**

    - `rod`: the [`jaxrod.RodChannel`][] (material, section, clearance R, μ_s, μ_d).
    - `n_segments`: number of segments n ≥ 4 (static; default 100).
    - `channel`: with the channel wall (`True`) or a free rod in space (`False`, static).
    - `ends`: `"pinned"` (end nodes held, rotations free: the rod may spin about its axis at
      the ends, so under a high load its interior can roll sideways as a whole), `"fork"` (end
      nodes held and the end segments' spin about their axis held, bending rotations free: a
      fork support, the reduced models' pinned ends without rolling of the whole rod),
      `"clamped"` (end nodes held and end segments' rotations held) or `"free"` (static).
    - `control`: `"force"` (ends held where the initial state puts them: a pre-compressed rod
      keeps its axial force until it deforms, E3), `"load"` (a dead load: node n free along x
      and pushed by the constant force `end_load`, as in the reduced models) or
      `"displacement"` (node 0 held, node n pushed along −x at `speed`, E1) (static).
    - `end_load`: the dead load [N] for `control="load"`.
    - `load_rate`: with `control="load"`, the load's rise [N/s] from `end_load` at t = 0 (static,
      default 0; a rising load is never frozen as stuck; the energy balance omits its work).
    - `preload`: for `control="force"`, the uniform compressive force [N] at which the straight
      rod's ends are held (the default `F` of `initial_state` and `perturbed_state`); it sets
      the buckling threshold (see `buckle_threshold`).
    - `speed`: pushing speed [m/s] for displacement control (negative: pulled back, to unload).
    - `far_load`: with displacement control, node 0 free along x and held back by this dead load
      [N] (the rod slides against it: a bit on a rock); `None` (default): node 0 held (static).
    - `contact_stiffness`: Hertz constant k [N/m^2.5] per length; default: the rod sinks δ₀ = 1e-3·R
      under its weight, k = w/δ₀^{3/2}. Past `wrinkling_load` (≈ 50 N for the reference rod) only the
      friction at the contact point keeps the rod from wrinkling into the wall (docs/rod3d.md).
    - `contact_damping`: Hunt–Crossley ζ [s/m], ≥ 0 (default 0: energy is conserved at μ = 0).
    - `damping`: mass-proportional viscous damping [1/s] on translations, ≥ 0 (default 0).
    - `rotary_scale`: α ≥ 1 on the transverse rotary inertia (default: see module docstring).
    - `friction_sweeps`: the most projected Gauss–Seidel sweeps of the red–black friction pass
      per half step (static, default 64; 1: a single sweep, the coupled impulses of
      neighbouring nodes then left unconverged, which lets held contacts creep).
    - `friction_tol`: the pass stops once no contact impulse changes by more than this
      fraction of the largest friction bound μ_s N h in a sweep (default 1e-4); each pass
      starts from the last one's impulses (2–9 sweeps, 5–7 for a held rod). The last pass's residual
      and sweeps: `v.residual`, `v.sweeps` (observables `friction_residual`, `friction_sweeps`).
    - `friction_at`: `"surface"` (default: friction at the contact point, so it also rolls and
      twists the rod) or `"axis"` (at the centre line: sliding only, no rolling, as the reduced
      models assume) (static).
    - `friction_precision`: `"float32"` (default) or `"float64"`, the dtype of the friction pass
      (static; positions and forces stay float64, docs/physics.md §7, which gives the step's
      saving and the amplitudes' change); a `friction_tol` below ~1e-6 is not reached;
      forward-mode derivatives run in float64 (`for_tangents`).
    - `body_force`: extra force per length [N/m], a 3-vector or one per node (n + 1, 3) (default 0).
    - `gravity`: include gravity (static, default True).
    """

    held_is_fixed: ClassVar[bool] = False  # a stuck rod can creep at the contact (issue [rod3d])
    scheme: ClassVar[str] = "implicit"  # `jaxrod.ImplicitLeapfrog` (docs/rod3d.md, "The implicit step")
    implicit_step: ClassVar[float] = hessian.IMPLICIT_DT  # its step [s], set by accuracy

    rod: RodChannel
    n_segments: int = eqx.field(static=True)
    channel: bool = eqx.field(static=True)
    ends: str = eqx.field(static=True)
    control: str = eqx.field(static=True)
    gravity: bool = eqx.field(static=True)
    friction_sweeps: int = eqx.field(static=True)
    friction_tol: Float[Array, ""]
    friction_at: str = eqx.field(static=True)
    friction_precision: str = eqx.field(static=True)
    speed: Float[Array, ""]
    end_load: Float[Array, ""]
    load_rate: float = eqx.field(static=True)
    far_loaded: bool = eqx.field(static=True)
    far_load: Float[Array, ""]
    preload: Float[Array, ""]
    contact_stiffness: Float[Array, ""]
    contact_damping: Float[Array, ""]
    damping: Float[Array, ""]
    rotary_scale: Float[Array, ""]
    shear_coefficient: Float[Array, ""]
    body_force: Float[Array, "3"] | Float[Array, "n1 3"]

    def __init__(
        self,
        rod: RodChannel,
        n_segments: int = 100,
        *,
        channel: bool = True,
        ends: str = "pinned",
        control: str = "force",
        speed: ArrayLike = 0.0,
        end_load: ArrayLike = 0.0,
        load_rate: float = 0.0,
        far_load: ArrayLike | None = None,
        preload: ArrayLike = 0.0,
        contact_stiffness: ArrayLike | None = None,
        contact_damping: ArrayLike = 0.0,
        damping: ArrayLike = 0.0,
        rotary_scale: ArrayLike | None = None,
        friction_sweeps: int = 64,
        friction_tol: ArrayLike = 1e-4,
        friction_at: str = "surface",
        friction_precision: str = "float32",
        body_force: ArrayLike = (0.0, 0.0, 0.0),
        gravity: bool = True,
    ):
        if not (isinstance(n_segments, (int, np.integer)) and n_segments >= 4):
            raise ValueError(f"Rod3D.n_segments = {n_segments!r} is invalid: expected an int >= 4.")
        self.rod = rod
        self.n_segments = int(n_segments)
        self.channel = bool(channel)
        self.ends, self.control = ends, control
        self.gravity = bool(gravity)
        self.speed = float_leaf(speed)
        self.end_load = float_leaf(end_load)
        self.load_rate = float(load_rate)
        self.far_loaded, self.far_load = far_load is not None, float_leaf(0.0 if far_load is None else far_load)
        self.preload = float_leaf(preload)
        l0 = rod.L / n_segments
        if contact_stiffness is None:
            contact_stiffness = rod.w / (1e-3 * rod.R) ** 1.5
        self.contact_stiffness = float_leaf(contact_stiffness)
        self.contact_damping = float_leaf(contact_damping)
        self.damping = float_leaf(damping)
        kappa = 6.0 * (1.0 + rod.nu) / (7.0 + 6.0 * rod.nu)
        self.shear_coefficient = float_leaf(kappa)
        if rotary_scale is None:
            # 4√(κG/ρ_v)/(d√α) = 2c/l̂  ⇒  α = 4 κ (G/E) (l̂/d)²
            rotary_scale = jnp.maximum(1.0, 4.0 * kappa * (rod.G / rod.E) * (l0 / rod.d) ** 2)
        self.rotary_scale = float_leaf(rotary_scale)
        self.body_force = float_leaf(body_force)
        self.friction_sweeps = friction_sweeps
        self.friction_tol = float_leaf(friction_tol)
        self.friction_at, self.friction_precision = friction_at, friction_precision

    __check_init__ = check_arguments

    # -- discretisation --------------------------------------------------------------------
    n = property(lambda self: self.n_segments)
    l0 = property(lambda self: self.rod.L / self.n, doc="Reference segment length l̂ = L/n [m].")

    @property
    def voronoi(self) -> Float[Array, " n1"]:
        """Length l̄ᵢ attached to each node [m]."""
        w = jnp.ones(self.n + 1).at[0].set(0.5).at[-1].set(0.5)
        return w * self.l0

    mass = property(lambda self: self.rod.rho * self.voronoi)

    @property
    def inertia(self) -> Float[Array, "3"]:
        """Segment rotary inertia in the material frame [kg·m²]."""
        I = self.rod.I
        return self.rod.rho_v * self.l0 * jnp.stack([self.rotary_scale * I, self.rotary_scale * I, 2.0 * I])

    g_vec = property(lambda self: jnp.stack([0.0, 0.0, -1.0]) * (self.rod.g if self.gravity else 0.0 * self.rod.g))

    def held(self) -> tuple[Bool[Array, "n1 3"], Bool[Array, "n 3"]]:
        """Node velocity components prescribed, segment spins held at zero (`state.held_pattern`)."""
        return tuple(jnp.asarray(a) for a in held_pattern(self))

    def prescribed_velocity(self) -> Float[Array, "n1 3"]:
        """Velocity of the held nodes (the pushed end moves along −x at `speed`)."""
        v = jnp.zeros((self.n + 1, 3), dtype=self.speed.dtype)
        if self.control == "displacement":
            v = v.at[-1, 0].set(-self.speed)
        return v

    # -- energies (`jaxrod.rod3d.energy`) ------------------------------------------------------
    strains, elastic_terms, penetration = energy.strains, energy.elastic_terms, energy.penetration  # (x, Q), (x, Q), (x)
    contact_energy, external_energy = energy.contact_energy, energy.external_energy  # (x)
    potential, kinetic_terms = energy.potential, energy.kinetic_terms  # (x, Q), (v, w)

    def energy_terms(self, q: Rod3DPosition, v: Rod3DVelocity, t=None) -> dict[str, Float[Array, ""]]:
        """Every energy by kind [J]: kinetic, rotational, stretch, shear, bend, twist,
        gravity (+ body force and the dead end load), contact."""
        out = self.kinetic_terms(v.v, v.w)
        out.update(self.elastic_terms(q.x, q.Q))
        out["gravity"] = self.external_energy(q.x)
        out["contact"] = self.contact_energy(q.x)
        return out

    def kinetic_energy(self, v: Rod3DVelocity) -> Float[Array, ""]:
        return sum(self.kinetic_terms(v.v, v.w).values())

    # -- the model interface: the pieces of a projected step (leapfrog or Verlet) --------------
    def acceleration(self, q: Rod3DPosition, t=None) -> Rod3DForces:
        """The conservative forces at `q` (those of a rod at rest)."""
        return self.accelerations(q, at_rest(q), t)

    def accelerations(self, q: Rod3DPosition, v: Rod3DVelocity, t=None) -> Rod3DForces:
        """Forces, torques and wall forces at `q` with velocities `v` (contact and viscous
        damping depend on them), and the friction pass's fields there (`friction_table`)."""
        f, tau, N, fd = self.forces(q.x, q.Q, v.v)
        if self.load_rate and t is not None:  # the rise of the dead load (`load_rate`)
            f = f.at[-1, 0].add(-self.load_rate * t)
        return Rod3DForces(f, tau, N, fd, friction_table(self, q.x, q.Q, N))

    def kick(self, q, v: Rod3DVelocity, a: Rod3DForces, h) -> Rod3DVelocity:
        """Node velocities by f/m, spins by Euler's equations J ω̇ = τ − ω × Jω; held degrees of
        freedom keep their prescribed values."""
        J, W = c3.unpack(self.inertia), c3.unpack(v.w)
        gyro, tau = c3.gyroscopic(J, W), c3.unpack(a.tau)
        w = c3.pack(tuple(W[k] + h * (tau[k] - gyro[k]) / J[k] for k in range(3)))
        vn = v.v + h * a.f / self.mass[:, None]
        vn, w = self.constrain(vn, w)
        return Rod3DVelocity(vn, w, v.stuck, v.force, v.residual, v.sweeps)

    implicit_kick = hessian.implicit_kick  # (q, v, a, hk, h, beta, gamma): `jaxrod.ImplicitLeapfrog`'s kick
    damping_loss = hessian.damping_loss  # the energy its numerical damping removes (`ImplicitLeapfrog.kick_loss`)
    coupled_kick = coupled.coupled_kick  # the kick and the wall friction on the step's operator (`ImplicitLeapfrog(coupled=True)`)
    step_error = _error.step_error  # a step's local error estimate (`AdaptiveImplicitLeapfrog`)

    def drift(self, q: Rod3DPosition, v: Rod3DVelocity, h) -> Rod3DPosition:
        """x ← x + h v, Q ← exp(−h [ω]×) Q."""
        W = c3.unpack(v.w)
        # −hω as arrays of their own: a step h that is not a compile-time constant (the engine's
        # zero step of a finished run) otherwise costs 7 µs of the 100 at 500 segments
        phi = computed_once(c3.scale(-h, W), W[0])
        Q = computed_once(sum(c3.rotate(phi, c3.unpack_matrix(q.Q)), ()), q.Q[:, 0, 0])
        return Rod3DPosition(q.x + h * v.v, c3.pack_matrix((Q[0:3], Q[3:6], Q[6:9])))

    def friction_bounds(self, t=None):
        """(μ_s, μ_d): the bounds are μ N per contact, N from the state (`friction_update`)."""
        return self.rod.mu_s, self.rod.mu_d

    def friction_update(self, friction, v_trial: Rod3DVelocity, v_prev: Rod3DVelocity, h, t=None,
                        q: Rod3DPosition | None = None, a: Rod3DForces | None = None) -> Rod3DVelocity:
        """The wall friction impulses of a (half) step `h` at the contact points of `q` (their
        fields: `a.table`); a step of zero length changes nothing (not even the stuck flags)."""
        v, w, stuck, force, res, sweeps = self.friction_step(friction, a.table, q.Q, v_trial.v, v_trial.w,
                                                             v_prev.stuck, v_trial.force, h)
        v, w = self.constrain(v, w)
        moved = h > 0
        return Rod3DVelocity(v, w, jnp.where(moved, stuck, v_prev.stuck), jnp.where(moved, force, v_trial.force),
                             jnp.where(moved, res, v_trial.residual), jnp.where(moved, sweeps, v_trial.sweeps))

    def impulse_work(self, v_prev, v_trial, v_after, a: Rod3DForces, h):
        """`(lost, work_in)` over a half step `h` [J] (`jaxrod.rod3d.energy.impulse_work`)."""
        return energy.impulse_work(self, v_prev, v_trial, v_after, a, h)

    def amplitude(self, q: Rod3DPosition) -> Float[Array, ""]:
        """max |θ| over the interior nodes [rad] (`jaxrod.rod3d.measures.amplitude`)."""
        return measures.amplitude(self, q)

    def stop_measures(self, q, v: Rod3DVelocity, a, t=None):
        """The amplitude and the stick test after a step (`jaxrod.rod3d.measures.stop_measures`)."""
        return measures.stop_measures(self, q, v, a)

    def is_stuck(self, q, v: Rod3DVelocity, a, t=None):  # at the start of a run: `measures.is_stuck`
        return measures.is_stuck(self, q, v, a)

    @property
    def autonomous(self) -> bool:
        return self.control != "displacement" and not self.load_rate

    @property
    def buckle_threshold(self) -> Float[Array, ""]:
        """The buckling amplitude [rad] of this control (`jaxrod.rod3d.measures.buckle_threshold`)."""
        return measures.buckle_threshold(self)

    axial_preload = state.axial_preload  # the straight rod's axial force [N] (`state.axial_preload`)

    def observables(self, q: Rod3DPosition, v: Rod3DVelocity, a: Rod3DForces, t=None) -> dict:
        """What a save records (`jaxrod.rod3d.measures.observables` lists them)."""
        return measures.observables(self, q, v, a)

    # -- forces and friction ---------------------------------------------------------------
    generalized_forces = energy.generalized_forces  # (x, Q)
    contact_normal = energy.contact_normal  # (x, v)
    forces = energy.forces  # (x, Q, v)

    def friction_step(self, friction, table, Q, v, w, stuck, force, h):
        """The friction impulses of a (half) step `h` [s]: `contact.friction_pass`."""
        return friction_pass(self, friction, table, Q, v, w, stuck, force, h)

    # -- constraints and the step limit -------------------------------------------------------
    def constrain(self, v, w):
        held_n, held_s = self.held()
        return jnp.where(held_n, self.prescribed_velocity(), v), jnp.where(held_s, 0.0, w)

    def max_frequency(self, q: Rod3DPosition | None = None) -> Float[Array, ""]:
        """ω_max [rad/s] at `q` (default: straight, preloaded): `jaxrod.rod3d.stiffness.frequency_bound`."""
        return frequency_bound(self, q)

    static_sag = state.static_sag  # the rod's sink into the wall under its weight [m] (`state.static_sag`)
    wrinkling_load = state.wrinkling_load  # the axial force [N] past which the straight rod wrinkles into the wall
    implicit_inadequate = state.implicit_inadequate  # (coupled) -> `ImplicitLeapfrog` outside its measured range here
    initial_state = straight_state  # (F=None, lateral_velocity=None, lateral_offset=None) -> (q0, v0)

    # -- where a perturbation field is given (the AbstractModel interface) -------------------
    def sample_points(self) -> Float[Array, " n1"]:
        """The n + 1 nodes of the straight rod, s_j = jL/n [m] (ends included)."""
        return jnp.arange(self.n + 1, dtype=self.rod.L.dtype) * (self.rod.L / self.n)

    @property
    def resolved_modes(self) -> int:
        """n − 1: the sine modes the n − 1 interior nodes carry."""
        return self.n - 1

    def from_samples(self, values):
        raise TypeError("Rod3D has no coordinates per sample point: a lateral field becomes a state through "
                        "Rod3D.perturbed_state (UserState fields are not available with the 3D rod).")

    translation = lambda self, q, v: (q.x, v.v)  # positions and velocities: spins are not rates of the directors

    def for_tangents(self) -> Rod3D:
        """This rod with a float64 friction pass (float32 tangents overflow at a vanishing slip)."""
        new = copy.copy(self)
        object.__setattr__(new, "friction_precision", "float64")  # a static field
        return new

    def under_lateral_force(self, force) -> Rod3D:
        """This rod with the lateral (y) force per length `force` [N/m] at its nodes added to `body_force`."""
        lateral = jnp.stack([0.0 * force, force, 0.0 * force], -1)
        return eqx.tree_at(lambda m: m.body_force, self, energy._body_force(self) + lateral)

    perturbed_state = lambda self, offset, velocity: self.initial_state(None, lateral_velocity=velocity, lateral_offset=offset)

    # -- the rest of the interface: the fixed-step schemes only (friction is an impulse pass) -------
    def friction_acceleration(self, friction, v, t):
        raise NotImplementedError("Rod3D runs with the fixed-step schemes only (its friction is an impulse pass).")


    theta = staticmethod(wall_angle)  # (x) -> each node's angle from the channel bottom [rad], θ of the field model
    axial_force = energy.axial_force  # (x, Q) -> each segment's compressive axial force −EA σ₃ [N]
