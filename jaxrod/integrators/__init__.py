from .base import AbstractFixedStep as AbstractFixedStep
from .base import AbstractIntegrator as AbstractIntegrator
from .base import RunOptions as RunOptions
from .exact import Exact as Exact
from .explicit import SplitLinearFriction as SplitLinearFriction
from .explicit import SymplecticEuler as SymplecticEuler
from .smooth import DiffraxSmooth as DiffraxSmooth
from .verlet import ProjectedVerlet as ProjectedVerlet
