"""The interface every model implements: what the integrators, the engine and the perturbations
ask of a model: eight abstract methods, and defaults for the rest; the shared per-degree-of-freedom
machinery of the reduced models is in [`jaxrod.models.dof.AbstractDOFModel`][], and how a problem
is posed for a model is its recipe's ([`jaxrod.models.recipe`][])."""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

__all__ = ["AbstractModel", "friction_work"]


class AbstractModel(eqx.Module):
    """A mechanical system `M q̈ = −∇V(q, t) − friction(q̇)`, M constant and diagonal, with
    friction a bounded force per friction point: what the integrators and the engine ask of a
    model.

    **Abstract** (what a model must write): `accelerations`, `friction_bounds`, `energy_terms`,
    `kinetic_energy`, `max_frequency`, `autonomous`, `amplitude`, `stop_measures`. The other
    methods have defaults for a model whose state is one array with friction per degree of
    freedom (the kick v + h a, the drift q + h v, the per-DOF friction law with
    `friction_bounds`, friction's work by `friction_work`); a model with another state (the 3D
    rod) overrides them. How a problem is posed for a model (its size, step, scheme, initial
    state, search) is its recipe's ([`jaxrod.models.recipe.AbstractRecipe`][]), registered with
    the model's name ([`jaxrod.registry.register_model`][]). Accelerations and the friction
    bounds are in the model's coordinates with the mass scaled out; energies in the model's
    energy unit (J for the rod models).
    """

    # whether a state that passes the stick test stays put under the sharp law's projected
    # step (true for the per-DOF prox; the 3D rod's contact keeps it from being exact)
    held_is_fixed: ClassVar[bool] = True
    # the fixed-step scheme a run of this model uses by default (`jaxrod.integrators.default_for`):
    # "verlet" (projected Verlet), "leapfrog" (one friction pass per step) or "implicit"
    scheme: ClassVar[str] = "verlet"

    # -- forces and energies (abstract) ---------------------------------------------------------

    @abc.abstractmethod
    def accelerations(self, q, v, t):
        """What a kick needs at (q, t) with velocities `v` (the integrators hold it as `a`)."""

    @abc.abstractmethod
    def friction_bounds(self, t) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
        """Static and dynamic friction bounds per friction point, as accelerations."""

    @abc.abstractmethod
    def energy_terms(self, q, v, t) -> dict[str, Float[Array, ""]]:
        """Named energies (kinetic and the potential parts) at a state."""

    @abc.abstractmethod
    def kinetic_energy(self, v) -> Float[Array, ""]:
        """Kinetic energy of the velocities `v`."""

    @abc.abstractmethod
    def max_frequency(self, q=None) -> Float[Array, ""]:
        """The highest angular frequency of the conservative part [rad/s] (at `q` where it
        depends on the state); a fixed-step explicit scheme is stable for `dt · max_frequency < 2`."""

    # -- stopping (abstract) --------------------------------------------------------------------

    @property
    @abc.abstractmethod
    def autonomous(self) -> bool:
        """Whether the forces do not depend on time (a stuck state then stays stuck)."""

    @abc.abstractmethod
    def amplitude(self, q) -> Float[Array, ""]:
        """The largest deflection angle of the state [rad]."""

    @abc.abstractmethod
    def stop_measures(self, q, v, a, t) -> tuple[Float[Array, ""], Bool[Array, ""]]:
        """`(amplitude(q), is_stuck(q, v, a, t))`, which the time loop needs after every step."""

    # -- the pieces of a step (kick → prox → drift → kick → prox): per-DOF defaults -------------

    def acceleration(self, q, t):
        """The conservative acceleration −M⁻¹∇V at `q`, time `t`, without velocity-dependent
        forces (the per-DOF integrators' `ExplicitFrictionless`, `DiffraxSmooth`; none by default)."""
        raise NotImplementedError(f"{type(self).__name__} has no velocity-free acceleration (use its accelerations).")

    def kick(self, q, v, a, h):
        """Velocities after a kick of `h` [s] with `a` (no friction): v + h a."""
        return v + h * a

    def drift(self, q, v, h):
        """Coordinates after moving `h` [s] with the velocities `v`: q + h v."""
        return q + h * v

    def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
        """Velocity after the friction impulse of a step `h` [s] under the law `friction`: the
        per-DOF law's update with the bounds of `friction_bounds`."""
        f_s, f_d = self.friction_bounds(t)
        return friction.update(v_trial, v_prev, h, f_s, f_d)

    def friction_acceleration(self, friction, v, t):
        """The friction acceleration opposing `v`, for ODE solvers (per DOF)."""
        f_s, f_d = self.friction_bounds(t)
        return friction.acceleration(v, f_s, f_d)

    def impulse_work(self, v_prev, v_trial, v_after, a, h):
        """`(lost, work_in)` over a half step `h`: the energy friction (and any damping) removed,
        per degree of freedom (`friction_work`), and the work done by driven boundaries [J]
        (none by default)."""
        return friction_work(self, v_prev, v_trial, v_after), jnp.zeros((), jnp.result_type(float))

    def linear_flow(self, q, v, t, h):
        """Exact flow of the conservative (linear) part over `h` [s] (only the documented
        failure case [`jaxrod.SplitLinearFriction`][] needs it; by default there is none)."""
        raise NotImplementedError(f"{type(self).__name__} has no exact linear flow (SplitLinearFriction needs one).")

    def check(self) -> Bool[Array, ""]:
        """Whether the model's parameters are valid (for result codes under vmap; by default the
        model checks its arguments when it is made, and this is true)."""
        return jnp.array(True)

    # -- stopping and reading: defaults ---------------------------------------------------------

    @property
    def buckle_threshold(self):
        """Default amplitude past which a run counts as buckled and stops (`inf`: never, the default)."""
        return math.inf

    def is_stuck(self, q, v, a, t) -> Bool[Array, ""]:
        """Whether the whole system is at rest and held by static friction, given `a` (`stop_measures`)."""
        return self.stop_measures(q, v, a, t)[1]

    def observables(self, q, v, a, t) -> dict:
        """Model-specific quantities recorded at every save (none by default)."""
        return {}

    # -- perturbations and derivatives: defaults ------------------------------------------------

    def sample_points(self) -> Float[Array, " n"]:
        """Arc-length positions s [m] at which a lateral field is given to this model (none by default)."""
        raise TypeError(f"{type(self).__name__} takes no field perturbation: it has no sample points.")

    def from_samples(self, values):
        """The model's coordinates of a field given at `sample_points`."""
        raise TypeError(f"{type(self).__name__} has no coordinates per sample point.")

    @property
    def resolved_modes(self) -> int:
        """How many sine modes sin(mπs/L) a field given at `sample_points` can carry (static):
        by default one per sample point."""
        return self.sample_points().shape[-1]

    def perturbed_state(self, offset, velocity):
        """The initial state (q₀, v₀) of the rod displaced laterally by `offset` [m] and moving
        laterally at `velocity` [m/s], both given at `sample_points`."""
        raise TypeError(f"{type(self).__name__} takes no field perturbation.")

    def under_lateral_force(self, force) -> AbstractModel:
        """This model with a constant lateral force per length `force` [N/m] (at `sample_points`)."""
        raise TypeError(f"{type(self).__name__} takes no lateral force.")

    def translation(self, q, v):
        """The coordinates of `q` and the velocities of `v` that are their time derivatives, as two
        pytrees of one structure (the boundary search's departure rate projects one on the
        other): `(q, v)` by default."""
        return q, v

    def for_tangents(self) -> AbstractModel:
        """This model as forward-mode derivatives of its runs need it (itself by default)."""
        return self


def friction_work(model: AbstractModel, v_prev, v_trial, v_after):
    """Energy friction dissipated by an impulse that took `v_trial` to `v_after` over a
    (half) step that began at velocity `v_prev`, per degree of freedom (shape of `v`): the
    impulse times the mean velocity over the step, (v_trial − v_after)·M·(v_prev + v_after)/2
    (a midpoint rule for ∫ f|v| dt). Zero for a point held at rest: it does not move, so
    friction does no work on it. Kept per degree of freedom and summed only at the saves: a sum
    over the nodes at every step costs as much as the rest of the step's bookkeeping."""
    return jax.grad(model.kinetic_energy)(0.5 * (v_prev + v_after)) * (v_trial - v_after)


