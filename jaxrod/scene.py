"""Scenes: the loaded rod, one model of it and one perturbation, from a few plain settings.

This is the layer the CLI and the sweeps use. ΔF is always measured from the frictionless load
of the rod's critical mode F⁰_m* (P5; 1.308 N for the reference rod), whatever the model.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from . import theory
from ._numerics import float_leaf
from .integrators import AbstractFixedStep, ProjectedVerlet, default_for
from .integrators.base import RunOptions
from .models.dof import DT_FRACTION, static_float
from .models.field import DEFAULT_NODES, FieldModel, default_nodes
from .models.galerkin import DEFAULT_MODES
from .models.recipe import AbstractRecipe
from .params import RodChannel
from .perturbations import AbstractPerturbation, SineVelocity
from .problem import DEFAULT_T1, Problem
from .registry import model_names, name_of, perturbation_names, recipe

__all__ = ["Scene", "MODELS", "PERTURBATIONS", "DEFAULT_NODES", "DEFAULT_MODES", "DEFAULT_T1",
           "default_nodes", "scheme_for"]

# the built-in names (`jaxrod.registry.model_names()` and `perturbation_names()` include any registered since)
MODELS = model_names()
PERTURBATIONS = perturbation_names()


class Scene(eqx.Module):
    """A rod loaded to F = F⁰_m* + `dF`, one model of it, and one perturbation.

    **Arguments:**

    - `rod`: the [`jaxrod.RodChannel`][].
    - `dF`: load above the critical mode's frictionless load [N] (dynamic).
    - `perturbation`: any perturbation (dynamic leaves: amplitude, key, ...).
    - `kind`: the model's recipe (a [`jaxrod.models.recipe.AbstractRecipe`][] instance, registered
      or not), or the name of a registered one: `"mode"`, `"galerkin"`, `"field"` or `"rod3d"` (the full 3D rod,
      [`jaxrod.rod3d.Rod3D`][], under the dead load F with friction at the contact point;
      perturbations as lateral velocities or offsets of its nodes) (static).
    - `n`: nodes (field; default `default_nodes` of the load: 128, or 384 past 32 unstable
      modes), modes (Galerkin, default 32) or segments (3D rod, default 60) (static).
    - `mode`: the single-mode model's mode (static, default 6).
    - `dt`: fixed step [s] (static; default 0.4 of the step limit at ΔF = 0 for field and
      Galerkin, 1e-4 s for one mode, 0.5 of the explicit limit for the 3D rod).
    - `threshold`: buckling amplitude max|θ| [rad] (static, default 0.5).
    - `grid_dt`: step of that grid's forcing phase (static; default 0.4 of its limit).
    - `scheme_key`: the runs' scheme, a key of `jaxrod.integrators.SCHEMES` (static; default
      `None`: the model's choice under the perturbation and the load, `scheme`).
    - `n_grid`: nodes of the field grid on which random perturbations are drawn before being
      projected onto the single mode (static).
    """

    rod: RodChannel
    dF: Float[Array, ""] = eqx.field(converter=float_leaf)
    perturbation: AbstractPerturbation = eqx.field(default_factory=lambda: SineVelocity(0.01, 6.0))
    kind: str | AbstractRecipe = eqx.field(static=True, default="field")
    n: int | None = eqx.field(static=True, default=None)
    mode: int = eqx.field(static=True, default=6)
    dt: float | None = eqx.field(static=True, default=None)
    n_grid: int = eqx.field(static=True, default=128)
    threshold: float = eqx.field(static=True, default=0.5)
    grid_dt: float | None = eqx.field(static=True, default=None)
    scheme_key: str | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        cls = recipe(self.kind)
        if not (isinstance(self.mode, int) and self.mode >= 1):
            raise ValueError(f"mode = {self.mode!r} is invalid: expected an int >= 1.")
        if self.n is not None and not (isinstance(self.n, int) and self.n >= cls.min_size):
            raise ValueError(f"n = {self.n!r} is invalid for the {name_of(self.kind)} model: expected an int >= "
                             f"{cls.min_size} ({cls.size_name}).")
        if self.dt is not None and not (isinstance(self.dt, (int, float)) and self.dt > 0):
            raise ValueError(f"dt = {self.dt!r} is invalid: expected a float > 0 [s].")

    @property
    def recipe(self):
        """The recipe of the scene's model (`jaxrod.registry.recipe(kind)`)."""
        return recipe(self.kind)

    @property
    def model_class(self):
        """The class of the scene's model (its recipe's `model_class`)."""
        return self.recipe.model_class

    @property
    def F(self) -> Float[Array, ""]:
        """The axial load [N]."""
        return theory.reference_load(self.rod) + self.dF

    def model(self):
        """The model of `kind` at the load F and `size()` (its recipe's `build`)."""
        return self.recipe.build(self.rod, self.F, self.size(), self.mode)

    def size(self) -> int | None:
        """The model's static size (field nodes, Galerkin modes, 3D segments; `None`: one mode):
        `n`, or the recipe's `default_size` at the (concrete) load under the perturbation."""
        if self.n is not None:
            return self.n
        try:
            return self.recipe.default_size(self.rod, self.F, self.perturbation)
        except jax.errors.ConcretizationTypeError:
            raise ValueError(
                "Scene.n must be given explicitly when the load is traced (e.g. vmapped over "
                "dF): the size is a static setting."
            ) from None

    def _grid(self):
        """The field model and integrator on which a field perturbation is drawn before it is
        projected onto a model that takes none (the single mode)."""
        grid = FieldModel.from_rod(self.rod, self.n_grid, F=self.F)
        step = self.grid_dt or DT_FRACTION * 2.0 / static_float(
            lambda: jnp.max(grid.max_frequency()),
            "Scene.dt must be given explicitly when the rod's stiffness parameters are traced (e.g. vmapped over "
            "EI, rho or R): the step is a static setting.")
        return grid, ProjectedVerlet(step)

    def step(self, model=None, scheme: str | None = None) -> float:
        """The fixed step [s], static, from the rod's concrete values: `dt`, or the recipe's
        `step` of `model` (default: `model()`) under `scheme` (default: `scheme()`): the reduced
        rod models 0.4 of the stability limit at ΔF = 0 and at most 0.25/λ_max; the single mode
        1e-4 s; the 3D rod its scheme's default step."""
        if self.dt is not None:
            return float(self.dt)
        from .integrators import default_step

        model = self.model() if model is None else model
        scheme = self.scheme(model) if scheme is None else scheme

        def scheme_step(model):
            try:
                return default_step(model, scheme=scheme)
            except jax.errors.ConcretizationTypeError:
                raise ValueError(f"Scene.dt must be given explicitly for the {name_of(self.kind)} model when the rod or the "
                                 "load is traced: the step is a static setting.") from None

        return self.recipe.step(model, self.rod, self.F, scheme_step)

    def scheme(self, model=None) -> str | None:
        """The scheme of the scene's runs (a key of `jaxrod.integrators.SCHEMES`; `None`: the
        model's own): the recipe's `scheme_under` the perturbation for `model` (default: `model()`)
        (the 3D rod runs its implicit default only under a perturbation measured adequate for it,
        `implicit_3d`, and below the wall's wrinkling load)."""
        if self.scheme_key is not None:
            return self.scheme_key
        return self.recipe.scheme_under(self.perturbation, self.model() if model is None else model)

    def integrator(self, model=None) -> AbstractFixedStep:
        """The run's integrator for `model` (default: `model()`): the scene's scheme (`scheme`;
        `jaxrod.integrators.default_for`) at `step`."""
        model = self.model() if model is None else model
        scheme = self.scheme(model)
        return default_for(model, self.step(model, scheme), scheme)

    def initial_state(self):
        """(q₀, v₀) in the model's coordinates (the recipe's `initial_state`; `resolve`'s)."""
        problem = self.resolve()
        return problem.q0, problem.v0

    def resolve(self, save_state: bool = True, model=None) -> Problem:
        """The scene resolved once into a [`jaxrod.Problem`][]: its model (`model`, or built once
        by `model()`), the integrator of its scheme at its step, the initial state under the
        perturbation (the recipe's `initial_state`) and the run's options (`threshold`;
        `save_state`: keep q and v at every save)."""
        model = self.model() if model is None else model
        integrator = self.integrator(model)
        q0, v0 = self.recipe.initial_state(model, self.perturbation, integrator, self._grid)
        return Problem(model, integrator, q0, v0, RunOptions(buckle_threshold=self.threshold, save_state=save_state))

    def run(self, t1: float = DEFAULT_T1, n_save: int = 201, save_state: bool = True, throw: bool = False):
        """Simulate the scene to `t1` [s] (`resolve().run(...)`); returns a [`jaxrod.Solution`][].
        The run stops when max|θ| passes `threshold` (buckled) or the rod is stuck."""
        return self.resolve(save_state).run(t1, n_save=n_save, throw=throw)

    def field_of(self, q):
        """θ on a grid of nodes for plots: (s [m], θ [rad]) from the model's coordinates."""
        return self.recipe.field_of(self.model(), q)

    def dominant_mode(self, q):
        """The dominant sine mode of the state `q` (the model's own mode for one mode)."""
        return self.recipe.dominant_mode(self.model(), q)


def scheme_for(kind: str, perturbation) -> str | None:
    """The scheme of a run of the model registered as `kind` under `perturbation` (`Scene.scheme`)."""
    return recipe(kind).scheme_under(perturbation)
