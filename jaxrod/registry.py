"""Names at the edge: one registry of model and perturbation classes by the names the command
line, JSON settings and file names use. Everything below the edge works with the classes.

    jaxrod.registry.register_model("toy", ToyModel)   # then Scene(kind="toy"), sweeps, CLI
    jaxrod.registry.model_class("field")               # -> jaxrod.FieldModel

A model registers a subclass of [`jaxrod.AbstractModel`][] (it implements the scene group of
the interface), a perturbation a subclass of [`jaxrod.perturbations.AbstractPerturbation`][]
(with `from_settings`). See docs/extending.md.
"""

from __future__ import annotations

import importlib

__all__ = ["register_model", "register_perturbation", "model_class", "perturbation_class", "model_names",
           "perturbation_names", "name_of_model", "make_perturbation"]

# name -> class, or "module:attribute" for a class imported when first asked for
_MODELS: dict[str, object] = {
    "mode": "jaxrod.models.single_mode:SingleMode",
    "galerkin": "jaxrod.models.galerkin:GalerkinModel",
    "field": "jaxrod.models.field:FieldModel",
    "rod3d": "jaxrod.rod3d.model:Rod3D",
}
_PERTURBATIONS: dict[str, object] = {
    "sine": "jaxrod.perturbations:SineVelocity",
    "random-velocity": "jaxrod.perturbations:RandomVelocity",
    "random-position": "jaxrod.perturbations:RandomForce",
    "random-shape": "jaxrod.perturbations:RandomShape",
}


def _register(table: dict, what: str, name: str, cls) -> None:
    if not (isinstance(name, str) and name and not any(c.isspace() for c in name)):
        raise ValueError(f"{what} name = {name!r} is invalid: expected a non-empty string without spaces.")
    if not isinstance(cls, type):
        raise TypeError(f"{what} {name!r}: expected a class, got {cls!r}.")
    table[name] = cls


def register_model(name: str, cls) -> None:
    """Make the model class `cls` (a subclass of [`jaxrod.AbstractModel`][]) available by `name`
    to scenes, sweeps, boundary searches and the command line (replacing one of that name)."""
    from .models.base import AbstractModel

    if isinstance(cls, type) and not issubclass(cls, AbstractModel):
        raise TypeError(f"model {name!r}: {cls.__name__} is not a subclass of jaxrod.AbstractModel.")
    _register(_MODELS, "model", name, cls)


def register_perturbation(name: str, cls) -> None:
    """Make the perturbation class `cls` (with `from_settings`) available by `name`."""
    from .perturbations import AbstractPerturbation

    if isinstance(cls, type) and not issubclass(cls, AbstractPerturbation):
        raise TypeError(f"perturbation {name!r}: {cls.__name__} is not a subclass of AbstractPerturbation.")
    _register(_PERTURBATIONS, "perturbation", name, cls)


def _lookup(table: dict, name: str, argument: str):
    if name not in table:
        raise ValueError(f"{argument} = {name!r} is invalid: expected one of {tuple(table)}.")
    cls = table[name]
    if isinstance(cls, str):
        module, attr = cls.split(":")
        cls = table[name] = getattr(importlib.import_module(module), attr)
    return cls


def model_class(name: str, argument: str = "model"):
    """The model class registered as `name` (`argument`: the name of the setting, for the error)."""
    return _lookup(_MODELS, name, argument)


def perturbation_class(name: str, argument: str = "perturbation"):
    """The perturbation class registered as `name`."""
    return _lookup(_PERTURBATIONS, name, argument)


def model_names() -> tuple[str, ...]:
    """The registered model names, in the order registered."""
    return tuple(_MODELS)


def perturbation_names() -> tuple[str, ...]:
    """The registered perturbation names, in the order registered."""
    return tuple(_PERTURBATIONS)


def name_of_model(cls) -> str:
    """The registered name of the model class `cls`."""
    for name in _MODELS:
        if model_class(name) is cls:
            return name
    raise ValueError(f"model class {cls!r} is not registered.")


def make_perturbation(kind: str, amplitude, mode: int = 6, key=None, duration=1e-3):
    """The perturbation registered as `kind` from plain settings (`from_settings`):

    - `"sine"`: lateral velocity `amplitude`·sin(`mode`·πs/L) [m/s];
    - `"random-velocity"`: uniform in ±`amplitude` [m/s] at every point;
    - `"random-position"`: random forces ±`amplitude` [N/m] for `duration` [s], then released
      from rest (the reference paper's position perturbation);
    - `"random-shape"`: random lateral displacement ±`amplitude` [m], from rest.

    `key` defaults to `jax.random.key(0)`.
    """
    cls = perturbation_class(kind)
    if key is None:
        import jax

        key = jax.random.key(0)
    return cls.from_settings(amplitude, mode, key, duration)
