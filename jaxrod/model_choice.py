"""Which model answers a scene: the rule measured by `benchmarks/model_choice.py`."""

from __future__ import annotations

import math


__all__ = ["choose_model"]

# Thresholds of the rule, from benchmarks/results/model_choice.csv (reference rod).
SINGLE_MODE_MAX_DF = 1.0  # N: sine perturbations, single mode 0.17 % off at 1 N, 5.5 % at 5 N
FINE_FIELD_DF = 20.0  # N: past it more than 32 modes are unstable and 128 nodes no longer suffice
# perturbation: ((the largest ΔF [N] the row holds for, model, n), ...), the first row that holds
RULES = {
    "sine": ((SINGLE_MODE_MAX_DF, "mode", None), (FINE_FIELD_DF, "field", 128), (math.inf, "field", 384)),
    "random-position": ((math.inf, "field", 384),),
    "random-velocity": ((math.inf, "field", 768),),
    "random-shape": ((math.inf, "field", 768),),  # not measured: a white-noise state, as the random velocity
}


def choose_model(perturbation: str, dF: float, mu: float) -> tuple[str, int | None]:
    """A cheap model, with its resolution, whose answer is within the tolerance of
    `benchmarks/model_choice.py` of the finest field model's on the reference rod: the cheapest
    measured one, unless a slightly dearer one holds over the whole load range. The measurements
    behind each row, with their commit, are the table "Which model for which scene" in
    benchmarks/README.md.

    The rule (`RULES`):

    - `"sine"` (mode-6 lateral velocity), ΔF ≤ `SINGLE_MODE_MAX_DF`: the single-mode oscillator,
      `("mode", None)`; above it friction feeds the odd harmonics of mode 6 (18, 30, …) and the
      single mode drifts off.
    - `"sine"` up to `FINE_FIELD_DF`: the field model with 128 nodes; past it, where more than 32
      modes are unstable, 384 nodes (the package's `default_nodes`).
    - `"random-position"` (forces for 1 ms, then released): the field model with 384 nodes.
    - `"random-velocity"`: the field model with 768 nodes. The perturbation, drawn on the
      reference paper's 500 segments, puts as much energy in mode 499 as in mode 6, and pointwise
      friction couples them all: a model that does not resolve the whole perturbation gets the
      critical load wrong.
    - `"random-shape"` (not measured): as `"random-velocity"`, a white-noise state too.

    The measured choice did not depend on μ, so `mu` is only checked. The thresholds are in
    newtons of the reference rod; for another rod they are a heuristic.

    **Arguments:**

    - `perturbation`: a perturbation name with a measured rule (`RULES`).
    - `dF`: the largest load above F⁰_m* the computation meets [N] (for a critical-load
      search: the top of its bracket).
    - `mu`: the (largest) friction coefficient, ≥ 0.

    **Returns:** `(model, n)`: `"mode"`, `"galerkin"` or `"field"`, and the number of nodes or
    modes (`None` for the single mode).

    **Raises:** `ValueError` for an unknown perturbation, a non-finite `dF` or a negative or
    non-finite `mu`.
    """
    if perturbation not in RULES:
        raise ValueError(f"perturbation = {perturbation!r} is invalid: expected one of {tuple(RULES)} (those measured).")
    if not math.isfinite(dF):
        raise ValueError(f"dF = {dF!r} is invalid: expected a finite load [N].")
    if not (math.isfinite(mu) and mu >= 0):
        raise ValueError(f"mu = {mu!r} is invalid: expected a finite friction coefficient >= 0.")
    return next((model, n) for top, model, n in RULES[perturbation] if dF <= top)
