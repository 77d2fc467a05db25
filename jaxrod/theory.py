r"""Analytic theory of the frictionally confined rod (docs/physics.md §2–4).

Pure `jax.numpy` functions: every one is safe under `jit`, `vmap` and `grad`. Amplitudes are
deflection angles θ in radians (lateral displacement R·θ, lateral velocity R·θ̇) unless
`planar=True`, which takes the planar limit R → ∞ (a rod on a flat frictional plane): the
gravity term drops out of the stiffness and amplitudes become lateral displacements in metres.

Notation: mode m has wavenumber ω_m = mπ/L; the single-mode oscillator (P4) is
`Ä + k A + f sgn(Ȧ) = 0` with

- k_m = (ω_m²/ρ)(EI ω_m² + ρg/(R ω_m²) − F)        (P3)
- f = 4 μ N / (π ρ R)                                 (P4)
- F⁰_m = EI ω_m² + ρg/(R ω_m²)                         (P5)
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from ._numerics import float_leaf
from .params import RodChannel

__all__ = [
    "reference_load",
    "wavenumber",
    "stiffness",
    "friction_amplitude",
    "frictionless_load",
    "critical_load_continuous",
    "critical_wavenumber",
    "critical_mode",
    "velocity_intercept",
    "position_intercept",
    "in_stable_zone",
    "stable_zone_boundary",
    "critical_load_velocity",
    "critical_load_position",
    "critical_loads",
    "min_critical_load",
    "held_end_amplitude",
]


def wavenumber(rod: RodChannel, m: ArrayLike) -> Float[Array, "..."]:
    """ω_m = mπ/L [rad/m] of the pinned-pinned sine mode `m` (m = 1, 2, ...)."""
    return float_leaf(m) * math.pi / rod.L


def frictionless_load(rod: RodChannel, m: ArrayLike, planar: bool = False) -> Float[Array, "..."]:
    """F⁰_m = EI ω_m² + ρg/(R ω_m²) [N] (P5): the axial load at which mode `m` loses its
    stiffness without friction. With `planar=True`, Euler's load EI ω_m²."""
    om2 = wavenumber(rod, m) ** 2
    if planar:
        return rod.EI * om2
    return rod.EI * om2 + rod.w / (rod.R * om2)


def stiffness(
    rod: RodChannel, m: ArrayLike, F: ArrayLike, planar: bool = False
) -> Float[Array, "..."]:
    """k_m = (ω_m²/ρ)(F⁰_m − F) [1/s²] (P3) under a compressive axial load `F` [N]."""
    om2 = wavenumber(rod, m) ** 2
    return om2 / rod.rho * (frictionless_load(rod, m, planar) - float_leaf(F))


def friction_amplitude(
    rod: RodChannel, mu: ArrayLike | None = None, planar: bool = False
) -> Float[Array, "..."]:
    """f = 4μN/(πρR) [rad/s²] (P4): the friction term of the single-mode oscillator.

    `mu` defaults to the rod's dynamic coefficient `mu_d`. With `planar=True` the amplitude is a
    lateral displacement and f = 4μN/(πρ) [m/s²].
    """
    mu = rod.mu_d if mu is None else float_leaf(mu)
    f = 4 * mu * rod.N / (math.pi * rod.rho)
    return f if planar else f / rod.R


def critical_load_continuous(rod: RodChannel, planar: bool = False) -> Float[Array, "..."]:
    """F⁰_cr = 2√(ρg EI/R) [N]: the minimum of P5 over a continuous wavenumber (an infinitely
    long rod). In the planar limit there is no continuous minimum: returns Euler's load of the
    first mode π²EI/L² of the finite rod instead."""
    if planar:
        return frictionless_load(rod, 1, planar=True)
    return 2 * jnp.sqrt(rod.w * rod.EI / rod.R)


def critical_wavenumber(rod: RodChannel, planar: bool = False) -> Float[Array, "..."]:
    """ω₀ = (ρg/(EI R))^(1/4) [rad/m], the wavenumber that minimises P5 (π/L if planar)."""
    if planar:
        return wavenumber(rod, 1)
    return (rod.w / (rod.EI * rod.R)) ** 0.25


def critical_mode(rod: RodChannel, planar: bool = False) -> Int[Array, "..."]:
    """The mode m ≥ 1 of the finite pinned rod with the lowest frictionless load F⁰_m.

    F⁰_m is convex in ω_m², so the minimiser is one of the two integers around ω₀L/π.
    """
    if planar:
        return jnp.ones(jnp.shape(rod.L), dtype=int)
    mc = critical_wavenumber(rod) * rod.L / math.pi
    lo = jnp.maximum(jnp.floor(mc), 1.0)
    hi = lo + 1.0
    m = jnp.where(frictionless_load(rod, lo) <= frictionless_load(rod, hi), lo, hi)
    return m.astype(int)



@jax.jit  # called eagerly by every command and scene: one compiled call, not ~20 small ones (0.16 s)
def reference_load(rod: RodChannel) -> Float[Array, ""]:
    """F⁰_m* [N]: the frictionless load of the rod's critical mode (P5; 1.308 N, mode 6, for the
    reference rod). Every ΔF in jaxrod is measured from it."""
    return frictionless_load(rod, critical_mode(rod))

def max_growth_rate(rod: RodChannel, F: ArrayLike) -> Float[Array, "..."]:
    """λ_max = max over κ of √(−k(κ)) [1/s]: the fastest exponential growth of any lateral
    wave of the frictionless rod under the load `F` [N] (P3 with a continuous wavenumber:
    −k(κ) = κ²(F − EIκ²)/ρ − ρg/(ρR) is largest at κ² = F/(2EI)); 0 if nothing grows. Sliding
    friction is a constant force and does not change it: every departure from a marginally held
    state grows at most this fast."""
    F = float_leaf(F)
    lam2 = F**2 / (4 * rod.EI * rod.rho) - rod.w / (rod.R * rod.rho)
    return jnp.sqrt(jnp.maximum(lam2, 0.0))


def velocity_intercept(k: ArrayLike, f: ArrayLike) -> Float[Array, "..."]:
    """Ȧ_cr = f/√|k| (P6): the largest pure velocity perturbation that leaves a loaded
    (k < 0) single mode stable. `inf` where k ≥ 0 (every trajectory is bounded)."""
    k, f = float_leaf(k), float_leaf(f)
    neg = k < 0
    safe_k = jnp.where(neg, k, -1.0)
    return jnp.where(neg, f / jnp.sqrt(-safe_k), jnp.inf)


def position_intercept(k: ArrayLike, f: ArrayLike) -> Float[Array, "..."]:
    """A_cr = f/|k| (P6): half-width of the stick line, the largest pure position perturbation
    released from rest that stays put. `inf` where k = 0."""
    k, f = float_leaf(k), float_leaf(f)
    nz = k != 0
    safe_k = jnp.where(nz, k, 1.0)
    return jnp.where(nz, f / jnp.abs(safe_k), jnp.inf)


def in_stable_zone(
    A: ArrayLike,
    Adot: ArrayLike,
    k: ArrayLike,
    f: ArrayLike,
    f_static: ArrayLike | None = None,
) -> Bool[Array, "..."]:
    """Whether the state (A, Ȧ) of `Ä + kA + f sgn(Ȧ) = 0` stays bounded (ends stuck).

    For k < 0 with λ = √|k| and a = f/|k|, and Ȧ > 0 (Ȧ < 0 by the symmetry
    (A, Ȧ) → (−A, −Ȧ)), the zone is `Ȧ < λ(a − A)` (left of the saddle's separatrix) and
    `Ȧ² ≥ λ²((a − A)² − 4a²)` (the phase stops at A ≥ −a, on the stick line). At rest the
    zone is the stick line |A| ≤ a. For k > 0 every state ends on the stick line; for k = 0
    every state with f > 0 stops. Without friction only k > 0, or rest, is bounded.

    **Arguments:**

    - `A`, `Adot`: the state [rad, rad/s].
    - `k`: modal stiffness [1/s²]; `f`: dynamic friction amplitude [rad/s²].
    - `f_static`: static friction amplitude for the stick test [rad/s²] (default `f`).

    **Returns:** a boolean array, the broadcast of the arguments.
    """
    A, Adot, k, f = float_leaf(A), float_leaf(Adot), float_leaf(k), float_leaf(f)
    fs = f if f_static is None else float_leaf(f_static)
    flip = Adot < 0
    A = jnp.where(flip, -A, A)
    Adot = jnp.abs(Adot)
    neg = k < 0
    absk = jnp.where(neg, -k, 1.0)
    lam = jnp.sqrt(absk)
    a = f / absk
    a_s = fs / absk
    moving = Adot > 0
    below_separatrix = Adot < lam * (a - A)
    # The slip phase stops at A_stop = a - sqrt((a - A)^2 - (Adot/lam)^2); it sticks when
    # A_stop >= -a_s, i.e. (a - A)^2 - (Adot/lam)^2 <= (a + a_s)^2.
    stops_on_line = (a - A) ** 2 - (Adot / lam) ** 2 <= (a + a_s) ** 2
    zone_neg = jnp.where(moving, below_separatrix & stops_on_line, jnp.abs(A) <= a_s)
    zone_zero = jnp.where(f > 0, True, Adot == 0)
    out = jnp.where(neg, zone_neg, jnp.where(k == 0, zone_zero, True))
    return jnp.broadcast_to(out, jnp.broadcast_shapes(A.shape, k.shape, f.shape, fs.shape))


def stable_zone_boundary(
    k: ArrayLike, f: ArrayLike, n: int = 200, extent: float = 50.0
) -> tuple[Float[Array, " 4*n"], Float[Array, " 4*n"]]:
    """The boundary of the stable zone of a loaded mode (k < 0), as a closed polygon.

    With λ = √|k| and a = f/|k|, the zone's upper half (Ȧ > 0) lies below the separatrix
    Ȧ = λ(a − A) and, for A < −a, above the hyperbola Ȧ = λ√((a − A)² − 4a²). The two curves
    are asymptotic, so the zone is a strip that tapers to zero width as A → −∞ (its lower
    half is the mirror image, tapering as A → +∞). The polygon runs from (a, 0) along the
    separatrix to A = −`extent`·a, back along the hyperbola to (−a, 0), then the mirror
    image; the truncated tails are narrower than 2a/`extent` times the zone's height.

    **Arguments:** `k` < 0 [1/s²] and `f` ≥ 0 [rad/s²] (scalars); `n` points per arc
    (static); `extent` > 1, how far the tails are drawn, in units of a.

    **Returns:** `(A, Adot)`, the polygon's vertices [rad, rad/s], each of shape (4n,).
    """
    k, f = float_leaf(k), float_leaf(f)
    lam = jnp.sqrt(-k)
    a = f / (-k)
    s = jnp.linspace(0.0, 1.0, n)
    A_far = -extent * a
    A_sep = a + (A_far - a) * s**2  # (a, 0) -> far left, denser near the saddle
    Ad_sep = lam * (a - A_sep)
    A_hyp = -a + (A_far + a) * (1 - s) ** 2  # far left -> (-a, 0), denser near the vertex
    Ad_hyp = lam * jnp.sqrt(jnp.maximum((a - A_hyp) ** 2 - 4 * a**2, 0.0))
    A_up = jnp.concatenate([A_sep, A_hyp])
    Ad_up = jnp.concatenate([Ad_sep, Ad_hyp])
    return jnp.concatenate([A_up, -A_up]), jnp.concatenate([Ad_up, -Ad_up])


def critical_load_velocity(
    rod: RodChannel,
    m: ArrayLike,
    Adot0: ArrayLike,
    mu: ArrayLike | None = None,
    planar: bool = False,
) -> Float[Array, "..."]:
    """F_cr,m = F⁰_m + ρ f²/(ω_m² Ȧ₀²) [N] (P7): the load at which a pure velocity
    perturbation of amplitude `Adot0` [rad/s] (lateral speed R·Ȧ₀) in mode `m` sits exactly
    on the stable zone's velocity intercept."""
    f = friction_amplitude(rod, mu, planar)
    om2 = wavenumber(rod, m) ** 2
    return frictionless_load(rod, m, planar) + rod.rho * f**2 / (om2 * float_leaf(Adot0) ** 2)


def critical_load_position(
    rod: RodChannel,
    m: ArrayLike,
    A0: ArrayLike,
    mu: ArrayLike | None = None,
    planar: bool = False,
) -> Float[Array, "..."]:
    """F_cr,m = F⁰_m + ρ f/(ω_m² A₀) [N] (P7): the load at which a pure position
    perturbation of amplitude `A0` [rad] in mode `m`, released from rest, leaves the stick
    line."""
    f = friction_amplitude(rod, mu, planar)
    om2 = wavenumber(rod, m) ** 2
    return frictionless_load(rod, m, planar) + rod.rho * f / (om2 * jnp.abs(float_leaf(A0)))


def critical_loads(
    rod: RodChannel,
    n_modes: int,
    amplitude: ArrayLike,
    kind: str = "velocity",
    mu: ArrayLike | None = None,
    planar: bool = False,
) -> Float[Array, " n_modes"]:
    """P7 for modes 1..`n_modes` (static int) when every mode receives the same pure
    perturbation `amplitude` (rad/s for `kind="velocity"`, rad for `kind="position"`)."""
    if kind not in ("velocity", "position"):
        raise ValueError(f"kind = {kind!r} is invalid: expected 'velocity' or 'position'.")
    if not isinstance(n_modes, int) or n_modes < 1:
        raise ValueError(f"n_modes = {n_modes!r} is invalid: expected an int >= 1.")
    m = jnp.arange(1, n_modes + 1)
    fn = critical_load_velocity if kind == "velocity" else critical_load_position
    return fn(rod, m, amplitude, mu, planar)


def min_critical_load(
    rod: RodChannel,
    n_modes: int,
    amplitude: ArrayLike,
    kind: str = "velocity",
    mu: ArrayLike | None = None,
    planar: bool = False,
) -> tuple[Float[Array, ""], Int[Array, ""]]:
    """The lowest P7 load over modes 1..`n_modes` and the mode that attains it.

    **Returns:** `(F_cr, m)` — the load [N] and the mode number (int).
    """
    loads = critical_loads(rod, n_modes, amplitude, kind, mu, planar)
    i = jnp.argmin(loads)
    return loads[i], i + 1


def held_end_amplitude(rod: RodChannel, dF: ArrayLike, m: ArrayLike = 6) -> Float[Array, "..."]:
    """A_held = (2/(R ω_m)) √(ΔF/EA) [rad]: the amplitude of mode `m` whose end shortening
    ∫½y'² ds = (R A ω_m)² L/4 relieves a load excess ΔF = F − F⁰ [N] of a rod whose ends are
    held (EA·shortening/L = ΔF). A rod with held ends that buckles settles near this amplitude
    instead of growing without bound (0.38 rad at ΔF = 5 N for the reference rod), so a fixed
    0.5 rad threshold cannot tell buckled from stable there."""
    return 2.0 / (rod.R * wavenumber(rod, m)) * jnp.sqrt(jnp.maximum(float_leaf(dF), 0.0) / rod.EA)
