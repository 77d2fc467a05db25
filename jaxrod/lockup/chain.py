"""The chained rod of docs/physics.md §8: a helical section near the pushed entry, then a
sinusoidal one down to 2F₀, then a straight one, each transferring force by its closed form
(`jaxrod.lockup.closed_forms`): the far-end force, the force along the rod, the largest force
that reaches the far end, the lock-up length and the sections' extents."""

from __future__ import annotations

import math

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .closed_forms import HELICAL_LAWS, HELICAL_ONSETS, SINUSOIDAL_LAWS
from .._numerics import float_leaf
from .closed_forms import _check, _choice, _rod, _si, _transfer, _transfer_length, transfer_length

__all__ = ["wall_force", "far_force", "entry_force", "force_profile", "far_force_max", "lockup_length", "section_extents"]

# ---------------------------------------------------------------------------------------------
# The chain: helical near the entry, then sinusoidal, then straight (P14–P16).

def _laws(helical_onset: str = "chen", sinusoidal_law: str = "weight",
          helical_law: str = "with_weight"):
    fh = _choice("helical_onset", helical_onset, HELICAL_ONSETS)
    sin = _choice("sinusoidal_law", sinusoidal_law, SINUSOIDAL_LAWS)
    hel = _choice("helical_law", helical_law, HELICAL_LAWS)
    return fh, 2.0, sin, hel


def _chain(f_in, X, fh, fs, sin, hel):
    """f_far, and the friction lengths of the helical and sinusoidal sections, for f_in ≥ 0
    and X = μL/ℓ ≥ 0 (dimensionless)."""
    # Helical section: from f_in down to the helical onset (none if f_in <= fh).
    f_hi = jnp.maximum(f_in, fh)
    xh = jnp.maximum(_transfer_length(f_hi, fh, *hel), 0.0)
    far_h = _transfer(f_hi, jnp.minimum(X, xh), *hel)
    # Sinusoidal section: from min(f_in, fh) down to the sinusoidal onset.
    f1 = jnp.minimum(f_in, fh)
    X1 = jnp.maximum(X - xh, 0.0)
    f1_hi = jnp.maximum(f1, fs)
    xs = jnp.maximum(_transfer_length(f1_hi, fs, *sin), 0.0)
    far_s = _transfer(f1_hi, jnp.minimum(X1, xs), *sin)
    # Straight section: w_c = w.
    f2 = jnp.minimum(f1, fs)
    X2 = jnp.maximum(X1 - xs, 0.0)
    far_0 = jnp.maximum(f2 - X2, 0.0)
    in_h = (f_in > fh) & (X <= xh)
    in_s = (f1 > fs) & (X1 <= xs)
    far = jnp.where(in_h, far_h, jnp.where(in_s, far_s, far_0))
    return far, jnp.minimum(xh, X), jnp.minimum(xs, X1)


def wall_force(F: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike, *,
               helical_onset: str = "chen", sinusoidal_law: str = "weight",
               helical_law: str = "with_weight") -> Float[Array, "..."]:
    """The wall force per length [N/m] of the chained model (P11) at the compressive force
    `F` [N]: w up to the sinusoidal onset 2F₀, the sinusoidal law up to the helical onset
    (included), the helical law above it.

    **Arguments:** `F` [N] ≥ 0; `EI` [N·m²], `w` [N/m], `r` [m] > 0; the static choices
    `helical_onset` (a key of [`HELICAL_ONSETS`][jaxrod.lockup.closed_forms.HELICAL_ONSETS]),
    `sinusoidal_law` (of `SINUSOIDAL_LAWS`), `helical_law` (of `HELICAL_LAWS`).

    **Raises:** `ValueError` naming the argument for concrete invalid input or an unknown choice.
    """
    fh, fs, (a_s, b_s), (a_h, b_h) = _laws(helical_onset, sinusoidal_law, helical_law)
    EI, w, r = _rod(EI, w, r)
    f = _check("F", F, "N") / jnp.sqrt(EI * w / r)
    law = jnp.where(f > fh, a_h + b_h * f**2, jnp.where(f > fs, a_s + b_s * f**2, 1.0))
    return w * law


def far_force(F_in: ArrayLike, L: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
              mu: ArrayLike, *, helical_onset: str = "chen", sinusoidal_law: str = "weight",
              helical_law: str = "with_weight") -> Float[Array, "..."]:
    """The force [N] that reaches the far end of a rod of length `L` [m] pushed at its entry
    with `F_in` [N] (P14): the section near the entry is helical while F exceeds the helical
    onset, then sinusoidal down to 2F₀, then straight; each piece is the closed form P12 over
    the length P13 it needs, chained. 0 where the force dies out before the far end.

    **Arguments:** `F_in` [N] ≥ 0 (inf allowed: see
    [`far_force_max`][jaxrod.lockup.chain.far_force_max]),
    `L` [m] ≥ 0, `EI` [N·m²], `w` [N/m], `r` [m] > 0, `mu` ≥ 0; the static choices as in
    [`wall_force`][jaxrod.lockup.chain.wall_force].

    **Returns:** F_far [N], the broadcast shape. Increasing in `F_in`, decreasing in `L` and
    `mu`, with dF_far/dF_in = w_c(F_far)/w_c(F_in) (P16).

    **Raises:** `ValueError` naming the argument for concrete invalid input or an unknown choice.
    """
    fh, fs, sin, hel = _laws(helical_onset, sinusoidal_law, helical_law)
    L = _check("L", L, "m")
    f_in, X, F0 = _si(F_in, L, EI, w, r, mu)
    return F0 * _chain(f_in, X, fh, fs, sin, hel)[0]


def entry_force(F_far: ArrayLike, L: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike, mu: ArrayLike, *,
                helical_onset: str = "chen", sinusoidal_law: str = "weight",
                helical_law: str = "with_weight") -> Float[Array, "..."]:
    """The entry force [N] a rod of length `L` [m] sliding toward its far end needs to push the
    load `F_far` [N] there: P11 integrated backward from the far end (straight up to 2F₀, then
    sinusoidal up to the helical onset, then helical), the inverse of
    [`far_force`][jaxrod.lockup.chain.far_force] for `F_far` > 0 (F_far + μwL for `F_far` = 0: the
    whole rod must slide). `inf` where the helical section's force diverges within the length
    (`F_far` above F_far,max(L), past lock-up). Arguments as in `far_force`.
    """
    fh, fs, sin, hel = _laws(helical_onset, sinusoidal_law, helical_law)
    L, F_far = _check("L", L, "m"), _check("F_far", F_far, "N")
    f_far, X, F0 = _si(F_far, L, EI, w, r, mu)
    x0 = jnp.maximum(fs - f_far, 0.0)  # the straight section, up to the sinusoidal onset
    f1, X1 = jnp.maximum(f_far, fs), jnp.maximum(X - x0, 0.0)
    xs = jnp.maximum(_transfer_length(jnp.maximum(f1, fh), f1, *sin), 0.0)  # the sinusoidal one
    f2, X2 = jnp.maximum(f1, fh), jnp.maximum(X1 - xs, 0.0)
    f_in = jnp.where(X <= x0, f_far + X, jnp.where(X1 <= xs, _backward(f1, X1, *sin), _backward(f2, X2, *hel)))
    return F0 * f_in


def _backward(f, x, a, b):
    """The force at the start of a friction length `x` of a section with wall force w (a + b f²)
    that ends with the force `f` (P12 run backward; `inf` where it diverges)."""
    if b == 0:
        return f + a * x
    if a == 0:
        den = 1.0 / jnp.where(f > 0, f, 1.0) - b * x
        return jnp.where(f > 0, jnp.where(den > 0, 1.0 / jnp.where(den > 0, den, 1.0), jnp.inf), 0.0)
    c = math.sqrt(a / b)
    phi = jnp.arctan(f / c) + math.sqrt(a * b) * x
    return jnp.where(phi < 0.5 * math.pi, c * jnp.tan(jnp.minimum(phi, 0.5 * math.pi)), jnp.inf)


def force_profile(F_in: ArrayLike, s: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                  mu: ArrayLike, **laws: str) -> Float[Array, "..."]:
    """The axial force F(s) [N] at the distances `s` [m] from the entry of a rod pushed with
    `F_in` [N] (P14): the force that reaches the end of the first `s` metres, which is what
    [`far_force`][jaxrod.lockup.chain.far_force] computes (the chain is the flow of one
    autonomous equation, P11). `laws` as in `far_force`.
    """
    return far_force(F_in, s, EI, w, r, mu, **laws)


def far_force_max(L: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike, mu: ArrayLike,
                  **laws: str) -> Float[Array, "..."]:
    """F_far,max(L) [N] (P14): the largest force that can reach the far end of a rod of length
    `L` [m] however hard it is pushed (`far_force` at F_in → ∞). With the default laws,
    F_far,max/F₀ depends on μL/ℓ alone: 2 cot(μL/(2ℓ)) while the whole rod can be helical
    (μL/ℓ ≤ 2 arctan(1/√2) = 1.231), then the sinusoidal and straight pieces, 0 from the lock-up
    length on. `laws` as in [`far_force`][jaxrod.lockup.chain.far_force].
    """
    return far_force(jnp.inf, L, EI, w, r, mu, **laws)


def lockup_length(EI: ArrayLike, w: ArrayLike, r: ArrayLike, mu: ArrayLike, *, F_in: ArrayLike | None = None,
                  helical_onset: str = "chen", sinusoidal_law: str = "weight",
                  helical_law: str = "with_weight") -> Float[Array, "..."]:
    """The lock-up length L_lock [m] of the chained model (P15): beyond it no force reaches the
    far end however hard the rod is pushed (F_far,max = 0). μL_lock/ℓ is the sum of the three
    sections' friction lengths from an unbounded push: the helical one from ∞ to the helical
    onset f_h (2(π/2 − arctan(f_h/2)) with the weight term, 4/f_h without), the sinusoidal one
    from f_h to 2, and 2 for the straight one. 4.059 ℓ/μ with the default laws; inf at μ = 0.

    With `F_in` [N], the entry force is bounded: the length beyond which `F_in` pushes nothing to
    the far end (the same sum from f_in = F_in/F₀ down; `far_force(F_in, L)` is 0 from it on),
    the closed forms' counterpart of a rod run that resolves entry forces up to `F_in` only
    (`jaxrod.lockup.staircase`).

    **Raises:** `ValueError` naming the argument for concrete invalid input or an unknown choice.
    """
    fh, fs, sin, hel = _laws(helical_onset, sinusoidal_law, helical_law)
    EI, w, r = _rod(EI, w, r)
    mu = _check("mu", mu, "")
    ell = jnp.sqrt(EI / (r * w))
    if F_in is None:
        X = transfer_length(jnp.inf, fh, *hel) + transfer_length(fh, fs, *sin) + fs
    else:
        f = _check("F_in", F_in, "N") / jnp.sqrt(EI * w / r)
        X = (_transfer_length(jnp.maximum(f, fh), fh, *hel) + _transfer_length(jnp.clip(f, fs, fh), fs, *sin)
             + jnp.minimum(f, fs))
    return X * ell / mu


def section_extents(F_in: ArrayLike, L: ArrayLike, EI: ArrayLike, w: ArrayLike, r: ArrayLike,
                    mu: ArrayLike, **laws: str) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """The lengths [m] of the helical and the sinusoidal sections (from the entry: helical
    first) of a rod of length `L` [m] pushed with `F_in` [N] (P14); the rest, L minus both, is
    straight. At μ = 0 the force is F_in all along and one section holds the whole rod.

    **Returns:** `(L_helical, L_sinusoidal)` [m], each the broadcast shape.
    """
    fh, fs, sin, hel = _laws(**laws)
    L = _check("L", L, "m")
    f_in, X, _ = _si(F_in, L, EI, w, r, mu)
    EI, w, r, mu = float_leaf(EI), float_leaf(w), float_leaf(r), float_leaf(mu)
    ell = jnp.sqrt(EI / (r * w))
    _, xh, xs = _chain(f_in, X, fh, fs, sin, hel)

    at_zero = mu == 0  # then X = 0: the force is F_in all along, decide by its level alone

    def to_metres(x):
        return jnp.minimum(x * ell / jnp.where(at_zero, 1.0, mu), L)

    lh = jnp.where(at_zero, jnp.where(f_in > fh, L, 0.0), to_metres(xh))
    ls = jnp.where(at_zero, jnp.where((f_in > fs) & (f_in <= fh), L, 0.0), to_metres(xs))
    return lh, ls
