"""What every `jaxrod` command shares: the one-line-error parser, argument types, rod options,
the CPU-device setting, CSV rows and the curve plot."""

from __future__ import annotations

import argparse
import math
import sys

# Rod options: (option, RodChannel field, help)
_ROD_OPTIONS = [
    ("--L", "L", "rod length [m]"),
    ("--d", "d", "rod diameter [m]"),
    ("--E", "E", "Young's modulus [Pa]"),
    ("--rho-v", "rho_v", "density [kg/m^3]"),
    ("--nu", "nu", "Poisson's ratio"),
    ("--R", "R", "clearance [m]"),
    ("--g", "g", "gravity [m/s^2]"),
]

_FIELD_TO_OPTION = {field: opt for opt, field, _ in _ROD_OPTIONS}

_FIELD_TO_OPTION.update({"mu_s": "--mu", "mu_d": "--mu"})


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, naming the option, non-zero exit
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        sys.exit(2)


def _fail(message: str) -> None:
    sys.stderr.write(f"jaxrod: error: {message}\n")
    sys.exit(2)


def _finite_float(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid number: {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return x


def _add_rod_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("rod and channel (default: the reference rod)")
    for opt, field, help_ in _ROD_OPTIONS:
        g.add_argument(opt, dest=field, type=_finite_float, default=None, help=help_)


def _rod_from_args(args, mu: float):
    from ..params import RodChannel

    overrides = {f: getattr(args, f) for _, f, _ in _ROD_OPTIONS if getattr(args, f) is not None}
    try:
        return RodChannel.reference(mu=mu, **overrides)
    except ValueError as err:
        msg = str(err)
        for field, opt in _FIELD_TO_OPTION.items():
            if msg.startswith(f"RodChannel.{field} "):
                msg = f"argument {opt}: " + msg
                break
        _fail(msg)


def _json_number(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _check_writable(option: str, path: str, folder: bool = True) -> None:
    """Fail with one line, before any work, if `path` (a folder to create, or a file's folder)
    cannot be written."""
    import os
    import tempfile

    target = path if folder else (os.path.dirname(path) or ".")
    try:
        os.makedirs(target, exist_ok=True)
        with tempfile.TemporaryFile(dir=target):
            pass
    except OSError as err:
        _fail(f"argument {option}: cannot write to {path!r}: {err.strerror or err}.")


def _int_at_least(lo: int):
    """An argparse type: an int ≥ `lo`."""

    def parse(text: str) -> int:
        try:
            x = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid integer: {text!r}") from None
        if x < lo:
            raise argparse.ArgumentTypeError(f"{text!r} must be >= {lo}")
        return x

    return parse


_positive_int = _int_at_least(1)
_nonnegative_int = _int_at_least(0)


def _range_spec(text: str):
    """LO:HI:N -> N log-spaced values from LO to HI (linear if LO <= 0); or a list A,B,C."""
    import numpy as np

    if "," in text or (":" not in text):
        try:
            values = np.array([float(v) for v in text.split(",") if v.strip()])
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not of the form LO:HI:N or A,B,C (numbers)") from None
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise argparse.ArgumentTypeError(f"{text!r}: need finite numbers")
        return values
    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(f"{text!r} is not of the form LO:HI:N")
    try:
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not of the form LO:HI:N (numbers)") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or n < 1 or (n > 1 and hi <= lo):
        raise argparse.ArgumentTypeError(f"{text!r}: need finite LO < HI and N >= 1")
    if n == 1:
        return np.array([lo])
    return np.geomspace(lo, hi, n) if lo > 0 else np.linspace(lo, hi, n)


RTOL_MIN = 1e-13  # 450 ulp of float64: a bracket cannot be resolved much finer


def _rtol(text: str) -> float:
    """A relative tolerance in [1e-13, 0.5) (float64 resolves about 2.2e-16)."""
    x = _finite_float(text)
    if not RTOL_MIN <= x < 0.5:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a relative tolerance in [{RTOL_MIN:g}, 0.5) (float64 resolves about 2.2e-16)")
    return x


def _write_rows(path, rows):
    from ..output import write_csv

    write_csv(path, rows)


def _plot_curve(path, x, y, ok, theory_y, p, se, c, xlabel, ylabel, scale, title):
    import numpy as np

    from ..output import subplots

    fig, ax = subplots(figsize=(6.4, 4.6))
    ax.plot(x[ok], scale * y[ok], "o", label="jaxrod (root search)")
    if theory_y is not None:
        ax.plot(x, scale * np.asarray(theory_y), "k--", label="single-mode theory")
    if math.isfinite(p):
        xs = np.geomspace(x[ok].min(), x[ok].max(), 100)
        ax.plot(xs, scale * c * xs**p, "-", label=f"fit: ∝ x^({p:.3f} ± {se:.3f})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _use_all_cpu_cores() -> None:
    """On a CPU-only machine, expose one XLA device per core so that sweeps shard their batch
    over every core (set before JAX starts its backend; an explicit XLA_FLAGS wins)."""
    import os

    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        n = os.cpu_count() or 1
        os.environ["XLA_FLAGS"] = (flags + f" --xla_force_host_platform_device_count={n}").strip()

