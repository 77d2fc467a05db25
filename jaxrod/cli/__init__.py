"""The `jaxrod` command line: one module per command under `jaxrod/cli/`, each adding its own
subparser, checks and function (`register`)."""

from __future__ import annotations

import argparse
import os
import sys

from . import boundary, figure, lockup, map, reproduce, simulate, theory
from ._checks import check_args, check_figure_path
from ._common import _Parser, _check_writable, _fail, _use_all_cpu_cores
from ._distributed import _start_distributed

REGISTER = (theory.register, simulate.register, map.register, boundary.register_boundary,
            boundary.register_critical_load, reproduce.register, lockup.register, figure.register)
"""Each command's module adds its own subparser, its checks (`check`) and its function (`func`)."""

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

    for register in REGISTER:
        register(sub)
    return p


def _resolve_auto_model(args) -> None:
    """`--model auto`: the model and resolution of `jaxrod.model_choice.choose_model` for the
    command's perturbation, its largest load (for critical-load: the bracket top --max-dF) and
    its largest μ; an explicit --n is kept. Says what it chose on stderr."""
    import numpy as np

    from ..model_choice import choose_model

    dF = args.max_dF if hasattr(args, "max_dF") else float(np.max(args.dF))  # critical-load: the bracket top
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
    if getattr(args, "all_cores", False):
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

