from .base import AbstractFixedStep as AbstractFixedStep
from .base import AbstractIntegrator as AbstractIntegrator
from .base import RunOptions as RunOptions
from .exact import Exact as Exact
from .explicit import SplitLinearFriction as SplitLinearFriction
from .explicit import SymplecticEuler as SymplecticEuler
from .smooth import DiffraxSmooth as DiffraxSmooth
from .verlet import ProjectedVerlet as ProjectedVerlet
from .leapfrog import ProjectedLeapfrog as ProjectedLeapfrog


SCHEMES = {"leapfrog": ProjectedLeapfrog, "verlet": ProjectedVerlet}
"""The projected schemes by the name a model's `scheme` gives."""


def default_for(model, dt: float, **kwargs) -> AbstractFixedStep:
    """The fixed-step integrator a run of `model` uses by default, step `dt` [s] (`kwargs`, e.g.
    `friction`, go to it): `SCHEMES[model.scheme]`, [`jaxrod.ProjectedLeapfrog`][] for the 3D rod,
    [`jaxrod.ProjectedVerlet`][] for the reduced models."""
    return SCHEMES[model.scheme](dt, **kwargs)
