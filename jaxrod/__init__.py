"""jaxrod: dynamics and stability of an elastic rod confined in a channel with dry friction."""

from importlib.metadata import PackageNotFoundError, version

from . import theory as theory
from ._results import RESULTS as RESULTS
from .friction import AbstractFriction as AbstractFriction
from .friction import Coulomb as Coulomb
from .friction import Tanh as Tanh
from .friction import coulomb_prox as coulomb_prox
from .integrators import AbstractFixedStep as AbstractFixedStep
from .integrators import AbstractIntegrator as AbstractIntegrator
from .integrators import DiffraxSmooth as DiffraxSmooth
from .integrators import Exact as Exact
from .integrators import ProjectedVerlet as ProjectedVerlet
from .integrators import RunOptions as RunOptions
from .integrators import SplitLinearFriction as SplitLinearFriction
from .integrators import SymplecticEuler as SymplecticEuler
from . import modal as modal
from . import perturbations as perturbations
from . import boundary as boundary
from . import scene as scene
from . import search as search
from . import stability_map as stability_map
from . import worst_case as worst_case
from . import rod3d as rod3d
from .sweeps import SweepResult as SweepResult
from .sweeps import SweepSpec as SweepSpec
from .sweeps import sweep as sweep
from .sweeps import wilson_interval as wilson_interval
from .perturbations import RandomForce as RandomForce
from .perturbations import RandomShape as RandomShape
from .perturbations import RandomVelocity as RandomVelocity
from .perturbations import SineVelocity as SineVelocity
from .perturbations import UserState as UserState
from .loads import AbstractLoad as AbstractLoad
from .loads import ConstantLoad as ConstantLoad
from .loads import RampLoad as RampLoad
from .models import AbstractModel as AbstractModel
from .models import FieldModel as FieldModel
from .models import GalerkinModel as GalerkinModel
from .models import SingleMode as SingleMode
from .models import exact_solution as exact_solution
from .params import RodChannel as RodChannel
from .simulate import simulate as simulate
from .solution import Solution as Solution

try:
    __version__ = version("jaxrod")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "0.0.0"
