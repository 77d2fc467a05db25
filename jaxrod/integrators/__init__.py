from typing import TYPE_CHECKING

from .base import AbstractFixedStep as AbstractFixedStep
from .base import AbstractIntegrator as AbstractIntegrator
from .base import RunOptions as RunOptions
from .exact import Exact as Exact
from .explicit import SplitLinearFriction as SplitLinearFriction
from .explicit import SymplecticEuler as SymplecticEuler
from .verlet import ProjectedVerlet as ProjectedVerlet
from .leapfrog import ProjectedLeapfrog as ProjectedLeapfrog
from .implicit import ImplicitLeapfrog as ImplicitLeapfrog
from .adaptive import AdaptiveImplicitLeapfrog as AdaptiveImplicitLeapfrog

if TYPE_CHECKING:  # imported on first use: diffrax takes 0.7 s to import (`__getattr__`)
    from .smooth import DiffraxSmooth as DiffraxSmooth


def __getattr__(name):
    if name == "DiffraxSmooth":
        from .smooth import DiffraxSmooth

        return DiffraxSmooth
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


SCHEMES = {"leapfrog": ProjectedLeapfrog, "verlet": ProjectedVerlet, "implicit": ImplicitLeapfrog}
"""The projected schemes by the name a model's `scheme` gives."""


def _scheme_class(model, scheme: str | None):
    """`SCHEMES[scheme]`, or the model's own scheme's class for `None`."""
    name = model.scheme if scheme is None else scheme
    if name not in SCHEMES:
        raise ValueError(f"scheme = {name!r} is invalid: expected one of {tuple(SCHEMES)}.")
    return SCHEMES[name]


def default_step(model, q=None, scheme: str | None = None) -> float:
    """The step [s] a run of `model` from `q` takes by default with its scheme (or `scheme`, a key of
    `SCHEMES`): `default_step` of that integrator class (the implicit leapfrog: the model's
    `implicit_step`; an explicit scheme: half its stability limit at `q`)."""
    return _scheme_class(model, scheme).default_step(model, q)


def default_for(model, dt: float, scheme: str | None = None, **kwargs) -> AbstractFixedStep:
    """The fixed-step integrator a run of `model` uses by default, step `dt` [s] (`kwargs`, e.g.
    `friction`, go to it): `SCHEMES[model.scheme]`, [`jaxrod.ImplicitLeapfrog`][] for the 3D rod,
    [`jaxrod.ProjectedVerlet`][] for the reduced models; `scheme`, a key of `SCHEMES`, chooses
    another."""
    return _scheme_class(model, scheme)(dt, **kwargs)
