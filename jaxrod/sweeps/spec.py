"""What a sweep is, apart from its swept values: `SweepSpec`, the names a sweep takes and the outputs it gives."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping


from ..models.recipe import AbstractRecipe
from ..registry import name_of, perturbation_class, recipe

__all__ = ['ROD_FIELDS', 'PARAMETERS', 'OUTPUTS', 'SweepSpec']


ROD_FIELDS = ("L", "d", "E", "rho_v", "nu", "R", "g", "mu_s", "mu_d")


PARAMETERS = ("dF", "amplitude", "mu", "realization") + ROD_FIELDS


_STIFFNESS_FIELDS = ("L", "d", "E", "rho_v", "R", "g")  # set the step limit


OUTPUTS = ("buckled", "t_buckle", "dominant_mode", "max_theta", "final_theta", "stuck", "t_stop", "result",
           "steps")


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """Everything about a sweep except the swept values (plain and JSON-serialisable, the model
    by its name in `to_json`).

    - `model`: the model's recipe (an `AbstractRecipe` instance, registered or not) or the name
      of a registered one: "mode", "galerkin", "field" or "rod3d" (the full 3D rod, [`jaxrod.rod3d.Rod3D`][],
      under the dead load F⁰_m* + ΔF with friction at the contact point; `n` segments, default
      60; dt 0.5 of its explicit limit; `threshold` on max|θ| as for the other models).
    - `perturbation`: "sine", "random-velocity", "random-position" or "random-shape"
      (amplitude units as in [`jaxrod.registry.make_perturbation`][]; "random-position", a
      timed force pulse of 1 ms, for "rod3d" too).
    - `mu`: friction coefficient (μ_s = μ_d) unless swept; `dF` [N], `amplitude` defaults.
    - `mode`: sine / single mode number; `n`: nodes, modes or 3D segments (`None`: the
      default for the largest load of the sweep); `dt` [s] (`None`: 0.4 of the step limit of
      the stiffest member, 0.5 for "rod3d"); `t1` [s] horizon; `threshold` [rad] buckling
      amplitude.
    - `rod`: overrides of the reference rod's fields (e.g. `{"R": 0.01}`).
    """

    model: str | AbstractRecipe = "field"
    perturbation: str = "sine"
    mu: float = 0.3
    dF: float = 5.0
    amplitude: float = 0.01
    mode: int = 6
    n: int | None = None
    dt: float | None = None
    t1: float = 2.0
    threshold: float = 0.5
    duration: float = 1e-3
    rod: Mapping[str, float] = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        cls = recipe(self.model, "SweepSpec.model")
        if self.n is not None and not (isinstance(self.n, int) and self.n >= cls.min_size):
            raise ValueError(f"SweepSpec.n = {self.n!r} is invalid for model {name_of(self.model)!r}: expected an int >= "
                             f"{cls.min_size} {cls.size_name or ''}".rstrip() + ".")
        perturbation_class(self.perturbation, "SweepSpec.perturbation")
        if not (isinstance(self.t1, (int, float)) and self.t1 > 0):
            raise ValueError(f"SweepSpec.t1 = {self.t1!r} is invalid: expected > 0 s.")
        bad = set(self.rod) - set(ROD_FIELDS)
        if bad:
            raise ValueError(f"SweepSpec.rod has unknown field(s) {sorted(bad)}; valid: {ROD_FIELDS}.")

    def to_json(self) -> dict:
        d = dataclasses.asdict(self)
        d["model"] = name_of(self.model)  # a recipe by its registered name (or its class's)
        d["rod"] = dict(self.rod)
        return d

