"""What a valid 3D rod is: each argument of `Rod3D` against its range, with a one-line error
naming the argument, its value and the valid range (values traced under `jit` or `vmap` are left
to the run's result code)."""

from __future__ import annotations

import numpy as np

from .._numerics import concrete_value as _concrete

__all__ = ["check_arguments"]

CHOICES = {"ends": ("pinned", "fork", "clamped", "free"), "control": ("force", "load", "displacement"),
           "friction_at": ("surface", "axis"), "friction_precision": ("float32", "float64")}
# name: (lower bound, bound included, unit)
RANGES = {"speed": (None, True, "m/s"), "preload": (None, True, "N"), "far_load": (0.0, True, "N"), "contact_damping": (0.0, True, "s/m"), "damping": (0.0, True, "1/s"),
          "contact_stiffness": (0.0, False, "N/m^2.5"), "rotary_scale": (1.0, True, "")}


def check_arguments(model) -> None:
    """Raise `ValueError` for the first argument of `model` (a `Rod3D`) out of its range, or for a
    rod in single precision: the 3D rod's positions and forces need float64 (in float32 the
    rounding of the stiff axial and shear forces, ~1e-7 of EA, is larger than the friction that
    holds a rod in its stable zone: a rod that sticks in float64 can buckle in float32)."""
    dtype = np.dtype(getattr(model.rod.L, "dtype", np.float64))
    if dtype != np.float64:
        raise ValueError(f"Rod3D.rod has dtype {dtype}: the 3D rod needs float64; call "
                         "jax.config.update('jax_enable_x64', True) before building the rod.")
    for name, allowed in CHOICES.items():
        value = getattr(model, name)
        if value not in allowed:
            raise ValueError(f"Rod3D.{name} = {value!r} is invalid: expected one of {allowed}.")
    if model.far_loaded and (model.control != "displacement" or model.ends == "free"):
        raise ValueError(f"Rod3D.far_load is only for control='displacement' with held ends, not control="
                         f"{model.control!r}, ends={model.ends!r}.")
    if not (isinstance(model.friction_sweeps, int) and model.friction_sweeps >= 1):
        raise ValueError(f"Rod3D.friction_sweeps = {model.friction_sweeps!r} is invalid: expected an int >= 1.")
    for name, (lo, closed, unit) in RANGES.items():
        v = _concrete(getattr(model, name))
        if v is None:
            continue
        ok = np.all(np.isfinite(v)) and (lo is None or np.all(v >= lo if closed else v > lo))
        if not ok:
            bound = "" if lo is None else f" and {'>=' if closed else '>'} {lo:g}"
            raise ValueError(f"Rod3D.{name} = {np.asarray(v).tolist()!r}{' ' + unit if unit else ''} is invalid: it must be finite{bound}.")
