"""The physical rod and channel: one parameter object with every number as an array leaf."""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float

from ._numerics import concrete_value as _concrete, float_leaf, format_value as _fmt

__all__ = ["RodChannel"]

_POSITIVE = {"L": "m", "d": "m", "E": "Pa", "rho_v": "kg/m^3", "R": "m", "g": "m/s^2"}  # fields > 0 [unit]


class RodChannel(eqx.Module):
    """An elastic rod of circular section lying in a horizontal cylindrical channel.

    Every physical number is a JAX array leaf (any shape that broadcasts), so a sweep or a
    gradient over any of them never recompiles. SI units throughout.

    **Arguments:**

    - `L`: rod length [m], > 0.
    - `d`: rod diameter [m], > 0.
    - `E`: Young's modulus [Pa], > 0.
    - `rho_v`: density of the rod material [kg/m³], > 0.
    - `nu`: Poisson's ratio [-], in (−1, 0.5).
    - `R`: clearance [m], > 0: channel radius minus rod radius, the radius of the cylinder on
      which the rod's centre line moves.
    - `g`: gravitational acceleration [m/s²], > 0.
    - `mu_s`: static Coulomb friction coefficient [-], ≥ 0.
    - `mu_d`: dynamic Coulomb friction coefficient [-], in [0, mu_s].

    **Raises:**

    `ValueError` naming the field, its value and the valid range, for non-positive or
    non-finite `L`, `d`, `E`, `rho_v`, `R`, `g`; `nu` outside (−1, 0.5); negative or
    non-finite `mu_s`, `mu_d`; or `mu_d > mu_s`. Values traced under `jit`/`vmap` cannot be
    checked at construction; the drivers then report bad members through result codes.
    """

    L: Float[Array, "..."] = eqx.field(converter=float_leaf)
    d: Float[Array, "..."] = eqx.field(converter=float_leaf)
    E: Float[Array, "..."] = eqx.field(converter=float_leaf)
    rho_v: Float[Array, "..."] = eqx.field(converter=float_leaf)
    nu: Float[Array, "..."] = eqx.field(converter=float_leaf)
    R: Float[Array, "..."] = eqx.field(converter=float_leaf)
    g: Float[Array, "..."] = eqx.field(converter=float_leaf)
    mu_s: Float[Array, "..."] = eqx.field(converter=float_leaf)
    mu_d: Float[Array, "..."] = eqx.field(converter=float_leaf)

    def __check_init__(self):
        for name, unit in _POSITIVE.items():
            v = _concrete(getattr(self, name))
            if v is not None and not (np.all(np.isfinite(v)) and np.all(v > 0)):
                raise ValueError(
                    f"RodChannel.{name} = {_fmt(v)} {unit} is invalid: "
                    f"it must be finite and > 0."
                )
        nu = _concrete(self.nu)
        if nu is not None and not (np.all(nu > -1.0) and np.all(nu < 0.5)):
            raise ValueError(
                f"RodChannel.nu = {_fmt(nu)} is invalid: Poisson's ratio must lie in (-1, 0.5)."
            )
        for name in ("mu_s", "mu_d"):
            v = _concrete(getattr(self, name))
            if v is not None and not (np.all(np.isfinite(v)) and np.all(v >= 0)):
                raise ValueError(
                    f"RodChannel.{name} = {_fmt(v)} is invalid: a friction coefficient must be "
                    f"finite and >= 0."
                )
        mu_s, mu_d = _concrete(self.mu_s), _concrete(self.mu_d)
        if mu_s is not None and mu_d is not None and np.any(mu_d > mu_s):
            raise ValueError(
                f"RodChannel.mu_d = {_fmt(mu_d)} is invalid: the dynamic coefficient must lie "
                f"in [0, mu_s] with mu_s = {_fmt(mu_s)}."
            )

    def valid(self) -> Bool[Array, ""]:
        """The rules of the construction's check as one traced boolean (every member): for values
        traced under `jit`/`vmap`, which the construction cannot check (a sweep's members, a
        model's `check` for its result code). The one definition of a valid rod besides the
        construction's messages."""
        ok = jnp.array(True)
        for name in _POSITIVE:
            v = getattr(self, name)
            ok &= jnp.all(jnp.isfinite(v) & (v > 0))
        ok &= jnp.all((self.nu > -1.0) & (self.nu < 0.5))
        for v in (self.mu_s, self.mu_d):
            ok &= jnp.all(jnp.isfinite(v) & (v >= 0))
        return ok & jnp.all(self.mu_d <= self.mu_s)

    @classmethod
    def reference(cls, mu: ArrayLike = 0.3, **overrides) -> RodChannel:
        """The reference rod of the reference paper (Su et al. 2013): a nitinol rod,
        L = 3 m, d = 1.5 mm, E = 77 GPa, ρ_v = 6450 kg/m³, ν = 0.33, in a channel of
        clearance R = 5.125 mm, g = 9.81 m/s², with μ_s = μ_d = `mu`.

        **Arguments:**

        - `mu`: friction coefficient used for both `mu_s` and `mu_d` [-].
        - `overrides`: any field of [`jaxrod.RodChannel`][] to replace.
        """
        values = dict(
            L=3.0,
            d=1.5e-3,
            E=77e9,
            rho_v=6450.0,
            nu=0.33,
            R=5.125e-3,
            g=9.81,
            mu_s=mu,
            mu_d=mu,
        )
        unknown = set(overrides) - set(values)
        if unknown:
            raise ValueError(
                f"RodChannel.reference got unknown field(s) {sorted(unknown)}; "
                f"valid fields are {sorted(values)}."
            )
        values.update(overrides)
        return cls(**values)

    def with_friction(self, mu_s: ArrayLike, mu_d: ArrayLike | None = None) -> RodChannel:
        """A copy with new friction coefficients (`mu_d` defaults to `mu_s`)."""
        mu_d = mu_s if mu_d is None else mu_d
        return RodChannel(self.L, self.d, self.E, self.rho_v, self.nu, self.R, self.g, mu_s, mu_d)

    # Derived section and material quantities.
    @property
    def area(self) -> Float[Array, "..."]:
        """Cross-section area A = πd²/4 [m²]."""
        return math.pi * self.d**2 / 4

    @property
    def I(self) -> Float[Array, "..."]:  # noqa: E743
        """Second moment of area I = πd⁴/64 [m⁴]."""
        return math.pi * self.d**4 / 64

    @property
    def J(self) -> Float[Array, "..."]:
        """Polar moment of area J = 2I [m⁴]."""
        return 2 * self.I

    @property
    def G(self) -> Float[Array, "..."]:
        """Shear modulus G = E / (2(1 + ν)) [Pa]."""
        return self.E / (2 * (1 + self.nu))

    @property
    def EI(self) -> Float[Array, "..."]:
        """Bending rigidity [N·m²]."""
        return self.E * self.I

    @property
    def GJ(self) -> Float[Array, "..."]:
        """Torsional rigidity [N·m²]."""
        return self.G * self.J

    @property
    def EA(self) -> Float[Array, "..."]:
        """Axial rigidity [N]."""
        return self.E * self.area

    @property
    def GA(self) -> Float[Array, "..."]:
        """Shear rigidity G·A [N] (no shear correction factor)."""
        return self.G * self.area

    @property
    def rho(self) -> Float[Array, "..."]:
        """Mass per unit length ρ = ρ_v·A [kg/m]."""
        return self.rho_v * self.area

    @property
    def w(self) -> Float[Array, "..."]:
        """Weight per unit length w = ρg [N/m]."""
        return self.rho * self.g

    @property
    def N(self) -> Float[Array, "..."]:
        """Normal contact force per unit length while the rod lies on the bottom, N = w [N/m]."""
        return self.w
