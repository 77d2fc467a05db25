"""Initial perturbations, as data: each one turns a model into an initial state (q₀, v₀).

All are equinox Modules with array leaves (amplitudes, JAX keys), so a batch of them is a
`vmap` away. Velocities are lateral speeds [m/s] and displacements lateral [m]: the model
divides by the clearance R to get θ̇ and θ.

**Random fields belong to the scene, not to the model.** The reference paper draws them on the
nodes of its 500-segment rod: "a lateral velocity uniform in [−15, 15] mm/s on each node", or
small random lateral forces on all nodes for 1 ms. jaxrod draws them the same way, on `grid`
segments of the rod (default 500: the interior nodes s_j = jL/500), and gives every model the
sine series of that nodal field, r(s) = Σ_m c_m sin(mπs/L), c_m = (2/grid) Σ_j r_j sin(mπj/grid),
truncated to the modes the model resolves (m ≤ its number of sample points). The same key
therefore gives the same modal amplitudes c_m to a field model of any n, a Galerkin model, the
single mode (c_m itself) and the 3D rod, and a finer model resolves more of the same field
instead of receiving new, weaker noise (white noise on a model's own n nodes puts ∝ 1/n of
its energy into each mode, so results drifted with n). `grid=None` restores that per-node
noise.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float, PRNGKeyArray

from ._numerics import float_leaf
from .models.base import AbstractModel

__all__ = [
    "AbstractPerturbation",
    "SineVelocity",
    "RandomVelocity",
    "RandomForce",
    "RandomShape",
    "UserState",
    "initial_state",
    "scene_noise",
    "scene_noise_modes",
    "GRID",
]


GRID = 500  # segments of the scene's noise grid: the reference paper's rod


def scene_noise(key, amplitude, s, L, grid: int | None = GRID, modes: int | None = None):
    """A random field uniform in ±`amplitude` on the interior nodes of `grid` equal segments of a
    rod of length `L` [m], evaluated at the points `s` [m] through its sine series truncated to
    min(grid − 1, `modes`) modes (`modes` default: len(s), what interior points resolve;
    `grid=None`: drawn independently at every point of `s`)."""
    if grid is None:
        return jax.random.uniform(key, s.shape, s.dtype, -1.0, 1.0) * amplitude
    if not (isinstance(grid, int) and grid >= 2):
        raise ValueError(f"grid = {grid!r} is invalid: expected an int >= 2 (segments) or None.")
    c = scene_noise_modes(key, amplitude, grid, min(grid - 1, s.shape[-1] if modes is None else modes), s.dtype)
    m = jnp.arange(1, c.shape[-1] + 1, dtype=s.dtype)
    return jnp.sum(jnp.sin(jnp.pi * s[:, None] * m[None, :] / L) * c[None, :], axis=-1)


def scene_noise_modes(key, amplitude, grid: int = GRID, modes: int | None = None, dtype=None):
    """The sine coefficients c_m, m = 1..`modes` (default grid − 1), of the field that
    `scene_noise` draws from `key`: c_m = (2/grid) Σ_j r_j sin(mπj/grid) [units of `amplitude`]."""
    dtype = dtype or jnp.result_type(float)
    j = jnp.arange(1, grid, dtype=dtype)
    r = jax.random.uniform(key, (grid - 1,), dtype, -1.0, 1.0) * amplitude
    m = jnp.arange(1, (grid - 1 if modes is None else modes) + 1, dtype=dtype)
    # sums rather than matrix products: the same reduction order alone and under vmap, so a
    # sweep member equals its single run bit for bit
    return (2.0 / grid) * jnp.sum(jnp.sin(jnp.pi * m[:, None] * j[None, :] / grid) * r[None, :], axis=-1)


def _noise(p, model, s):
    """The scene noise of a random perturbation `p` at `model`'s sample points `s`."""
    return scene_noise(p.key, p.amplitude, s, model.rod.L, p.grid, modes=model.resolved_modes)


class AbstractPerturbation(eqx.Module):
    """Maps a model to its initial state (θ₀, θ̇₀) in the model's coordinates."""

    # whether the 3D rod's default implicit scheme was measured to give this perturbation's
    # answers (docs/rod3d.md, "The implicit step"): E3's sine velocity yes; the random ones moved E4's
    # ΔF* by 2–23 % at its step, so a 3D scene with them runs the explicit leapfrog (`Scene.scheme`)
    implicit_3d: ClassVar[bool] = False
    # whether the single mode's exact solution answers a boundary search under it (a sine
    # velocity of the mode: `search_method = "exact"`)
    projects_exactly: ClassVar[bool] = False

    @classmethod
    @abc.abstractmethod
    def from_settings(cls, amplitude, mode: int, key, duration) -> AbstractPerturbation:
        """The perturbation from a scene's plain settings: `amplitude` (its unit), the sine
        `mode`, a random `key`, a forcing `duration` [s] (each takes what it uses)."""

    @property
    def least_nodes(self) -> int:
        """Field nodes a model needs to resolve this perturbation (a scene's field model takes
        at least this many): none by default."""
        return 0

    @abc.abstractmethod
    def fields(self, model: AbstractModel) -> tuple[Float[Array, " n"], Float[Array, " n"]]:
        """Lateral displacement [m] and velocity [m/s] at the model's sample points."""

    def initial_state(self, model: AbstractModel, integrator=None):
        """(q₀, v₀) in the model's coordinates (`model.perturbed_state` of the fields)."""
        return model.perturbed_state(*self.fields(model))

    def modal_state(self, mode: int, R, grid):
        """(A₀, Ȧ₀) of sine mode `mode` [rad, rad/s] of a rod of clearance `R` [m]: the state this
        perturbation gives the field model of `grid()` (a model and its integrator), projected
        onto the mode."""
        model, integrator = grid()
        q, v = self.initial_state(model, integrator)
        return project_to_mode(q, mode), project_to_mode(v, mode)


class SineVelocity(AbstractPerturbation):
    """Lateral velocity v(s) = `amplitude`·sin(`mode`·πs/L) [m/s] on a straight rod.

    `amplitude` (v₀ [m/s]) and `mode` (≥ 1) are dynamic leaves. `v0` is a deprecated alias of
    `amplitude`.
    """

    implicit_3d: ClassVar[bool] = True
    projects_exactly: ClassVar[bool] = True

    amplitude: Float[Array, ""] = eqx.field(converter=float_leaf)
    mode: Float[Array, ""] = eqx.field(converter=float_leaf, default=6.0)

    @classmethod
    def from_settings(cls, amplitude, mode, key, duration):
        return cls(amplitude, float(mode))

    def fields(self, model):
        s = model.sample_points()
        v = self.amplitude * jnp.sin(self.mode * jnp.pi * s / model.rod.L)
        return jnp.zeros_like(s), v

    def modal_state(self, mode, R, grid):
        """Exact: a sine velocity field projects onto its own mode only."""
        v = jnp.where(self.mode == mode, self.amplitude / R, 0.0)
        return jnp.zeros_like(v), v


class _AbstractNoiseState(AbstractPerturbation):
    """A random state drawn on the scene's noise grid (`amplitude`, `key`, `grid`): every mode of the
    grid carries as much as the critical one, so a model must resolve them all."""

    amplitude: eqx.AbstractVar[Float[Array, ""]]
    key: eqx.AbstractVar[PRNGKeyArray]
    grid: eqx.AbstractVar[int | None]

    @classmethod
    def from_settings(cls, amplitude, mode, key, duration):
        return cls(amplitude, key)

    @property
    def least_nodes(self) -> int:
        """grid − 1: its high modes decide the result (their vibration releases static friction;
        benchmarks/README.md, "Which model for which scene")."""
        return 0 if self.grid is None else self.grid - 1


class RandomVelocity(_AbstractNoiseState):
    """A lateral velocity of at most `amplitude` [m/s], drawn uniformly in [−`amplitude`,
    `amplitude`] on every node of the scene's noise grid (`grid` segments, static; see the
    module) from `key`; the rod straight."""

    amplitude: Float[Array, ""] = eqx.field(converter=float_leaf)
    key: PRNGKeyArray
    grid: int | None = eqx.field(static=True, default=GRID)

    def fields(self, model):
        s = model.sample_points()
        return jnp.zeros_like(s), _noise(self, model, s)


class RandomShape(_AbstractNoiseState):
    """A lateral displacement of at most `amplitude` [m], drawn uniformly in [−`amplitude`,
    `amplitude`] on every node of the scene's noise grid (`grid` segments, static) from `key`,
    released from rest."""

    amplitude: Float[Array, ""] = eqx.field(converter=float_leaf)
    key: PRNGKeyArray
    grid: int | None = eqx.field(static=True, default=GRID)

    def fields(self, model):
        s = model.sample_points()
        return _noise(self, model, s), jnp.zeros_like(s)


class RandomForce(AbstractPerturbation):
    """The reference paper's random position perturbation: lateral forces per unit length
    of at most `amplitude` [N/m], drawn uniformly in [−`amplitude`, `amplitude`] on every node
    of the scene's noise grid (`grid` segments, static) act on the loaded, straight rod
    (friction included) for `duration` [s] (default 1 ms); the rod is then released from rest
    in the shape they produced.

    The forcing phase is integrated with the run's fixed-step integrator (required).
    """

    amplitude: Float[Array, ""] = eqx.field(converter=float_leaf)
    key: PRNGKeyArray
    duration: Float[Array, ""] = eqx.field(converter=float_leaf, default=1e-3)
    grid: int | None = eqx.field(static=True, default=GRID)

    @classmethod
    def from_settings(cls, amplitude, mode, key, duration):
        return cls(amplitude, key, duration)

    def fields(self, model):
        s = model.sample_points()
        return _noise(self, model, s), jnp.zeros_like(s)

    def initial_state(self, model, integrator=None):
        from .integrators.base import AbstractFixedStep

        if not isinstance(integrator, AbstractFixedStep):
            raise TypeError(
                "RandomForce needs the run's fixed-step integrator (e.g. ProjectedVerlet) to "
                f"integrate its forcing phase; got {type(integrator).__name__}."
            )
        force, _ = self.fields(model)
        forced = model.under_lateral_force(force)
        q, v = model.perturbed_state(jnp.zeros_like(force), jnp.zeros_like(force))
        a = forced.acceleration(q, 0.0)
        h = jnp.asarray(integrator.dt, force.dtype)
        n = jnp.maximum(jnp.ceil(self.duration / h), 1.0)
        h = self.duration / n

        def body(i, c):
            q, v, a = c
            q, v, a, _ = integrator.step(forced, q, v, a, i.astype(h.dtype) * h, h)
            return q, v, a

        q, v, a = jax.lax.fori_loop(0, n.astype(jnp.int32), body, (q, v, a))
        return q, jax.tree_util.tree_map(jnp.zeros_like, v)  # released from rest


class UserState(AbstractPerturbation):
    """Any initial state given directly in the model's coordinates: `q0` [rad] and `v0`
    [rad/s] (θ, θ̇ at the nodes of a field model; modal amplitudes of a Galerkin model)."""

    q0: Float[Array, " n"] = eqx.field(converter=float_leaf)
    v0: Float[Array, " n"] = eqx.field(converter=float_leaf)

    @classmethod
    def from_settings(cls, amplitude, mode, key, duration):
        raise TypeError("UserState is given as a state, not from a scene's settings.")

    def fields(self, model):
        return self.q0 * model.rod.R, self.v0 * model.rod.R

    def initial_state(self, model, integrator=None):
        return self.q0, self.v0


def project_to_mode(
    theta: Float[Array, " n"], mode: ArrayLike
) -> Float[Array, ""]:
    """Amplitude of sine mode `mode` in a field θ given at n equally spaced interior nodes
    (used to start the single-mode model from a field perturbation)."""
    n = theta.shape[-1]
    j = jnp.arange(1, n + 1, dtype=theta.dtype)
    return (2.0 / (n + 1)) * jnp.sum(theta * jnp.sin(jnp.pi * j * float_leaf(mode) / (n + 1)))


def initial_state(perturbation: AbstractPerturbation, model, integrator=None):
    """`perturbation.initial_state(model, integrator)`: (q₀, v₀) in the model's coordinates."""
    return perturbation.initial_state(model, integrator)
