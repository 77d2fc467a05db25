"""The shared machinery of the models whose friction acts per degree of freedom (or per sample
point of a field): [`AbstractDOFModel`][jaxrod.models.dof.AbstractDOFModel], the rod models with
a rod and an axial load ([`AbstractRodDOFModel`][jaxrod.models.dof.AbstractRodDOFModel]: the
field and Galerkin models) with their recipe ([`RodDOFRecipe`][jaxrod.models.dof.RodDOFRecipe]),
and the lateral force of a random position perturbation's forcing phase as a wrapper that
forwards the whole interface."""

from __future__ import annotations

from typing import ClassVar

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import theory
from ..loads import AbstractLoad, as_load
from ..params import RodChannel
from .base import AbstractModel
from .recipe import AbstractRecipe

__all__ = ["AbstractDOFModel", "AbstractRodDOFModel", "RodDOFRecipe", "DT_FRACTION", "GROWTH_FRACTION", "static_float"]

DT_FRACTION = 0.4  # a scene's step: this fraction of the explicit step limit 2/ω_max at ΔF = 0
GROWTH_FRACTION = 0.25  # ... and at most this fraction of 1/λ_max, the loaded rod's fastest growth


def static_float(fn, message: str) -> float:
    """`fn()` as a Python float from concrete values, or a `ValueError(message)` when traced."""
    try:
        with jax.ensure_compile_time_eval():
            return float(fn())
    except jax.errors.ConcretizationTypeError:
        raise ValueError(message) from None


class AbstractDOFModel(AbstractModel):
    """A model with friction per degree of freedom (or per sample point), whose state is one
    array: the conservative `acceleration` (abstract) is what a kick needs, a stick test per DOF,
    and a lateral field's coordinates are its samples. With the defaults of `AbstractModel` (the
    kick, drift, per-DOF friction and its work) a subclass writes its forces, friction bounds,
    energies, highest frequency and, to take field perturbations, its `sample_points`."""

    @abc.abstractmethod
    def acceleration(self, q, t):
        """The conservative (elastic + load + gravity) acceleration −M⁻¹∇V at `q`, time `t`."""

    def accelerations(self, q, v, t):
        """The conservative acceleration (no velocity-dependent forces)."""
        return self.acceleration(q, t)

    # -- stopping ---------------------------------------------------------------------------------

    @property
    def autonomous(self) -> bool:
        return True

    def amplitude(self, q) -> Float[Array, ""]:
        return jnp.max(jnp.abs(q))

    def stop_measures(self, q, v, a, t):
        """Both from one reduction, the largest of |q| and of |v| + max(|a| − f_s, 0), which is
        zero exactly when every DOF is at rest with |a| ≤ f_s (a float difference is zero only
        for equal floats, and has the right sign); one fused reduction of two rows is cheaper
        than two separate maxima."""
        f_s, _ = self.friction_bounds(t)
        held = jnp.abs(v) + jnp.maximum(jnp.abs(a) - f_s, 0.0)
        both = jnp.max(jnp.stack([jnp.abs(q), held]).reshape(2, -1), axis=-1)
        return both[0], both[1] == 0

    # -- perturbations ----------------------------------------------------------------------------

    def sample_points(self) -> Float[Array, " n"]:
        raise TypeError(
            f"{type(self).__name__} takes no field perturbation: it has no sample points (for "
            "SingleMode use jaxrod.perturbations.project_to_mode)."
        )

    def from_samples(self, values):
        """Identity: the nodal models' coordinates are the samples."""
        return values

    def perturbed_state(self, offset, velocity):
        """θ = offset/R and θ̇ = velocity/R in the model's coordinates (`from_samples`)."""
        R = self.rod.R
        return self.from_samples(offset / R), self.from_samples(velocity / R)

    def under_lateral_force(self, force) -> AbstractModel:
        """The acceleration force/(ρR) added, in the model's coordinates (`from_samples`)."""
        return _Forced(self, self.from_samples(force / (self.rod.rho * self.rod.R)))


class AbstractRodDOFModel(AbstractDOFModel):
    """A reduced rod model of P1 with a rod and an axial load: friction μN/(ρR) at each sample
    point, the load's constancy, its buckling threshold and step from the wavenumbers² its
    operator sees (`wavenumbers_sq`)."""

    rod: eqx.AbstractVar[RodChannel]
    load: eqx.AbstractVar[AbstractLoad]

    @abc.abstractmethod
    def wavenumbers_sq(self) -> Float[Array, " n"]:
        """κ_m² [1/m²] of the modes m = 1.. as the operator sees them."""

    def modal_stiffness(self, t=0.0) -> Float[Array, " n"]:
        """k_m = (κ_m²/ρ)(EIκ_m² + ρg/(Rκ_m²) − F(t)) [1/s²] (P3 with the operator's κ_m)."""
        r = self.rod
        k2 = self.wavenumbers_sq()
        return k2 / r.rho * (r.EI * k2 + r.w / (r.R * k2) - self.load(t))

    def max_frequency(self, q=None):
        r = self.rod
        k2 = self.wavenumbers_sq()
        F_min, _ = self.load.extremes()
        lam = k2 / r.rho * (r.EI * k2 + r.w / (r.R * k2) - F_min)
        return jnp.sqrt(jnp.maximum(jnp.max(lam), 0.0))

    def friction_bounds(self, t):
        """μ_s N/(ρR), μ_d N/(ρR) [rad/s²] at every sample point."""
        r = self.rod
        scale = r.N / (r.rho * r.R)
        return r.mu_s * scale, r.mu_d * scale

    @property
    def autonomous(self) -> bool:
        return self.load.constant

    @property
    def buckle_threshold(self) -> float:
        return self.threshold

    def check(self):
        return self.rod.valid() & jnp.isfinite(self.load(0.0))  # the rod's rules, once (`RodChannel.valid`)


class _Forced(AbstractModel):
    """A model with a constant extra acceleration `extra` (`under_lateral_force`): every member of
    the interface is the inner model's (forwarded below, from `AbstractModel`'s own list), the
    accelerations plus `extra`."""

    inner: AbstractModel
    extra: Float[Array, " n"]

    def acceleration(self, q, t):
        return self.inner.acceleration(q, t) + self.extra

    def accelerations(self, q, v, t):
        return self.inner.accelerations(q, v, t) + self.extra

    def under_lateral_force(self, force):
        return _Forced(self.inner, self.extra + self.inner.from_samples(force / (self.rod.rho * self.rod.R)))

    def for_tangents(self):
        return _Forced(self.inner.for_tangents(), self.extra)

    rod = property(lambda self: self.inner.rod)


def _forwarded(name, member):
    """`name` of `_Forced` as its inner model's: a property read through, a method called through."""
    if isinstance(member, property):
        return property(lambda self: getattr(self.inner, name))
    return lambda self, *args, **kwargs: getattr(self.inner, name)(*args, **kwargs)


for _name, _member in vars(AbstractModel).items():  # the interface's methods and properties, but _Forced's own
    if not _name.startswith("_") and (callable(_member) or isinstance(_member, property)) and _name not in vars(_Forced):
        setattr(_Forced, _name, _forwarded(_name, _member))
del _name, _member
abc.update_abstractmethods(_Forced)  # every abstract member is now forwarded


class RodDOFRecipe(AbstractRecipe):
    """The recipe of a reduced rod model (`AbstractRodDOFModel`: field, Galerkin): built by
    `from_rod` at the load, searched by the departure rate, stepped at `DT_FRACTION` of its
    stability limit."""

    search_method: ClassVar[str] = "departure"

    def build(self, rod, F, size, mode):
        """`from_rod(rod, size, F=F)` (the sine `mode` is not needed: every mode is modelled)."""
        return self.model_class.from_rod(rod, size, F=F)

    def step(self, model, rod, F, scheme_step) -> float:
        """`DT_FRACTION` of the stability limit 2/ω_max at ΔF = 0 (compression only lowers the
        highest frequency) and, when the load is concrete, at most `GROWTH_FRACTION`/λ_max,
        λ_max = F/(2√(EIρ)) the fastest growth rate of a loaded rod, so that fast-growing modes
        stay resolved (benchmarks/README.md, field convergence)."""
        unloaded = eqx.tree_at(lambda m: m.load, model, as_load(theory.reference_load(rod)))
        omega = static_float(lambda: jnp.max(unloaded.max_frequency()),
                        "Scene.dt must be given explicitly when the rod's stiffness parameters are traced "
                        "(e.g. vmapped over EI, rho or R): the step is a static setting.")
        dt = DT_FRACTION * 2.0 / omega
        try:
            with jax.ensure_compile_time_eval():
                lam = float(F / (2 * jnp.sqrt(rod.EI * rod.rho)))
        except jax.errors.ConcretizationTypeError:
            return dt
        return min(dt, GROWTH_FRACTION / lam) if lam > 0 else dt
