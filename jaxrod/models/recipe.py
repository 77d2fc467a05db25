"""How a problem is posed for one model: its recipe.

A model ([`jaxrod.AbstractModel`][]) is the physics the integrators step. Everything a scene, a
sweep, a boundary search and the command line decide around it — the model of a rod at a load
and size, the default size and step, the scheme under a perturbation, the initial state, how a
search finds its root, how many lanes a sweep runs, how a state is read back as a field — is
its recipe's, registered with the model's name at the edge:

    jaxrod.registry.register_model("beads", BeadsRecipe())   # then Scene(kind="beads"), sweeps, CLI

Recipes hold no numbers (their methods take the rod, the load and the model), so one instance
serves every problem of its model.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx

__all__ = ["AbstractRecipe"]


class AbstractRecipe(eqx.Module):
    """How a problem is posed for one model class (`model_class`), and how its runs are read.

    Abstract: `build`, `default_size`, `step`, `field_of`, `dominant_mode` and the class
    constants `model_class`, `size_name`, `min_size`, `search_method`. The rest have defaults.
    """

    # the model class this recipe builds
    model_class: eqx.AbstractClassVar[type]
    # the name of the static size (`"nodes"`, `"modes"`, `"segments"`; `None`: no size) and its
    # least valid value
    size_name: eqx.AbstractClassVar[str | None]
    min_size: eqx.AbstractClassVar[int]
    # how a boundary search finds its root: `"exact"` (the closed form, sine perturbations),
    # `"departure"` (the departure rate) or `"bisection"` (on the label)
    search_method: eqx.AbstractClassVar[str]
    # the horizon of a critical-velocity search's runs [s] (sine velocity): a run that neither sticks
    # nor buckles by then counts as stable (`critical_velocity`, `boundary_curve`; `critical_load` keeps 2 s)
    search_horizon: ClassVar[float] = 2.0
    # lanes of a sweep's continuous batch (`jaxrod.sweep`; `None`: the batching default)
    sweep_lanes: ClassVar[int | None] = None
    # how `jaxrod.stability_map` fills its grid: `"grid"` runs every cell, `"search"` finds each
    # column's boundary by bisection and labels the rest (`jaxrod.map_columns`)
    map_fill: ClassVar[str] = "grid"
    # the cheaper model whose map starts each searched column (`None`: plain bisection)
    map_guide: ClassVar[str | None] = None

    @abc.abstractmethod
    def build(self, rod, F, size: int | None, mode: int):
        """The model of `rod` under the axial load `F` [N] at the static `size` (sine `mode` for
        the models that need one)."""

    @abc.abstractmethod
    def default_size(self, rod, F, perturbation) -> int | None:
        """The size a problem of `rod` at the concrete load `F` [N] under `perturbation` uses
        when none is given."""

    def scheme_under(self, perturbation, model=None) -> str | None:
        """The scheme (a key of `jaxrod.integrators.SCHEMES`) of a run under `perturbation`, of
        `model` where it is given (a scheme may depend on the load it carries); `None` (the
        default): the model's own (`model_class.scheme`)."""
        return None

    def bytes_per_member(self, size: int | None) -> int:
        """Memory one member of a batch holds [bytes] (the sweeps size chunks by it): by default
        state, velocity, acceleration, trial velocities, stencil temporaries and per-save records
        of `size` numbers each."""
        return 8 * (24 * (size or 1) + 64) + 4096

    @abc.abstractmethod
    def step(self, model, rod, F, scheme_step: Callable[[object], float]) -> float:
        """The fixed step [s] of a run of `model`, from concrete values (`scheme_step(model)`:
        the default step of the run's scheme, `jaxrod.integrators.default_step`)."""

    def initial_state(self, model, perturbation, integrator, grid: Callable[[], tuple]):
        """(q₀, v₀) of `model` under `perturbation` (`grid()`: a field model and its integrator,
        for models that take no field and get the perturbation projected); by default the
        perturbation's own (`AbstractPerturbation.initial_state`)."""
        return perturbation.initial_state(model, integrator)

    @abc.abstractmethod
    def field_of(self, model, q):
        """θ on a grid for plots: (s [m], θ [rad]) from the state `q` of `model` (any leading axes)."""

    @abc.abstractmethod
    def dominant_mode(self, model, q):
        """The dominant sine mode of the state `q` of `model` (any leading axes)."""
