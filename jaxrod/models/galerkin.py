r"""The multi-mode Galerkin model (P2): sine modes coupled through friction."""

from __future__ import annotations

import functools
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import theory
from ..loads import AbstractLoad, as_load
from ..params import RodChannel
from .dof import AbstractRodDOFModel, RodDOFRecipe
from .single_mode import _stumpff

__all__ = ["GalerkinModel", "GalerkinRecipe", "DEFAULT_MODES"]

DEFAULT_MODES = 32  # a scene's Galerkin model


@functools.lru_cache(maxsize=32)
def _quadrature_np(n_modes: int, n_quad: int) -> np.ndarray:
    j = np.arange(n_quad)[:, None] + 0.5
    m = np.arange(1, n_modes + 1)[None, :]
    return np.sin(np.pi * j * m / n_quad)


class GalerkinModel(AbstractRodDOFModel):
    r"""P2 with modes m = 1..`n_modes`: `Ä_m + k_m A_m + (μN/(ρR)) B_m = 0`, where
    k_m is P3 (exact wavenumbers ω_m = mπ/L) and
    B_m = (2/L)∫₀ᴸ sgn(Σ_k Ȧ_k sin ω_k s) sin ω_m s ds.

    **Friction and sticking.** B_m is evaluated by the midpoint rule on `n_quad` points
    s_j = (j+½)L/Q, where the discrete sine transform is exactly orthogonal for modes < Q.
    The sharp law is applied as the field model applies it, pointwise: the velocity field
    u_j = Σ_k Ȧ_k sin ω_k s_j is passed through the proximal Coulomb step at every quadrature
    point, and the result is projected back onto the modes (Ȧ_m = (2/Q)Σ_j u_j sin ω_m s_j).
    While the rod slides this is exactly the quadrature of B_m (for one mode,
    B₁ = (4/π) sgn(Ȧ₁) up to the midpoint rule's relative error π²/(24Q²)); a point sticks
    while the elastic force there is inside μ_s N/R, and the rod is stuck when every point
    is — so a single mode sticks for |k A| ≤ μ_s N/(ρR), the field model's pointwise test,
    which is π/4 of the single-mode oscillator's stick line |k A| ≤ f.

    Coordinates: modal amplitudes A_m [rad]; energies in J (as for the field model, with
    the rod's integrals ∫ sin² = L/2).

    **Arguments:** `rod`, `load` as for [`jaxrod.FieldModel`][]; `n_modes` (static, ≥ 1);
    `n_quad` quadrature points (static, > `n_modes`; default max(64, 8·n_modes));
    `threshold` buckling amplitude max|θ| [rad] (static, default 0.5).
    """

    rod: RodChannel
    load: AbstractLoad
    n_modes: int = eqx.field(static=True)
    n_quad: int = eqx.field(static=True, default=0)
    threshold: float = eqx.field(static=True, default=0.5)

    def __post_init__(self):
        if isinstance(self.n_modes, int) and self.n_quad == 0:
            object.__setattr__(self, "n_quad", max(64, 8 * self.n_modes))

    def __check_init__(self):
        if not (isinstance(self.n_modes, int) and self.n_modes >= 1):
            raise ValueError(f"GalerkinModel.n_modes = {self.n_modes!r} is invalid: expected an int >= 1.")
        if not (isinstance(self.n_quad, int) and self.n_quad > self.n_modes):
            raise ValueError(
                f"GalerkinModel.n_quad = {self.n_quad!r} is invalid: expected an int > n_modes = "
                f"{self.n_modes}."
            )

    @classmethod
    def from_rod(
        cls,
        rod: RodChannel,
        n_modes: int = 16,
        *,
        F: ArrayLike | AbstractLoad | None = None,
        dF: ArrayLike | None = None,
        n_quad: int = 0,
        threshold: float = 0.5,
    ) -> GalerkinModel:
        """As [`jaxrod.FieldModel.from_rod`][]: load `F` [N] or F = F⁰_m* + `dF`."""
        if (F is None) == (dF is None):
            raise ValueError("GalerkinModel.from_rod needs exactly one of F and dF.")
        if dF is not None:
            F = theory.reference_load(rod) + jnp.asarray(dF)
        return cls(rod, as_load(F), n_modes, n_quad, threshold)

    def _phi(self):
        return jnp.asarray(_quadrature_np(self.n_modes, self.n_quad), dtype=self.rod.L.dtype)

    def sample_points(self) -> Float[Array, " Q"]:
        """Quadrature points s_j [m]."""
        j = jnp.arange(self.n_quad, dtype=self.rod.L.dtype) + 0.5
        return j * self.rod.L / self.n_quad

    def from_samples(self, values):
        return self.project(values)

    def project(self, values: Float[Array, " Q"]) -> Float[Array, " n_modes"]:
        """Modal amplitudes of a field given at the quadrature points."""
        return (2.0 / self.n_quad) * (values @ self._phi())

    def field(self, q: Float[Array, " n_modes"]) -> Float[Array, " Q"]:
        """θ at the quadrature points."""
        return self._phi() @ q

    def wavenumbers(self):
        """ω_m = mπ/L [1/m], m = 1..n_modes (exact)."""
        m = jnp.arange(1, self.n_modes + 1, dtype=self.rod.L.dtype)
        return m * math.pi / self.rod.L

    def wavenumbers_sq(self):
        return self.wavenumbers() ** 2

    def acceleration(self, q, t):
        return -self.modal_stiffness(t) * q

    def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
        f_s, f_d = self.friction_bounds(t)
        u = friction.update(self.field(v_trial), self.field(v_prev), h, f_s, f_d)
        return self.project(u)

    def friction_acceleration(self, friction, v, t):
        f_s, f_d = self.friction_bounds(t)
        return self.project(friction.acceleration(self.field(v), f_s, f_d))

    def stop_measures(self, q, v, a, t):
        f_s, _ = self.friction_bounds(t)
        stuck = jnp.all(v == 0) & jnp.all(jnp.abs(self.field(a)) <= f_s)
        return self.amplitude(q), stuck

    def amplitude(self, q):
        return jnp.max(jnp.abs(self.field(q)))

    def kinetic_energy(self, v):
        r = self.rod
        return 0.5 * r.rho * r.R**2 * (r.L / 2) * jnp.sum(v * v)

    def energy_terms(self, q, v, t):
        r = self.rod
        om2 = self.wavenumbers() ** 2
        c = r.R**2 * r.L / 2
        return {
            "kinetic": self.kinetic_energy(v),
            "bending": 0.5 * r.EI * c * jnp.sum(om2 * om2 * q * q),
            "gravity": 0.5 * r.w * r.R * (r.L / 2) * jnp.sum(q * q),
            "load": -0.5 * self.load(t) * c * jnp.sum(om2 * q * q),
        }

    def linear_flow(self, q, v, t, h):
        k = self.modal_stiffness(t)
        c0, c1, _ = _stumpff(k * h**2)
        return q * c0 + v * h * c1, v * c0 - k * q * h * c1


class GalerkinRecipe(RodDOFRecipe):
    """The Galerkin model's recipe: `DEFAULT_MODES` modes unless given."""

    model_class: ClassVar[type] = GalerkinModel
    size_name: ClassVar[str] = "modes"
    min_size: ClassVar[int] = 1

    def default_size(self, rod, F, perturbation) -> int:
        return DEFAULT_MODES

    def field_of(self, model, q):
        """θ at the quadrature points (any leading axes of `q`)."""
        return model.sample_points(), q @ model._phi().T

    def dominant_mode(self, model, q):
        """The mode of the largest amplitude."""
        return jnp.argmax(jnp.abs(q), axis=-1) + 1
