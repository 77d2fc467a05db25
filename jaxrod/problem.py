"""A problem resolved once: the model, the integrator, the initial state and the run's options
of one scene, built together and then only run ([`jaxrod.Scene.resolve`][]).

Every run of a scene needs the same four objects, and each depends on the others (the step on
the model and its scheme, the initial state on the model and the integrator). `Scene` derives
them; a `Problem` holds them, so that the model is built once per problem and a run is one call:

    problem = jr.Scene(rod, 5.0, kind="field").resolve()
    sol = problem.run(t1=0.5)
"""

from __future__ import annotations

import equinox as eqx
from jaxtyping import PyTree

from .integrators import AbstractFixedStep
from .integrators.base import RunOptions
from .models.base import AbstractModel
from .simulate import simulate
from .solution import Solution

__all__ = ["Problem"]

DEFAULT_T1 = 2.0  # [s]: E3's horizon, the reference paper's


class Problem(eqx.Module):
    """The model, integrator, initial state (q₀, v₀) and options of one run, frozen.

    **Arguments:**

    - `model`: the [`jaxrod.AbstractModel`][].
    - `integrator`: its fixed-step integrator (its scheme at its step).
    - `q0`, `v0`: the initial state in the model's coordinates.
    - `options`: the run's [`jaxrod.RunOptions`][] (buckling threshold, what is saved).
    """

    model: AbstractModel
    integrator: AbstractFixedStep
    q0: PyTree
    v0: PyTree
    options: RunOptions

    def run(self, t1: float = DEFAULT_T1, n_save: int = 201, throw: bool = False) -> Solution:
        """Simulate to `t1` [s] ([`jaxrod.simulate`][]); returns a [`jaxrod.Solution`][]."""
        return simulate(self.model, self.integrator, self.q0, self.v0, t1, n_save=n_save, options=self.options,
                        throw=throw)
