"""jaxrod: dynamics and stability of an elastic rod confined in a channel with dry friction.

The top level holds what a user reaches for: the rod (`RodChannel`), the models (one
`AbstractModel` interface: `SingleMode`, `GalerkinModel`, `FieldModel`, `Rod3D`), friction laws,
integrators and `simulate`, perturbations, `Scene`, `sweep`, and the boundary searches
(`critical_velocity`, `critical_load`). Submodules hold the rest (`theory`, `modal`,
`batching`, `distributed`, `boundary`, `stability_map`, `worst_case`, `experiments`,
`reproduce`).
"""

from typing import TYPE_CHECKING

from . import _xla

_xla.configure()  # before JAX starts its CPU backend: see jaxrod/_xla.py

from . import _cache

_cache.configure()  # the persistent compilation cache: see jaxrod/_cache.py

from . import boundary as boundary
from . import distributed as distributed
from . import modal as modal
from . import perturbations as perturbations
from . import rod3d as rod3d
from . import scene as scene
from . import stability_map as stability_map
from . import theory as theory
from . import worst_case as worst_case
from ._results import RESULTS as RESULTS
from ._version import __version__ as __version__
from .boundary import critical_load as critical_load
from .boundary import critical_velocity as critical_velocity
from .friction import AbstractFriction as AbstractFriction
from .friction import Coulomb as Coulomb
from .friction import Tanh as Tanh
from .friction import coulomb_prox as coulomb_prox
from .integrators import AbstractFixedStep as AbstractFixedStep
from .integrators import AbstractIntegrator as AbstractIntegrator
from .integrators import Exact as Exact
from .integrators import ProjectedLeapfrog as ProjectedLeapfrog
from .integrators import ImplicitLeapfrog as ImplicitLeapfrog
from .integrators import AdaptiveImplicitLeapfrog as AdaptiveImplicitLeapfrog
from .integrators import ProjectedVerlet as ProjectedVerlet
from .integrators import RunOptions as RunOptions
from .integrators import SplitLinearFriction as SplitLinearFriction
from .integrators import SymplecticEuler as SymplecticEuler
from .loads import AbstractLoad as AbstractLoad
from .loads import ConstantLoad as ConstantLoad
from .loads import RampLoad as RampLoad
from .models import AbstractModel as AbstractModel
from .models import FieldModel as FieldModel
from .models import GalerkinModel as GalerkinModel
from .models import SingleMode as SingleMode
from .models import exact_solution as exact_solution
from .params import RodChannel as RodChannel
from .perturbations import RandomForce as RandomForce
from .perturbations import RandomShape as RandomShape
from .perturbations import RandomVelocity as RandomVelocity
from .perturbations import SineVelocity as SineVelocity
from .perturbations import UserState as UserState
from .problem import Problem as Problem
from .rod3d import Rod3D as Rod3D
from .scene import Scene as Scene
from .simulate import simulate as simulate
from .solution import Solution as Solution
from .sweeps import SweepResult as SweepResult
from .sweeps import SweepSpec as SweepSpec
from .sweeps import sweep as sweep
from .sweeps import wilson_interval as wilson_interval

__all__ = [
    "RESULTS", "AbstractFixedStep", "AbstractFriction", "AbstractIntegrator", "AbstractLoad",
    "AbstractModel", "ConstantLoad", "Coulomb", "DiffraxSmooth", "Exact", "FieldModel",
    "AdaptiveImplicitLeapfrog", "GalerkinModel", "ImplicitLeapfrog", "Problem", "ProjectedLeapfrog", "ProjectedVerlet", "RampLoad", "RandomForce", "RandomShape",
    "RandomVelocity", "Rod3D", "RodChannel", "RunOptions", "Scene", "SineVelocity", "SingleMode",
    "Solution", "SplitLinearFriction", "SweepResult", "SweepSpec", "SymplecticEuler", "Tanh",
    "UserState", "__version__", "boundary", "coulomb_prox", "critical_load", "critical_velocity",
    "distributed", "exact_solution", "modal", "perturbations", "rod3d", "scene", "simulate",
    "stability_map", "sweep", "theory", "wilson_interval", "worst_case",
]


if TYPE_CHECKING:  # imported on first use (diffrax: 0.7 s), see `__getattr__`
    from .integrators.smooth import DiffraxSmooth as DiffraxSmooth


def __getattr__(name):
    if name == "DiffraxSmooth":
        from .integrators.smooth import DiffraxSmooth

        return DiffraxSmooth
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
