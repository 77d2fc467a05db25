"""Names at the edge: one registry of model recipes and perturbation classes by the names the
command line, JSON settings and file names use. Everything below the edge works with the objects.

    jaxrod.registry.register_model("toy", ToyRecipe())  # then Scene(kind="toy"), sweeps, CLI
    jaxrod.registry.recipe("field")                      # -> jaxrod.models.field.FieldRecipe()
    jaxrod.registry.model_class("field")                 # -> jaxrod.FieldModel

A model registers its recipe (a [`jaxrod.models.recipe.AbstractRecipe`][], whose `model_class`
is a subclass of [`jaxrod.AbstractModel`][]), a perturbation a subclass of
[`jaxrod.perturbations.AbstractPerturbation`][] (with `from_settings`). See docs/extending.md.
"""

from __future__ import annotations

import importlib

__all__ = ["register_model", "register_perturbation", "recipe", "model_class", "perturbation_class", "model_names",
           "perturbation_names", "name_of", "name_of_model", "make_perturbation"]

# name -> recipe (models) or class (perturbations), or "module:attribute" for a class imported
# when first asked for (a recipe class is made into its instance)
_MODELS: dict[str, object] = {
    "mode": "jaxrod.models.single_mode:SingleModeRecipe",
    "galerkin": "jaxrod.models.galerkin:GalerkinRecipe",
    "field": "jaxrod.models.field:FieldRecipe",
    "rod3d": "jaxrod.rod3d.recipe:Rod3DRecipe",
}
_PERTURBATIONS: dict[str, object] = {
    "sine": "jaxrod.perturbations:SineVelocity",
    "random-velocity": "jaxrod.perturbations:RandomVelocity",
    "random-position": "jaxrod.perturbations:RandomForce",
    "random-shape": "jaxrod.perturbations:RandomShape",
}


def _check_name(what: str, name: str) -> None:
    if not (isinstance(name, str) and name and not any(c.isspace() for c in name)):
        raise ValueError(f"{what} name = {name!r} is invalid: expected a non-empty string without spaces.")


def register_model(name: str, recipe) -> None:
    """Make the model of `recipe` (an instance of a [`jaxrod.models.recipe.AbstractRecipe`][]
    subclass, whose `model_class` is a subclass of [`jaxrod.AbstractModel`][]) available by
    `name` to scenes, sweeps, boundary searches and the command line (replacing one of that name)."""
    from .models.base import AbstractModel
    from .models.recipe import AbstractRecipe

    _check_name("model", name)
    if isinstance(recipe, type) and issubclass(recipe, AbstractModel):
        raise TypeError(f"model {name!r}: {recipe.__name__} is a model class; register its recipe, an "
                        "AbstractRecipe instance (docs/extending.md).")
    if not isinstance(recipe, AbstractRecipe):
        raise TypeError(f"model {name!r}: expected an AbstractRecipe instance (the model's recipe), got {recipe!r}.")
    cls = recipe.model_class
    if not (isinstance(cls, type) and issubclass(cls, AbstractModel)):
        raise TypeError(f"model {name!r}: {type(recipe).__name__}.model_class = {getattr(cls, '__name__', cls)} is "
                        "not a subclass of jaxrod.AbstractModel.")
    _MODELS[name] = recipe


def register_perturbation(name: str, cls) -> None:
    """Make the perturbation class `cls` (with `from_settings`) available by `name`."""
    from .perturbations import AbstractPerturbation

    _check_name("perturbation", name)
    if not isinstance(cls, type):
        raise TypeError(f"perturbation {name!r}: expected a class, got {cls!r}.")
    if not issubclass(cls, AbstractPerturbation):
        raise TypeError(f"perturbation {name!r}: {cls.__name__} is not a subclass of AbstractPerturbation.")
    _PERTURBATIONS[name] = cls


def _lookup(table: dict, name: str, argument: str, instance: bool = False):
    if name not in table:
        raise ValueError(f"{argument} = {name!r} is invalid: expected one of {tuple(table)}.")
    obj = table[name]
    if isinstance(obj, str):
        module, attr = obj.split(":")
        obj = getattr(importlib.import_module(module), attr)
        table[name] = obj = obj() if instance else obj
    return obj


def recipe(model, argument: str = "model"):
    """The recipe of `model`: `model` itself where it is a recipe (an `AbstractRecipe` instance,
    registered or not: the library takes objects), else the recipe registered under the name
    `model` (`argument`: the name of the setting, for the error)."""
    from .models.recipe import AbstractRecipe

    if isinstance(model, AbstractRecipe):
        return model
    return _lookup(_MODELS, model, argument, instance=True)


def model_class(model, argument: str = "model"):
    """The model class of `model` (a recipe or a registered name): its recipe's `model_class`."""
    return recipe(model, argument).model_class


def name_of(model) -> str:
    """The name of `model` (a recipe or a registered name) in messages and stored settings: the
    name it is registered under, else its recipe's class name."""
    if isinstance(model, str):
        return model
    for name, obj in _MODELS.items():
        if obj is model or (not isinstance(obj, str) and obj == model):
            return name
    return type(model).__name__


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
