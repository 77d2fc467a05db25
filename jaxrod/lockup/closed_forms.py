r"""Soft-string closed forms of force transfer and lock-up (docs/physics.md §8, P8–P16).

A rod lies in a horizontal channel of radial clearance r and is pushed at its entry end with
the compressive force F_in. Where it slides toward the far end, friction takes

    dF/ds = −μ w_c(F)                                                          (P11)

from the axial force, with w_c the wall force per length averaged over a buckle. Each section
of the rod has one law w_c = w (a + b (F/F₀)²) (a, b fixed numbers: P11's table), so the force
along a section, the length a section needs to bring the force from one value to another, and
their chain over a straight, a sinusoidal and a helical section are all closed forms.

Natural units (P8): the force F₀ = √(EI w / r) and the length ℓ = √(EI / (r w)); then
F₀ ℓ = EI / r and F₀ / ℓ = w, and μ only enters through μs/ℓ. Arguments are SI: EI [N·m²],
w [N/m], r [m], μ [-], forces [N], lengths [m]; any shapes that broadcast. Every function is
pure `jax.numpy` and safe under `jit`, `vmap` and `grad` (the wall-force laws and the onset
variant are static Python choices, keyword strings; every physical number is a dynamic
argument). Concrete invalid input raises `ValueError` naming the argument; traced input is not
checked.

Validity: quasi-static sliding toward the far end everywhere (friction fully mobilised), small
helix angles (F ≪ 2EI/r², 1457 N for the reference rod), no torque, a straight horizontal
channel.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._numerics import concrete_value as _concrete, float_leaf, format_value as _fmt

__all__ = [
    "HELICAL_ONSETS",
    "SINUSOIDAL_LAWS",
    "HELICAL_LAWS",
    "force_unit",
    "length_unit",
    "sinusoidal_onset",
    "helical_onset",
    "helix_pitch",
    "helical_wall_force",
    "transfer",
    "transfer_length",
    "straight_transfer",
    "sinusoidal_transfer",
    "helical_transfer",
    "helical_far_force_max",
    "helical_lockup_length",
]

HELICAL_ONSETS = {"chen": 2 * math.sqrt(2), "wu_juvkam_wold": 2 * (2 * math.sqrt(2) - 1)}
"""Helical onset loads in units of F₀ (P9): `"chen"`, Chen, Lin & Cheatham (1990), 2√2 (also
the load at which Wu & Juvkam-Wold's helix unwinds on unloading, as usually quoted);
`"wu_juvkam_wold"`, Wu & Juvkam-Wold (1993), on loading, 2(2√2 − 1)."""

SINUSOIDAL_LAWS = {"weight": (1.0, 0.0), "half_helical": (1.0, 0.125)}
"""Wall force per length of a sinusoidal section, as (a, b) in w_c = w (a + b (F/F₀)²) (P11):
`"weight"`, the weight alone (Dawson & Paslay, Chen et al.: a sinusoid adds no contact force to
first order); `"half_helical"`, the weight plus half the helical excess, r F²/(8EI)."""

HELICAL_LAWS = {"with_weight": (1.0, 0.25), "without_weight": (0.0, 0.25)}
"""Wall force per length of a helical section, as (a, b) (P10, P11): `"with_weight"`,
Mitchell's r F²/(4EI) plus the weight w (magnitudes added, as usually quoted for horizontal
wells); `"without_weight"`, r F²/(4EI), the weight's radial component averaged out over a
uniform helix in full contact."""


# ---------------------------------------------------------------------------------------------
# Argument checks (concrete values only: under jit/vmap the arguments are tracers).


def _check(name: str, x: ArrayLike, unit: str, *, positive: bool = False,
           allow_inf: bool = False) -> Float[Array, "..."]:
    """`x` as a float array; `ValueError` naming `name` if it is concrete and NaN, negative
    (or ≤ 0 with `positive`), or infinite (unless `allow_inf`)."""
    v = _concrete(x)
    if v is not None:
        v = np.asarray(v, dtype=float)
        finite_ok = np.all(np.isfinite(v)) if not allow_inf else not np.any(np.isnan(v))
        sign_ok = np.all(v > 0) if positive else np.all(v >= 0)
        if not (finite_ok and sign_ok):
            rule = "> 0" if positive else ">= 0"
            fin = "not NaN" if allow_inf else "finite"
            raise ValueError(f"{name} = {_fmt(v)}{' ' + unit if unit else ''} is invalid: it must be {fin} and {rule}.")
    return float_leaf(x)


def _rod(EI, w, r):
    return (_check("EI", EI, "N*m^2", positive=True), _check("w", w, "N/m", positive=True),
            _check("r", r, "m", positive=True))


def _choice(name: str, value: str, table: dict):
    if value not in table:
        raise ValueError(f"{name} = {value!r} is invalid: choose one of {sorted(table)}.")
    return table[value]


def _law(a: float, b: float) -> tuple[float, float]:
    a, b = float(a), float(b)
    if not (a >= 0 and b >= 0 and a + b > 0 and math.isfinite(a) and math.isfinite(b)):
        raise ValueError(f"(a, b) = ({a!r}, {b!r}) is invalid: the wall-force law "
                         f"w_c = w (a + b f²) needs finite a, b >= 0, not both zero.")
    return a, b


# ---------------------------------------------------------------------------------------------
# Units, onsets, the helix (P8–P10).


def force_unit(EI: ArrayLike, w: ArrayLike, r: ArrayLike) -> Float[Array, "..."]:
    """F₀ = √(EI w / r) [N] (P8): the force unit of the confined rod (half the sinusoidal onset;
    0.6461 N for the reference rod).

    **Arguments:** `EI` [N·m²], `w` weight per length [N/m], `r` radial clearance [m], all > 0.

    **Raises:** `ValueError` naming the argument if a concrete one is not finite and > 0.
    """
    EI, w, r = _rod(EI, w, r)
    return jnp.sqrt(EI * w / r)


def length_unit(EI: ArrayLike, w: ArrayLike, r: ArrayLike) -> Float[Array, "..."]:
    """ℓ = √(EI / (r w)) [m] (P8): the length unit (5.779 m for the reference rod). Not the buckle
    wavelength: that is 2π/ω₀ with ω₀ = (w/(EI r))^(1/4) = 1/√(ℓ r) (§3).

    **Arguments:** `EI` [N·m²], `w` [N/m], `r` [m], all > 0.

    **Raises:** `ValueError` naming the argument if a concrete one is not finite and > 0.
    """
    EI, w, r = _rod(EI, w, r)
    return jnp.sqrt(EI / (r * w))


def sinusoidal_onset(EI: ArrayLike, w: ArrayLike, r: ArrayLike) -> Float[Array, "..."]:
    """F_s = 2√(EI w / r) = 2F₀ [N] (P9): the sinusoidal (lateral) buckling load of a long rod
    on the bottom of a horizontal channel (Dawson & Paslay 1984; Chen, Lin & Cheatham 1990; P5's
    continuous minimum, §3).

    **Arguments:** `EI` [N·m²], `w` [N/m], `r` [m], all > 0.
    """
    return 2 * force_unit(EI, w, r)


def helical_onset(EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                  variant: str = "chen") -> Float[Array, "..."]:
    """The helical buckling load [N] (P9) in one of the published variants:

    - `"chen"`: 2√2 F₀ (Chen, Lin & Cheatham 1990: a helix has less energy than the straight
      rod; Wu & Juvkam-Wold's load for a helix to unwind on unloading).
    - `"wu_juvkam_wold"`: 2(2√2 − 1) F₀ ≈ 3.657 F₀ (Wu & Juvkam-Wold 1993: a helix forms on
      loading; about 1.3 times Chen's and 1.8 times the sinusoidal onset).

    **Arguments:** `EI` [N·m²], `w` [N/m], `r` [m], all > 0; `variant` (static) a key of
    [`HELICAL_ONSETS`][jaxrod.lockup.closed_forms.HELICAL_ONSETS].

    **Raises:** `ValueError` naming the argument for an unknown `variant` or a concrete rod
    number that is not finite and > 0.
    """
    c = _choice("variant", variant, HELICAL_ONSETS)
    return c * force_unit(EI, w, r)


def helix_pitch(EI: ArrayLike, F: ArrayLike) -> Float[Array, "..."]:
    """Lubinski's pitch p = π √(8 EI / F) [m] (P10) of the helix under the compressive force
    `F` [N] > 0 (wavenumber k = 2π/p with k² = F/(2EI), the minimum of the helix's energy).

    **Raises:** `ValueError` naming the argument if a concrete `EI` or `F` is not finite and > 0.
    """
    EI = _check("EI", EI, "N*m^2", positive=True)
    F = _check("F", F, "N", positive=True)
    return math.pi * jnp.sqrt(8 * EI / F)


def helical_wall_force(F: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                       weight: bool = True) -> Float[Array, "..."]:
    """Wall force per length of a helix [N/m] (P10): r F²/(4EI) + w (Mitchell, with the weight
    term) or, with `weight=False`, r F²/(4EI) (the weight's radial component, w cos θ, averages
    to zero over a uniform helix that touches the wall everywhere, which it does for F ≥ 2F₀).

    **Arguments:** `F` compressive force [N] ≥ 0; `EI` [N·m²], `w` [N/m], `r` [m] > 0;
    `weight` (static) whether to add w.

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    EI, w, r = _rod(EI, w, r)
    F = _check("F", F, "N")
    out = r * F**2 / (4 * EI)
    return out + w if weight else out


# ---------------------------------------------------------------------------------------------
# One section (P12, P13), dimensionless: f = F/F₀, x = μ s/ℓ, w_c = w (a + b f²).


def transfer(f_in: ArrayLike, x: ArrayLike, a: float, b: float) -> Float[Array, "..."]:
    """The force f = F/F₀ left after a section of friction length x = μs/ℓ whose wall force
    per length is w (a + b f²), entered with f_in (P12): the solution of df/dx = −(a + b f²),

    - b = 0: f = f_in − a x;
    - a = 0: f = f_in / (1 + b x f_in);
    - a, b > 0, c = √(a/b): f = c tan(arctan(f_in/c) − √(ab) x);

    held at 0 past the point where it vanishes (the rod beyond is not pushed). `f_in = inf` is
    allowed (the limit of an unbounded push).

    **Arguments:** `f_in` ≥ 0 and `x` ≥ 0 (arrays that broadcast); `a`, `b` (static) finite,
    ≥ 0, not both zero.

    **Returns:** f, the broadcast shape.

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    a, b = _law(a, b)
    return _transfer(_check("f_in", f_in, "", allow_inf=True), _check("x", x, ""), a, b)


def _transfer(f_in, x, a, b):
    if b == 0:
        return jnp.maximum(f_in - a * x, 0.0)
    if a == 0:
        # 1/(1/f + b x): finite at f_in = inf; the double where keeps grad finite at f_in = 0.
        pos = f_in > 0
        safe = jnp.where(pos, f_in, 1.0)
        return jnp.where(pos, 1.0 / (1.0 / safe + b * x), 0.0)
    c = math.sqrt(a / b)
    phi = jnp.maximum(jnp.arctan(f_in / c) - math.sqrt(a * b) * x, 0.0)
    return c * jnp.tan(phi)


def transfer_length(f_from: ArrayLike, f_to: ArrayLike, a: float, b: float) -> Float[Array, "..."]:
    """The friction length x = μs/ℓ a section with wall force w (a + b f²) needs to bring the
    force from `f_from` down to `f_to` (P13), the inverse of
    [`transfer`][jaxrod.lockup.closed_forms.transfer]:

    - b = 0: (f_from − f_to)/a;
    - a = 0: (1/f_to − 1/f_from)/b (inf for f_to = 0: the force never vanishes);
    - a, b > 0: (arctan(f_from/c) − arctan(f_to/c))/√(ab), c = √(a/b).

    **Arguments:** `f_from` ≥ `f_to` ≥ 0 (`f_from = inf` allowed); `a`, `b` (static) as in
    `transfer`.

    **Raises:** `ValueError` naming the argument for concrete negative or NaN input.
    """
    a, b = _law(a, b)
    f_from = _check("f_from", f_from, "", allow_inf=True)
    f_to = _check("f_to", f_to, "", allow_inf=True)
    return _transfer_length(f_from, f_to, a, b)


def _transfer_length(f_from, f_to, a, b):
    if b == 0:
        return (f_from - f_to) / a
    if a == 0:
        return (1.0 / f_to - 1.0 / f_from) / b
    c = math.sqrt(a / b)
    return (jnp.arctan(f_from / c) - jnp.arctan(f_to / c)) / math.sqrt(a * b)


def _si(F_in, s, EI, w, r, mu):
    EI, w, r = _rod(EI, w, r)
    F_in = _check("F_in", F_in, "N", allow_inf=True)
    s = _check("s", s, "m")
    mu = _check("mu", mu, "")
    F0 = jnp.sqrt(EI * w / r)
    ell = jnp.sqrt(EI / (r * w))
    return F_in / F0, mu * s / ell, F0


def straight_transfer(F_in: ArrayLike, s: ArrayLike, w: ArrayLike,
                      mu: ArrayLike) -> Float[Array, "..."]:
    """F(s) = max(F_in − μ w s, 0) [N] (P12, a = 1, b = 0): the axial force a distance `s` [m]
    into an unbuckled section entered with `F_in` [N], wall force per length w [N/m].

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    F_in = _check("F_in", F_in, "N")
    s = _check("s", s, "m")
    w = _check("w", w, "N/m", positive=True)
    mu = _check("mu", mu, "")
    return jnp.maximum(F_in - mu * w * s, 0.0)


def sinusoidal_transfer(F_in: ArrayLike, s: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                        mu: ArrayLike, law: str = "weight") -> Float[Array, "..."]:
    """The axial force [N] a distance `s` [m] into a sinusoidally buckled section entered with
    `F_in` [N] (P12): with `law="weight"` (w_c = w) F_in − μws; with `law="half_helical"`
    (w_c = w + rF²/(8EI)) 2√2 F₀ tan(arctan(F_in/(2√2 F₀)) − μs/(2√2 ℓ)). Held at 0 past the
    point where it vanishes.

    **Arguments:** `F_in` [N] ≥ 0, `s` [m] ≥ 0, `EI` [N·m²], `w` [N/m], `r` [m] > 0, `mu` ≥ 0;
    `law` (static) a key of [`SINUSOIDAL_LAWS`][jaxrod.lockup.closed_forms.SINUSOIDAL_LAWS].

    **Raises:** `ValueError` naming the argument for concrete invalid input or an unknown law.
    """
    a, b = _choice("law", law, SINUSOIDAL_LAWS)
    f_in, x, F0 = _si(F_in, s, EI, w, r, mu)
    return F0 * transfer(f_in, x, a, b)


def helical_transfer(F_in: ArrayLike, s: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                     mu: ArrayLike, weight: bool = True) -> Float[Array, "..."]:
    """The axial force [N] a distance `s` [m] into a helical section entered with `F_in` [N]
    (P12), the solution of dF/ds = −μ(rF²/(4EI) + w):

        F(s) = 2F₀ tan(arctan(F_in/(2F₀)) − μs/(2ℓ))

    held at 0 past s = (2ℓ/μ) arctan(F_in/(2F₀)); with `weight=False` (dF/ds = −μ rF²/(4EI))

        F(s) = F_in / (1 + μ r F_in s / (4EI)).

    **Arguments:** `F_in` [N] ≥ 0 (inf allowed), `s` [m] ≥ 0, `EI` [N·m²], `w` [N/m], `r` [m]
    > 0, `mu` ≥ 0; `weight` (static) whether the wall force carries the weight term.

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    a, b = HELICAL_LAWS["with_weight" if weight else "without_weight"]
    f_in, x, F0 = _si(F_in, s, EI, w, r, mu)
    return F0 * transfer(f_in, x, a, b)


def helical_far_force_max(L: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike, mu: ArrayLike,
                          weight: bool = True) -> Float[Array, "..."]:
    """The largest force [N] that can reach the far end of a helical section of length `L` [m],
    pushed however hard (F_in → ∞ in `helical_transfer`; P14):

    - with the weight term: 2F₀ cot(μL/(2ℓ)) for μL/ℓ < π, 0 beyond (lock-up at μL = πℓ);
    - without: 4EI/(μ r L) = 4F₀ ℓ/(μL), bounded but never 0.

    (A section that is helical all along, whatever the force: the chain with the sinusoidal and
    straight sections is [`far_force_max`][jaxrod.lockup.chain.far_force_max].)

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    return helical_transfer(jnp.inf, L, EI, w, r, mu, weight)


def helical_lockup_length(EI: ArrayLike, w: ArrayLike, r: ArrayLike, mu: ArrayLike,
                          weight: bool = True) -> Float[Array, "..."]:
    """The length [m] of a helical section through which no force reaches the far end (P15):
    πℓ/μ with the weight term, inf without it (the bound 4EI/(μrL) only decays). inf at μ = 0.

    **Raises:** `ValueError` naming the argument for concrete invalid input.
    """
    EI, w, r = _rod(EI, w, r)
    mu = _check("mu", mu, "")
    ell = jnp.sqrt(EI / (r * w))
    if not weight:
        return jnp.full(jnp.broadcast_shapes(ell.shape, mu.shape), jnp.inf, dtype=ell.dtype)
    return math.pi * ell / mu
