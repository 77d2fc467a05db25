r"""A real tubing in a real channel, in SI units: the rod and channel the lock-up scene runs, its
dimensionless case (μL/ℓ, r/ℓ) and its units F₀ and ℓ (docs/physics.md §8, P8).

[`tubing`][jaxrod.lockup.si.tubing] turns a tube (coiled tubing, drill pipe) or a solid rod
(a guidewire) given by its Young's modulus, outer and inner diameter, density or weight per
length, the radial clearance, the length and μ into a [`jaxrod.RodChannel`][].
`RodChannel` describes a solid circular section, so a tube of outer diameter D and inner
diameter D_i becomes the solid rod of diameter D whose modulus and density are scaled by
(1 − (D_i/D)⁴) and (1 − (D_i/D)²): bending and twisting stiffness (EI, GJ), mass and weight per
length are the tube's exactly; the axial stiffness EA is (1 + (D_i/D)²) times the tube's and
the rotary inertia ρI 1/(1 + (D_i/D)²) times (neither enters the soft string, and the rod
slides nearly inextensibly; the lock-up case depends on EI, w, r, L and μ only). A buoyed weight
per length (tubing in mud) is given as `weight_per_length` beside the steel's `density`: the mass
stays the tube's and the weight is carried by an effective g = w/(ρA).

[`case`][jaxrod.lockup.si.case] gives μL/ℓ, r/ℓ, F₀ [N] and ℓ [m] of any `RodChannel`.

Layer: beside `jaxrod.lockup.push` (it builds a `RodChannel`, imports nothing of the scene).
"""

from __future__ import annotations

import math

from ..params import RodChannel
from .closed_forms import force_unit, length_unit

__all__ = ["tubing", "case", "G_STANDARD"]

G_STANDARD = 9.80665
"""Standard gravity [m/s²], the `g` of a tubing given by its weight per length alone."""


def _positive(name, value, unit, allow_zero=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is invalid: expected a number [{unit}].") from None
    if not (math.isfinite(v) and (v >= 0 if allow_zero else v > 0)):
        raise ValueError(f"{name} = {value!r}{' ' + unit if unit else ''} is invalid: expected a finite number "
                         f"{'>= 0' if allow_zero else '> 0'}.")
    return v


def tubing(E, outer_diameter, clearance, length, mu, *, inner_diameter=0.0, density=None, weight_per_length=None,
           nu: float = 0.3, g: float = G_STANDARD) -> RodChannel:
    """The [`jaxrod.RodChannel`][] of a tube (or, with `inner_diameter` 0, a solid rod) in a
    channel, in SI units (module docstring: the solid section equivalent in EI, GJ, mass and
    weight per length).

    **Arguments:** `E` Young's modulus [Pa]; `outer_diameter`, `inner_diameter` [m] (0 ≤ inner <
    outer); `clearance` r [m]: the radius of the cylinder the tube's axis moves on (the channel's
    inner radius minus the tube's outer radius); `length` [m]; `mu` the friction coefficient
    (static = dynamic); `density` [kg/m³] and/or `weight_per_length` [N/m] (at least one: with
    both, the weight is the buoyed one given, the mass the density's; with only the weight, the
    mass is weight/`g`); `nu` Poisson's ratio; `g` [m/s²].

    **Raises:** `ValueError` naming the argument, its value and the valid range.
    """
    E = _positive("E", E, "Pa")
    D = _positive("outer_diameter", outer_diameter, "m")
    Di = _positive("inner_diameter", inner_diameter, "m", allow_zero=True)
    if Di >= D:
        raise ValueError(f"inner_diameter = {inner_diameter!r} m is invalid: expected 0 <= inner_diameter < "
                         f"outer_diameter = {D:g} m.")
    r = _positive("clearance", clearance, "m")
    L = _positive("length", length, "m")
    mu = _positive("mu", mu, "")
    g = _positive("g", g, "m/s^2")
    if density is None and weight_per_length is None:
        raise ValueError("density = None and weight_per_length = None: give the density [kg/m^3], the weight per "
                         "length [N/m], or both.")
    k = Di / D
    area = math.pi * D**2 / 4 * (1 - k**2)  # the tube's own cross-section [m²]
    if density is not None:
        rho = _positive("density", density, "kg/m^3")
        g_eff = g if weight_per_length is None else _positive("weight_per_length", weight_per_length, "N/m") / (rho * area)
    else:
        w = _positive("weight_per_length", weight_per_length, "N/m")
        rho, g_eff = w / (g * area), g
    return RodChannel(L=L, d=D, E=E * (1 - k**4), rho_v=rho * (1 - k**2), nu=nu, R=r, g=g_eff, mu_s=mu, mu_d=mu)


def case(rod: RodChannel) -> dict:
    """The lock-up case of `rod` (P8): `mu_L_over_ell` (μ_d L/ℓ), `r_over_ell`, `F0` [N] =
    √(EI w/r), `ell` [m] = √(EI/(r w)), `EI` [N·m²] and `w` [N/m] (plain floats)."""
    EI, w, r = float(rod.EI), float(rod.rho * rod.g), float(rod.R)
    F0, ell = float(force_unit(EI, w, r)), float(length_unit(EI, w, r))
    return {"mu_L_over_ell": float(rod.mu_d) * float(rod.L) / ell, "r_over_ell": r / ell, "F0": F0, "ell": ell,
            "EI": EI, "w": w}
