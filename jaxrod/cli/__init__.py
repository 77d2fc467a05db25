"""The `jaxrod` command line: one module per command under `jaxrod/cli/`."""

from __future__ import annotations

import argparse
import os
import sys

from ._checks import check_args, check_figure_path
from ._common import _Parser, _check_writable, _fail, _finite_float, _add_rod_options, _positive_int, _range_spec, _rtol, _use_all_cpu_cores
from ._distributed import _add_distributed_options, _start_distributed
from .theory import _cmd_theory
from .simulate import _cmd_simulate
from .map import _cmd_map
from .boundary import _cmd_boundary, _cmd_critical_load
from .figure import _cmd_figure
from .reproduce import _cmd_reproduce
from .lockup import _cmd_lockup

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    from .._version import __version__

    p = _Parser(prog="jaxrod", description="Dynamics and stability of a rod in a channel with dry friction.")
    p.add_argument("--version", action="version", version=f"jaxrod {__version__}")
    cache = p.add_mutually_exclusive_group()
    cache.add_argument("--cache-dir", metavar="DIR", default=None,
                       help="folder of the persistent compilation cache (default: the user's cache folder, "
                            "or $JAXROD_CACHE_DIR; jaxrod/_cache.py)")
    cache.add_argument("--no-cache", action="store_true",
                       help="compile everything anew, reading and writing no compilation cache")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    t = sub.add_parser("theory", help="analytic loads and stable-zone intercepts (docs/physics.md P3-P7)")
    t.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    t.add_argument("--dF", type=_finite_float, default=None, help="load above F0_m [N]")
    t.add_argument("--mode", type=int, default=None, help="mode m (default: the critical mode)")
    t.add_argument("--json", action="store_true", help="print one JSON object")
    _add_rod_options(t)
    t.set_defaults(func=_cmd_theory)

    sm = sub.add_parser("simulate", help="simulate one perturbed rod")
    sm.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="rod3d: the full 3D rod (jaxrod.rod3d); auto: the cheapest adequate model, "
                         "from the measured table (jaxrod.model_choice)")
    sm.add_argument("--control", choices=["force", "load", "displacement"], default=None,
                    help="rod3d only: ends held after pre-compression (force, the default), dead end load (load), "
                         "or one end pushed at --speed from zero load (displacement)")
    sm.add_argument("--speed", type=_finite_float, default=None,
                    help="rod3d displacement control only: pushing speed [m/s] (default 1e-3)")
    sm.add_argument("--dF", type=_finite_float, default=5.0, help="load above F0_m* [N] (default 5)")
    sm.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    sm.add_argument("--perturbation", choices=["sine", "random-velocity", "random-position", "random-shape"],
                    default="sine")
    sm.add_argument("--amplitude", type=_finite_float, default=0.02,
                    help="m/s (sine, random-velocity); N/m force for 1 ms (random-position); "
                         "m (random-shape); default 0.02")
    sm.add_argument("--mode", type=_positive_int, default=6, help="sine / single mode number (default 6)")
    sm.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sm.add_argument("--n", type=_positive_int, default=None, help="nodes (field; default 128, 384 past 32 unstable modes) or modes (galerkin, 32)")
    sm.add_argument("--dt", type=_finite_float, default=None, help="time step [s] (default: 0.4 of the limit)")
    sm.add_argument("--t1", type=_finite_float, default=2.0, help="horizon [s] (default 2)")
    sm.add_argument("--n-save", dest="n_save", type=_positive_int, default=2001, help="saved times (default 2001)")
    sm.add_argument("--json", action="store_true", help="print one JSON object")
    sm.add_argument("--plot", default=None, help="write theta(s,t) and the modal spectrum to this PNG")
    sm.add_argument("--export", default=None, metavar="DIR",
                    help="rod3d: write a ParaView time series (DIR/rod.pvd, one .vtu per save) and DIR/rod.gif")
    sm.add_argument("--quiet", action="store_true", help="no progress bar (rod3d runs)")
    _add_rod_options(sm)
    sm.set_defaults(func=_cmd_simulate)

    mp = sub.add_parser("map", help="E3 stability map over (dF, v0): the main job")
    mp.add_argument("--mu", type=_finite_float, default=None,
                    help="friction coefficient (default: 0.3 and, in the same figure, 0)")
    mp.add_argument("--dF", type=_range_spec, default="0.5:64:20", help="LO:HI:N loads above F0_6 [N] (log-spaced), or a list A,B,C")
    mp.add_argument("--v0", type=_range_spec, default="0.001:0.2:24", help="LO:HI:N sine amplitudes [m/s] (log-spaced), or a list A,B,C")
    mp.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    mp.add_argument("--n", type=_positive_int, default=None, help="nodes / modes (default: by the largest load)")
    mp.add_argument("--t1", type=_finite_float, default=2.0, help="horizon [s] (default 2)")
    mp.add_argument("--out", default="out/map", help="output folder (default: out/map under the working folder)")
    mp.add_argument("--quiet", action="store_true", help="no progress bar")
    mp.add_argument("--no-curve", dest="no_curve", action="store_true",
                    help="do not search the boundary at every load (drawn over the grid, rtol 1e-3)")
    _add_distributed_options(mp)
    mp.set_defaults(func=_cmd_map)

    bd = sub.add_parser("boundary", help="critical sine velocity v0*(dF) by root search")
    bd.add_argument("--mu", type=_finite_float, default=0.3)
    bd.add_argument("--dF", type=_range_spec, default="1:60:6", help="LO:HI:N loads above F0_6 [N], or a list A,B,C")
    bd.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    bd.add_argument("--n", type=_positive_int, default=None)
    bd.add_argument("--rtol", type=_rtol, default=1e-6, help="relative tolerance in (0, 0.5) (default 1e-6)")
    bd.add_argument("--out", default=None, help="folder for boundary.csv and boundary.png")
    bd.add_argument("--method", choices=["departure", "bisection"], default=None,
                    help="rod models: departure-rate secant (default) or label bisection (default for rod3d)")
    bd.add_argument("--json", action="store_true")
    bd.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_rod_options(bd)
    bd.set_defaults(func=_cmd_boundary)

    cl = sub.add_parser("critical-load", help="critical load dF*(mu) by root search")
    cl.add_argument("--mu", type=_range_spec, default="0.05:1:6", help="LO:HI:N friction coefficients, or a list A,B,C")
    cl.add_argument("--perturbation", choices=["sine", "random-velocity", "random-position", "random-shape"],
                    default="sine")
    cl.add_argument("--amplitude", type=_finite_float, default=0.015,
                    help="m/s for velocities, N/m for random-position, m for random-shape")
    cl.add_argument("--realizations", type=_positive_int, default=1)
    cl.add_argument("--seed", type=int, default=0)
    cl.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    cl.add_argument("--n", type=_positive_int, default=None)
    cl.add_argument("--max-dF", dest="max_dF", type=_finite_float, default=100.0, help="bracket top [N]")
    cl.add_argument("--rtol", type=_rtol, default=1e-6, help="relative tolerance in (0, 0.5) (default 1e-6)")
    cl.add_argument("--out", default=None)
    cl.add_argument("--method", choices=["departure", "bisection"], default=None,
                    help="rod models: departure-rate secant (default) or label bisection (default for rod3d)")
    cl.add_argument("--json", action="store_true")
    cl.set_defaults(func=_cmd_critical_load)

    rp = sub.add_parser("reproduce", help="reproduce the paper's experiments E1-E6 (E1 and E6's full-model part with the 3D rod) "
                        "and the post-buckling helix/hysteresis experiment ('all'); lock-up by name")
    rp.add_argument("which", nargs="+", choices=["e1", "e2", "e3", "e4", "e5", "e6", "helix", "lockup", "all"])
    rp.add_argument("--out", default="out/paper", help="output folder (default: out/paper under the working folder; "
                    "the committed reproduction is results/paper)")
    rp.add_argument("--quick", action="store_true", help="coarser, fewer realizations: a few minutes")
    rp.add_argument("--model", choices=["field", "rod3d"], default="field",
                    help="rod3d: E3, E4, E5 and E6C with the 3D rod "
                         "(jaxrod.experiments.paper3d; hours at 500 segments)")
    rp.add_argument("--n", type=_positive_int, default=None, help="segments of the 3D rod (default 500; 60 with --quick)")
    rp.add_argument("--quiet", action="store_true")
    rp.set_defaults(func=_cmd_reproduce)

    lk = sub.add_parser("lockup", help="one rod injected into a long channel against a far-end load (the 3D rod; "
                        "docs/physics.md section 8)")
    lk.add_argument("--mu-L", dest="mu_L", type=_finite_float, default=1.0, help="muL/ell (default 1)")
    lk.add_argument("--r-over-ell", type=_finite_float, default=0.02, help="clearance r/ell (default 0.02)")
    lk.add_argument("--mu", type=_finite_float, default=0.5, help="friction coefficient (default 0.5)")
    lk.add_argument("--far-load", type=_finite_float, default=2.5, help="far-end load in units of F0 (default 2.5)")
    lk.add_argument("--speed", type=_finite_float, default=5e-3, help="injection speed [m/s] (default 5e-3)")
    lk.add_argument("--push", type=_finite_float, default=0.3, help="how far the entry is pushed [m] (default 0.3)")
    lk.add_argument("--damping", type=_finite_float, default=20.0,
                    help="mass-proportional damping [1/s] that takes out the start's axial wave (default 20)")
    lk.add_argument("--unload", action="store_true", help="then pull the entry back as far")
    lk.add_argument("--n", type=_positive_int, default=None, help="segments (default: 16 per buckle wavelength)")
    lk.add_argument("--scheme", choices=["implicit", "leapfrog"], default="implicit",
                    help="time stepping: the implicit leapfrog at its own step (default) or the explicit one "
                         "at 0.3 of its limit")
    lk.add_argument("--n-save", type=_positive_int, default=201, help="saves per phase (default 201)")
    lk.add_argument("--out", default="out/lockup", help="output folder (default: out/lockup under the working folder)")
    lk.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    lk.add_argument("--quiet", action="store_true")
    lk.set_defaults(func=_cmd_lockup)

    fg = sub.add_parser("figure", help="write a figure")
    fg.add_argument("which", choices=["phase"], help="phase: E2 phase portraits")
    fg.add_argument("--out", default="out/figures", help="output folder (default: out/figures under the working folder)")
    fg.set_defaults(func=_cmd_figure)
    return p


def _resolve_auto_model(args) -> None:
    """`--model auto`: the model and resolution of `jaxrod.model_choice.choose_model` for the
    command's perturbation, its largest load (for critical-load: the bracket top --max-dF) and
    its largest μ; an explicit --n is kept. Says what it chose on stderr."""
    import numpy as np

    from ..model_choice import choose_model

    dF = args.max_dF if args.command == "critical-load" else float(np.max(args.dF))
    mu = 0.3 if args.mu is None else float(np.max(args.mu))  # map: μ = 0.3 (and 0) by default
    try:
        model, n = choose_model(getattr(args, "perturbation", "sine"), dF, mu)
    except ValueError as err:
        _fail(str(err))
    args.model = model
    args.n = n if args.n is None else args.n
    sys.stderr.write(f"jaxrod: --model auto chose the {model} model"
                     + (f" with n = {args.n}" if args.n is not None else "") + "\n")


def _set_cache(args) -> None:
    """`--no-cache` and `--cache-dir` (jaxrod/_cache.py)."""
    from .. import _cache

    if args.no_cache:
        _cache.use(None)
    elif args.cache_dir is not None:
        _check_writable("--cache-dir", args.cache_dir)
        _cache.use(os.path.abspath(os.path.expanduser(args.cache_dir)))


def main(argv: list[str] | None = None) -> int:
    """Run one command. Every error a user can cause ends in one line on stderr naming the
    option and exit code 2; values that need no computation are checked before any work."""
    args = build_parser().parse_args(argv)
    check_args(args)
    _set_cache(args)
    if hasattr(args, "distributed"):  # first: jax.distributed starts before any JAX computation
        _start_distributed(args)
    if getattr(args, "model", None) == "auto":
        _resolve_auto_model(args)
    if args.command in ("map", "boundary", "critical-load", "reproduce"):
        _use_all_cpu_cores()
    if getattr(args, "plot", None):
        check_figure_path("--plot", args.plot)
        _check_writable("--plot", args.plot, folder=False)
    for option in ("out", "export"):
        if getattr(args, option, None):
            _check_writable(f"--{option}", getattr(args, option))
    try:
        return args.func(args)
    except OSError as err:  # a file system error mid-run: one line, never a traceback
        _fail(f"cannot write {err.filename or 'the output'}: {err.strerror or err}.")

