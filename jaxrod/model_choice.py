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
    """A cheap model, with its resolution, whose answer is within 2 % of the finest field
    model's, as measured by `benchmarks/model_choice.py` on the reference rod (table in
    benchmarks/README.md, "Which model for which scene"): the cheapest measured one, unless a
    slightly dearer one holds over the whole load range (said below where so).

    The rule, and the measurements behind it (relative errors against the finest field model:
    768 nodes for the sine scenes, 1536 for the random ones; horizon 0.5 s; critical values by
    bisection):

    - `"sine"` (mode-6 lateral velocity), ΔF ≤ 1 N: the single-mode oscillator, `("mode",
      None)`. Its critical speed v₀* is 0.17 % off at ΔF = 1 N, but 5.5 % off at 5 N and 69 %
      at 20 N, where friction feeds the odd harmonics of mode 6 (18, 30, …).
    - `"sine"`, 1 N < ΔF ≤ 20 N: the field model with 128 nodes (v₀* 0.67 % off at 5 N and
      0.17 % at 20 N; 64 nodes are 3.7 % off at 5 N). Past 20 N: 384 nodes (the package's
      `default_nodes`; field_convergence.py: 128 nodes are 2.2 % off at 60 N, 384 within
      0.3 %). Models that land within 2 % at one load only (32 nodes at 20 N but 14 % off at
      5 N) are not picked; Galerkin with 32 modes was also within 2 % at 5 and 20 N (0.17 %,
      1.1 %) at about the same cost, but its accuracy past 20 N was not measured.
    - `"random-position"` (forces for 1 ms, then released): the field model with 384 nodes
      (mean critical load δF* 1.2 % off at μ = 0.05 and 0.34 % at μ = 1, same dominant
      mode; 128 nodes are 11 % and 6.2 % off; Galerkin with 64 modes is within 2 % too but
      runs 6-20× longer).
    - `"random-velocity"`: the field model with 768 nodes (δF* 0.47 % off at μ = 0.05 and
      0.41 % at μ = 1, same dominant mode; 384 nodes are 8.9 % and 2.6 % off, 128 nodes 75 %
      and 19 %). The perturbation, drawn on the reference paper's 500 segments, puts as much
      energy in mode 499 as in mode 6, and pointwise friction couples them all: a model that
      does not resolve the whole perturbation gets the critical load wrong.
    - `"random-shape"` (not measured): as `"random-velocity"`, a white-noise state too.

    The measured choice did not depend on μ (0.05 and 1 for the random scenes; the sine scenes
    were measured at μ = 0.3), so `mu` is only checked. The thresholds are in newtons of the
    reference rod; for another rod they are a heuristic.

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
