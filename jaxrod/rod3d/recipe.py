"""The 3D rod's recipe: how a scene, a sweep, a boundary search and the command line pose a
problem for [`jaxrod.rod3d.Rod3D`][] (a dead load F at the free end) and read its runs."""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp

from ..modal import dominant_mode
from ..models.recipe import AbstractRecipe
from . import state
from .model import Rod3D
from .state import wall_angle

__all__ = ["Rod3DRecipe"]


class Rod3DRecipe(AbstractRecipe):
    """A rod of `size` segments (60 by default, as E1 and E6: docs/rod3d.md) under the dead load F
    at its free end; its scheme's default step; label bisection for boundary searches; one lane
    per device in a sweep."""

    model_class: ClassVar[type] = Rod3D
    size_name: ClassVar[str] = "segments"
    min_size: ClassVar[int] = 4
    search_method: ClassVar[str] = "bisection"  # the departure rate is opt-in (`boundary.search`)
    search_horizon: ClassVar[float] = 0.4  # E3's brackets keep their labels to 2 s (benchmarks/rod3d_commands.py)
    sweep_lanes: ClassVar[int] = 1  # a lane per core: its steps are large enough to fill one
    map_fill: ClassVar[str] = "search"  # its map's columns are monotone, and a cell costs seconds (docs/rod3d.md)
    map_guide: ClassVar[str | None] = "field"  # its E3 boundary lies near the field model's (docs/rod3d.md)
    default_segments: ClassVar[int] = 60

    def build(self, rod, F, size, mode) -> Rod3D:
        return Rod3D(rod, size, control="load", end_load=F)

    def default_size(self, rod, F, perturbation) -> int:
        return self.default_segments

    def scheme_under(self, perturbation, model=None) -> str | None:
        """Its implicit default under a perturbation measured adequate for it (`implicit_3d`) and,
        where `model` is given, below the wall's wrinkling load (`state.past_wrinkling` of its
        axial force), else the explicit leapfrog."""
        past = model is not None and state.past_wrinkling(model)
        return None if type(perturbation).implicit_3d and not past else "leapfrog"

    def bytes_per_member(self, size: int | None) -> int:
        """Positions, velocities, rotations, forces, caches: 20 numbers per node per state row."""
        return 8 * (24 * 20 * (size + 1) + 64) + 4096

    def step(self, model, rod, F, scheme_step) -> float:
        return scheme_step(model)  # its scheme's default step

    def field_of(self, model, q):
        return jnp.linspace(0.0, model.rod.L, model.n + 1), wall_angle(q.x)  # (s [m], θ [rad])

    def dominant_mode(self, model, q):
        return dominant_mode(wall_angle(q.x)[..., 1:-1])
