"""The interface every model implements."""

from __future__ import annotations

from typing import ClassVar

import abc
import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

__all__ = ["AbstractModel", "friction_work"]


class AbstractModel(eqx.Module):
    """A mechanical system `M q̈ = −∇V(q, t) − friction(q̇)`, M constant and diagonal, with
    friction a bounded force per friction point.

    Integrators use only these methods, so any model that implements them runs with every
    integrator. `acceleration` and the friction bounds are in the model's coordinates with the
    mass scaled out; energies are in the model's energy unit (J for the rod models).
    """

    # whether a state that passes the stick test stays put under the sharp law's projected
    # step (true for the per-DOF prox; the 3D rod's contact keeps it from being exact)
    held_is_fixed: ClassVar[bool] = True
    # the fixed-step scheme a run of this model uses by default (`jaxrod.integrators.default_for`):
    # "verlet" (projected Verlet) or "leapfrog" (projected leapfrog: one friction pass per step,
    # for models whose friction pass is most of a step)
    scheme: ClassVar[str] = "verlet"

    @abc.abstractmethod
    def acceleration(self, q: Float[Array, "..."], t) -> Float[Array, "..."]:
        """The conservative (elastic + load + gravity) acceleration −M⁻¹∇V at `q`, time `t`."""

    @abc.abstractmethod
    def friction_bounds(self, t) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
        """Static and dynamic friction bounds per degree of freedom, as accelerations."""

    @abc.abstractmethod
    def energy_terms(self, q, v, t) -> dict[str, Float[Array, ""]]:
        """Named energies (kinetic and the potential parts) at a state."""

    @abc.abstractmethod
    def kinetic_energy(self, v: Float[Array, "..."]) -> Float[Array, ""]:
        """Kinetic energy of the velocities `v`."""

    @abc.abstractmethod
    def max_frequency(self) -> Float[Array, ""]:
        """The highest angular frequency of the conservative part [rad/s]; a fixed-step
        explicit integrator is stable for `dt · max_frequency < 2`."""

    # -- where a perturbation field is sampled (rod models along s) -------------------------

    def sample_points(self) -> Float[Array, " n"]:
        """Arc-length positions s [m] at which a lateral field is given to this model."""
        raise TypeError(
            f"{type(self).__name__} takes no field perturbation: it has no sample points (for "
            "SingleMode use jaxrod.perturbations.project_to_mode)."
        )

    def from_samples(self, values: Float[Array, " n"]) -> Float[Array, "..."]:
        """The model's coordinates of a field given at `sample_points` (identity for nodal
        models; a projection for modal ones)."""
        return values

    @property
    def resolved_modes(self) -> int:
        """How many sine modes sin(mπs/L) a field given at `sample_points` can carry (static):
        one per sample point by default."""
        return self.sample_points().shape[-1]

    def perturbed_state(self, offset: Float[Array, " n"], velocity: Float[Array, " n"]):
        """The initial state (q₀, v₀) of the rod in its reference state, displaced laterally by
        `offset` [m] and moving laterally at `velocity` [m/s], both given at `sample_points`.
        Default: θ = offset/R and θ̇ = velocity/R in the model's coordinates."""
        R = self.rod.R
        return self.from_samples(offset / R), self.from_samples(velocity / R)

    def translation(self, q, v):
        """The coordinates of `q` and the velocities of `v` that are their time derivatives, as
        two pytrees of one structure (the boundary search's departure rate projects one on the
        other). Default: `(q, v)` themselves."""
        return q, v

    def for_tangents(self) -> AbstractModel:
        """This model as forward-mode derivatives of its runs need it (the departure rate's
        tangents): itself by default; the 3D rod runs its friction pass in float64."""
        return self

    def under_lateral_force(self, force: Float[Array, " n"]) -> AbstractModel:
        """This model with a constant lateral force per length `force` [N/m] added, given at
        `sample_points` (the forcing phase of `jaxrod.RandomForce`). Default: the acceleration
        force/(ρR) in the model's coordinates (`from_samples`)."""
        return _Forced(self, self.from_samples(force / (self.rod.rho * self.rod.R)))

    # -- defaults that models with per-DOF friction and a constant load inherit ----------------

    @property
    def autonomous(self) -> bool:
        """Whether the forces do not depend on time (a stuck state then stays stuck)."""
        return True

    @property
    def buckle_threshold(self) -> float:
        """Default amplitude past which the run counts as buckled and stops (`inf`: never)."""
        return math.inf

    def amplitude(self, q) -> Float[Array, ""]:
        """The largest deflection of the state (rad)."""
        return jnp.max(jnp.abs(q))

    # -- the pieces of a step (kick → prox → drift → kick → prox); per-DOF defaults -----------

    def accelerations(self, q, v, t):
        """What a kick needs at (q, t) with velocities `v` (the integrators hold it as `a`):
        the conservative acceleration for the per-DOF models (a model with velocity-dependent
        forces, such as the 3D rod's contact damping, returns more)."""
        return self.acceleration(q, t)

    def kick(self, q, v, a, h):
        """Velocities after a kick of `h` [s] with `a` (no friction)."""
        return v + h * a

    def drift(self, q, v, h):
        """Coordinates after moving `h` [s] with the velocities `v`."""
        return q + h * v

    def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
        """Velocity after the friction impulse of a step `h` (per-DOF law; `q` and `a`, the
        state the impulse acts at, are used by models whose friction depends on them)."""
        f_s, f_d = self.friction_bounds(t)
        return friction.update(v_trial, v_prev, h, f_s, f_d)

    def impulse_work(self, v_prev, v_trial, v_after, a, h):
        """`(lost, work_in)` over a half step `h`: the energy friction (and any damping)
        removed, per degree of freedom (see `friction_work`), and the work done on the system
        by driven boundaries [J] (none here)."""
        return friction_work(self, v_prev, v_trial, v_after), jnp.zeros((), jnp.result_type(float))

    def observables(self, q, v, a, t) -> dict:
        """Model-specific quantities recorded at every save (none for the reduced models)."""
        return {}

    def friction_acceleration(self, friction, v, t):
        """The friction acceleration opposing `v`, for ODE solvers (per-DOF law)."""
        f_s, f_d = self.friction_bounds(t)
        return friction.acceleration(v, f_s, f_d)

    def is_stuck(self, q, v, a, t) -> Bool[Array, ""]:
        """Whether the whole system is at rest and held by static friction, given `a`, the
        conservative acceleration at (q, t) (the integrators already hold it)."""
        return self.stop_measures(q, v, a, t)[1]

    def stop_measures(self, q, v, a, t) -> tuple[Float[Array, ""], Bool[Array, ""]]:
        """`(amplitude(q), is_stuck(q, v, a, t))`, which the time loop needs after every step.

        Per-DOF default: both from one reduction, the largest of |q| and of
        |v| + max(|a| − f_s, 0), which is zero exactly when every DOF is at rest with
        |a| ≤ f_s (a float difference is zero only for equal floats, and has the right sign).
        On the CPU one fused reduction of two rows costs a third of two separate maxima."""
        f_s, _ = self.friction_bounds(t)
        held = jnp.abs(v) + jnp.maximum(jnp.abs(a) - f_s, 0.0)
        both = jnp.max(jnp.stack([jnp.abs(q), held]).reshape(2, -1), axis=-1)
        return both[0], both[1] == 0

    def linear_flow(self, q, v, t, h):
        """Exact flow of the conservative (linear) part over `h`; only needed by the
        documented failure case [`jaxrod.SplitLinearFriction`][]."""
        raise NotImplementedError(f"{type(self).__name__} has no exact linear flow.")

    def check(self) -> Bool[Array, ""]:
        """Whether the model's parameters are valid (for result codes under vmap)."""
        return jnp.array(True)


def friction_work(model, v_prev, v_trial, v_after):
    """Energy friction dissipated by an impulse that took `v_trial` to `v_after` over a
    (half) step that began at velocity `v_prev`, per degree of freedom (shape of `v`): the
    impulse times the mean velocity over the step, (v_trial − v_after)·M·(v_prev + v_after)/2
    (a midpoint rule for ∫ f|v| dt). Zero for a point held at rest: it does not move, so
    friction does no work on it. Kept per degree of freedom and summed only at the saves: a sum
    over the nodes at every step costs as much as the rest of the step's bookkeeping."""
    return jax.grad(model.kinetic_energy)(0.5 * (v_prev + v_after)) * (v_trial - v_after)


class _Forced(AbstractModel):
    """A model with a constant extra acceleration (`AbstractModel.under_lateral_force`)."""

    inner: AbstractModel
    extra: Float[Array, " n"]

    def acceleration(self, q, t):
        return self.inner.acceleration(q, t) + self.extra

    def friction_bounds(self, t):
        return self.inner.friction_bounds(t)

    def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
        return self.inner.friction_update(friction, v_trial, v_prev, h, t, q, a)

    def friction_acceleration(self, friction, v, t):
        return self.inner.friction_acceleration(friction, v, t)

    def energy_terms(self, q, v, t):
        return self.inner.energy_terms(q, v, t)

    def kinetic_energy(self, v):
        return self.inner.kinetic_energy(v)

    def max_frequency(self):
        return self.inner.max_frequency()
