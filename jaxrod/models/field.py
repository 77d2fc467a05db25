r"""The small-angle field model θ(s, t) (P1) on the nodes of a pinned rod."""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import theory
from ..loads import AbstractLoad, as_load
from ..modal import dominant_mode, sine_basis
from ..params import RodChannel
from .dof import AbstractRodDOFModel, RodDOFRecipe
from .single_mode import _stumpff

__all__ = ["FieldModel", "FieldRecipe", "DEFAULT_NODES", "default_nodes"]

DEFAULT_NODES = 128  # see benchmarks/README.md (field convergence) and `default_nodes`


def default_nodes(rod: RodChannel, F) -> int:
    """The field model's default node count for the load `F` [N] (concrete): 128 while at most
    32 modes are unstable (m_max = (L/π)√(F/EI) ≤ 32), 384 beyond, from the convergence study
    `benchmarks/field_convergence.py` (its table in benchmarks/README.md)."""
    with jax.ensure_compile_time_eval():
        m_max = float(rod.L / math.pi * jnp.sqrt(jnp.maximum(F, 0.0) / rod.EI))
    return DEFAULT_NODES if m_max <= 32 else 384

_OPERATORS = ("fd", "spectral")


class FieldModel(AbstractRodDOFModel):
    r"""P1 on `n_nodes` interior nodes of a pinned rod, with friction at every node:

    `ρ θ_tt + EI θ_ssss + F(t) θ_ss + (ρg/R) θ + (μN/R) sgn(θ_t) = 0`,  θ = θ_ss = 0 at s = 0, L.

    Coordinates: θ_j = θ(s_j, t) at s_j = jL/(n+1), j = 1..n [rad]; the lateral displacement
    is R·θ. Friction is a bound μN/(ρR) [rad/s²] on each node's angular acceleration: the node
    sticks while its elastic acceleration is within μ_s N/(ρR), and slips against μ_d N/(ρR).

    **The elastic operator.** `operator="fd"` (default): second differences
    D₂θ_j = (θ_{j−1} − 2θ_j + θ_{j+1})/Δ² with θ_0 = θ_{n+1} = 0, and θ_ssss = D₂D₂θ (the
    pinned condition θ_ss = 0 makes D₄ = D₂²). Its eigenvectors are exactly the sampled sine
    modes sin(mπs/L); mode m's wavenumber² is κ_m² = (4/Δ²)sin²(mπΔ/2L) instead of ω_m²
    (relative error ≈ (ω_mΔ)²/12). `operator="spectral"`: the same modes with the exact ω_m,
    applied through the sine transform (two dense n×n products per step). Either way the step
    limit of an explicit scheme is 2/ω_max with
    ω_max² = max_m (κ_m²/ρ)(EI κ_m² + ρg/(Rκ_m²) − F_min), i.e. about
    dt < Δ²/2·√(ρ/EI) for `fd` and π⁴/16 ≈ 6× less for `spectral`; see `max_frequency`.

    Energies are the discrete quadratic forms (J): kinetic ½ρR²Δ|θ_t|², bending
    ½EI R²Δ|D₂θ|², gravity ½ρgRΔ|θ|², load ½F R²Δ θ·D₂θ (= −½F R² ∫θ_s²), whose gradient is
    exactly the elastic force used by the integrators.

    **Arguments:**

    - `rod`: the [`jaxrod.RodChannel`][] (dynamic leaves: EI, ρ, R, μ_s, μ_d, ...).
    - `load`: the axial compressive load, a [`jaxrod.ConstantLoad`][] or [`jaxrod.RampLoad`][].
    - `n_nodes`: number of interior nodes (static, ≥ 4).
    - `operator`: `"fd"` or `"spectral"` (static).
    - `threshold`: buckling amplitude max|θ| [rad] (static, default 0.5: the end of the
      small-angle regime).

    Build with [`jaxrod.FieldModel.from_rod`][].
    """

    rod: RodChannel
    load: AbstractLoad
    n_nodes: int = eqx.field(static=True)
    operator: str = eqx.field(static=True, default="fd")
    threshold: float = eqx.field(static=True, default=0.5)

    def __check_init__(self):
        if not (isinstance(self.n_nodes, int) and self.n_nodes >= 4):
            raise ValueError(f"FieldModel.n_nodes = {self.n_nodes!r} is invalid: expected an int >= 4.")
        if self.operator not in _OPERATORS:
            raise ValueError(
                f"FieldModel.operator = {self.operator!r} is invalid: expected one of {_OPERATORS}."
            )
        if not self.threshold > 0:
            raise ValueError(f"FieldModel.threshold = {self.threshold!r} is invalid: expected > 0 rad.")

    @classmethod
    def from_rod(
        cls,
        rod: RodChannel,
        n_nodes: int = 64,
        *,
        F: ArrayLike | AbstractLoad | None = None,
        dF: ArrayLike | None = None,
        operator: str = "fd",
        threshold: float = 0.5,
    ) -> FieldModel:
        """The field model of `rod` under the load `F` [N] (a number or a load object), or
        F = F⁰_m* + `dF` with F⁰_m* the frictionless load of the rod's critical mode (P5; the
        continuous operator's value, 1.308 N for the reference rod). Exactly one of F, dF."""
        if (F is None) == (dF is None):
            raise ValueError("FieldModel.from_rod needs exactly one of F and dF.")
        if dF is not None:
            F = theory.reference_load(rod) + jnp.asarray(dF)
        return cls(rod, as_load(F), n_nodes, operator, threshold)

    # -- geometry and spectrum ---------------------------------------------------------------

    @property
    def spacing(self) -> Float[Array, ""]:
        """Node spacing Δ = L/(n+1) [m]."""
        return self.rod.L / (self.n_nodes + 1)

    def sample_points(self) -> Float[Array, " n"]:
        """Node positions s_j [m]."""
        j = jnp.arange(1, self.n_nodes + 1, dtype=self.rod.L.dtype)
        return j * self.spacing

    def wavenumbers_sq(self) -> Float[Array, " n"]:
        """κ_m² [1/m²] of modes m = 1..n as the operator sees them."""
        m = jnp.arange(1, self.n_nodes + 1, dtype=self.rod.L.dtype)
        if self.operator == "spectral":
            return (m * math.pi / self.rod.L) ** 2
        h = self.spacing
        return (4 / h**2) * jnp.sin(m * math.pi / (2 * (self.n_nodes + 1))) ** 2

    def frictionless_loads(self) -> Float[Array, " n"]:
        """F⁰_m [N] of the discrete operator (P5 with κ_m)."""
        r = self.rod
        k2 = self.wavenumbers_sq()
        return r.EI * k2 + r.w / (r.R * k2)

    # -- forces ------------------------------------------------------------------------------

    def _d2(self, theta):
        p = jnp.pad(theta, 1)
        return (p[:-2] - 2 * theta + p[2:]) / self.spacing**2

    def _stiffness_times(self, theta, t):
        """K θ = EI θ_ssss + F θ_ss + (ρg/R) θ [N/m per unit R]."""
        r = self.rod
        F = self.load(t)
        if self.operator == "spectral":
            S = sine_basis(self.n_nodes)
            k2 = self.wavenumbers_sq()
            a = (2.0 / (self.n_nodes + 1)) * (S.T @ theta)
            return S @ ((r.EI * k2 * k2 - F * k2 + r.w / r.R) * a)
        d2 = self._d2(theta)
        return r.EI * self._d2(d2) + F * d2 + (r.w / r.R) * theta

    def acceleration(self, q, t):
        return -self._stiffness_times(q, t) / self.rod.rho

    # -- energies (J) ------------------------------------------------------------------------

    def kinetic_energy(self, v):
        r = self.rod
        return 0.5 * r.rho * r.R**2 * self.spacing * jnp.sum(v * v)

    def energy_terms(self, q, v, t):
        r = self.rod
        h = self.spacing
        if self.operator == "spectral":
            S = sine_basis(self.n_nodes)
            k2 = self.wavenumbers_sq()
            a = (2.0 / (self.n_nodes + 1)) * (S.T @ q)
            # Parseval for the DST-I: h Σ θ_j² = (L/2) Σ a_m²
            half_L = r.L / 2
            bend = 0.5 * r.EI * r.R**2 * half_L * jnp.sum(k2 * k2 * a * a)
            load = -0.5 * self.load(t) * r.R**2 * half_L * jnp.sum(k2 * a * a)
        else:
            d2 = self._d2(q)
            bend = 0.5 * r.EI * r.R**2 * h * jnp.sum(d2 * d2)
            load = 0.5 * self.load(t) * r.R**2 * h * jnp.sum(q * d2)
        return {
            "kinetic": self.kinetic_energy(v),
            "bending": bend,
            "gravity": 0.5 * r.w * r.R * h * jnp.sum(q * q),
            "load": load,
        }

    def linear_flow(self, q, v, t, h):
        S = sine_basis(self.n_nodes)
        c = 2.0 / (self.n_nodes + 1)
        a, b = c * (S.T @ q), c * (S.T @ v)
        k = self.modal_stiffness(t)
        c0, c1, _ = _stumpff(k * h**2)
        a, b = a * c0 + b * h * c1, b * c0 - k * a * h * c1
        return S @ a, S @ b


class FieldRecipe(RodDOFRecipe):
    """The field model's recipe: `n` nodes, by default `default_nodes` of the load."""

    model_class: ClassVar[type] = FieldModel
    size_name: ClassVar[str] = "nodes"
    min_size: ClassVar[int] = 4

    def default_size(self, rod, F, perturbation) -> int:
        """`default_nodes` of the load, and at least the nodes the perturbation needs resolved
        (`AbstractPerturbation.least_nodes`)."""
        return max(default_nodes(rod, F), perturbation.least_nodes)

    def field_of(self, model, q):
        return model.sample_points(), q

    def dominant_mode(self, model, q):
        return dominant_mode(q)
