"""The checks of a command's values that need no computation, run by `main` before anything
else: before JAX starts, before a folder is created. Each failure is one line on stderr naming
the option, and exit code 2 (`_fail`). Checks that need the model (the 3D rod's step limit) stay
in the command."""

from __future__ import annotations

import os

import numpy as np

from ._common import _fail

# The bottom of the critical-load bracket [N] (jaxrod/cli/boundary.py)
MIN_DF_BRACKET = 1e-3


def check_args(args) -> None:
    """Fail on the first invalid value of the parsed `args`: the command's own checks (`check`,
    set by its module's `register`), then those every command shares."""
    check = getattr(args, "check", None)
    if check is not None:
        check(args)
    from ..registry import model_names, recipe

    if getattr(args, "n", None) is not None and getattr(args, "model", None) in model_names():
        cls = recipe(args.model)  # the smallest resolution: the model's own (`min_size`, `size_name`)
        if cls.size_name is None:
            _fail(f"argument --n: the {args.model} model has no size; leave --n out.")
        if args.n < cls.min_size:
            _fail(f"argument --n: {args.n!r} is invalid: the {args.model} model needs >= {cls.min_size} {cls.size_name}.")
    for option in ("out", "plot", "export"):
        if getattr(args, option, None) == "":
            _fail(f"argument --{option}: an empty path is invalid.")


def check_mu(args) -> None:
    """A friction coefficient given as one number must be >= 0."""
    if args.mu is not None and args.mu < 0:
        _fail(f"argument --mu: {args.mu!r} is invalid: a friction coefficient must be >= 0.")


def _check_theory(args) -> None:
    check_mu(args)
    if args.mode is not None and args.mode < 1:
        _fail(f"argument --mode: {args.mode!r} is invalid: a mode number must be >= 1.")


def _check_map(args) -> None:
    check_mu(args)
    if np.any(args.v0 <= 0):
        _fail(f"argument --v0: velocities must be > 0 m/s, got {float(args.v0.min())!r}.")
    if args.t1 is not None:
        _positive("--t1", args.t1, "s")


def _check_boundary(args) -> None:
    check_mu(args)
    if args.t1 is not None:
        _positive("--t1", args.t1, "s")
    if np.any(args.dF <= 0):
        _fail("argument --dF: loads above F0_6 must be > 0 N for a boundary to exist.")


def _check_critical_load(args) -> None:
    if np.any(args.mu <= 0):
        _fail("argument --mu: friction coefficients must be > 0 (no frictional boundary at mu = 0).")
    _positive("--amplitude", args.amplitude, "(m/s, N/m or m)")
    _positive("--t1", args.t1, "s")
    if args.max_dF <= MIN_DF_BRACKET:
        _fail(f"argument --max-dF: {args.max_dF!r} is invalid: the bracket's top must be > its "
              f"bottom, {MIN_DF_BRACKET:g} N.")


def _check_simulate(args) -> None:
    check_mu(args)
    _positive("--t1", args.t1, "s")
    if args.amplitude < 0:
        _fail(f"argument --amplitude: {args.amplitude!r} is invalid: expected >= 0.")
    if args.dt is not None:
        _positive("--dt", args.dt, "s")
    if args.n_save < 2:
        _fail(f"argument --n-save: {args.n_save!r} is invalid: expected >= 2 saved times.")
    if args.model == "rod3d":
        if args.speed is not None and args.speed < 0:
            _fail(f"argument --speed: {args.speed!r} is invalid: expected >= 0 m/s.")
        if args.speed is not None and args.control != "displacement":
            _fail("argument --speed: only with --control displacement (the pushed end's speed).")
    else:
        for option, value in (("--control", args.control), ("--speed", args.speed), ("--export", args.export)):
            if value is not None:
                _fail(f"argument {option}: only with --model rod3d (got --model {args.model}).")


_TUBING_ARGS = {"E": "--E", "outer_diameter": "--od", "inner_diameter": "--id", "density": "--density",
                "weight_per_length": "--weight", "clearance": "--clearance", "length": "--length", "nu": "--nu",
                "mu": "--mu"}


def _check_lockup(args) -> None:
    """Checks the case, or the tubing given by the SI options (`args.tubing`: the arguments of
    `jaxrod.lockup.si.tubing`, or None), each error naming its option."""
    given = {name: getattr(args, name) for name in ("E", "od", "id", "density", "weight", "clearance", "length", "nu")}
    args.tubing = None
    if any(v is not None for v in given.values()):
        if args.mu_L is not None or args.r_over_ell is not None:
            _fail("arguments --mu-L/--r-over-ell and a tubing (--E, --od, ...) describe the case twice: give one.")
        missing = [f"--{k}" for k in ("E", "od", "clearance", "length") if given[k] is None]
        if given["density"] is None and given["weight"] is None:
            missing.append("--density or --weight")
        if missing:
            _fail(f"a tubing in SI units needs {', '.join(missing)} as well.")
        from ..lockup.si import tubing

        args.tubing = dict(E=args.E, outer_diameter=args.od, clearance=args.clearance, length=args.length, mu=args.mu,
                           inner_diameter=args.id or 0.0, density=args.density, weight_per_length=args.weight,
                           nu=0.3 if args.nu is None else args.nu)
        try:
            tubing(**args.tubing)  # the command builds it again once float64 is on
        except ValueError as err:
            name, _, rest = str(err).partition(" = ")
            _fail(f"argument {_TUBING_ARGS.get(name, name)}: {rest}" if name in _TUBING_ARGS else str(err))
    else:
        args.mu_L = 1.0 if args.mu_L is None else args.mu_L
        args.r_over_ell = 0.02 if args.r_over_ell is None else args.r_over_ell
        for option, value in (("--mu-L", args.mu_L), ("--r-over-ell", args.r_over_ell)):
            _positive(option, value, "")
        if args.r_over_ell >= 0.5:
            _fail(f"argument --r-over-ell: {args.r_over_ell!r} is invalid: expected < 0.5 (a slender helix).")
    for option, value, unit in (("--mu", args.mu, ""), ("--speed", args.speed, "m/s"), ("--push", args.push, "m")):
        _positive(option, value, unit)
    if args.far_load is not None and args.far_force is not None:
        _fail("arguments --far-load and --far-force give the far load twice: give one.")
    if args.far_force is not None and args.far_force < 0:
        _fail(f"argument --far-force: {args.far_force!r} is invalid: expected >= 0 N.")
    args.far_load = 2.5 if (args.far_load is None and args.far_force is None) else args.far_load
    if args.far_load is not None and args.far_load < 0:
        _fail(f"argument --far-load: {args.far_load!r} is invalid: expected >= 0 (in units of F0).")
    if args.damping < 0:
        _fail(f"argument --damping: {args.damping!r} is invalid: expected >= 0 1/s.")
    if args.n is not None and args.n < 4:
        _fail(f"argument --n: {args.n!r} is invalid: the 3D rod needs >= 4 segments.")


def _positive(option: str, x: float, unit: str) -> None:
    if not x > 0:
        _fail(f"argument {option}: {x!r} is invalid: expected > 0 {unit}.")


def check_figure_path(option: str, path: str) -> None:
    """A file matplotlib can write: not a folder, and a format it knows (by the extension)."""
    if os.path.isdir(path):
        _fail(f"argument {option}: {path!r} is a folder; give a file name such as {os.path.join(path, 'sim.png')!r}.")
    ext = os.path.splitext(path)[1].lstrip(".").lower()
    if ext:
        from matplotlib.backend_bases import FigureCanvasBase

        known = FigureCanvasBase.get_supported_filetypes()
        if ext not in known:
            _fail(f"argument {option}: {ext!r} is not an image format matplotlib writes "
                  f"(one of {', '.join(sorted(known))}).")
