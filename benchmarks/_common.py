"""Helpers shared by the benchmark scripts (not a benchmark itself: `make bench` skips `_*.py`).

The scripts are run as `python benchmarks/NAME.py`, so this directory is on `sys.path` and
`from _common import ...` works. Nothing here touches the x64 switch: each script sets it
before it imports jaxrod.
"""

from __future__ import annotations

import csv
import math
import os
import subprocess
import time

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")


# XLA's loop option as jaxrod sets it (jaxrod/_xla.py OPTION); written out here so that a run
# of an older revision, which has no jaxrod._xla, can be given it too
XLA_LOOP_OPTION = "--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold=100000000"


def with_devices(flags: str, devices: int | None = None) -> str:
    """`flags` (an `XLA_FLAGS` value) with `devices` XLA CPU devices (default one per core, as
    `jaxrod map` sets it), unless `flags` already sets a device count (its choice is kept)."""
    if "xla_force_host_platform_device_count" in flags:
        return flags
    return f"{flags} --xla_force_host_platform_device_count={devices or os.cpu_count() or 1}".strip()


def worker_in_process(script: str, name: str, env: dict, label: str) -> dict:
    """`worker(name)` of the benchmark `script` (its module name) run in a fresh Python process
    with the environment `env`: the dict it returns (printed as JSON). `label` names the run in
    the error that a failed process raises."""
    import json
    import subprocess
    import sys

    here = os.path.dirname(os.path.abspath(__file__))
    code = f"import sys, json; sys.path.insert(0, {here!r}); import {script} as b; print(json.dumps(b.worker({name!r})))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"{name} ({label}) failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def xla_env(condition: str) -> dict:
    """The environment of a benchmark's worker process under XLA's loop option: `shipped` (as
    jaxrod sets it on import; older revisions do not), `on` (set explicitly) or `off`
    (`JAXROD_XLA_DEFAULTS=0`). The parent's own `XLA_FLAGS` is not passed on, and jaxrod's
    compilation cache is off (`JAXROD_CACHE_DIR=off`): each process compiles every program, none
    read back from an earlier round's process."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAXROD_XLA_DEFAULTS")}
    env["JAXROD_CACHE_DIR"] = "off"
    if condition == "on":
        env["XLA_FLAGS"] = XLA_LOOP_OPTION
    elif condition == "off":
        env["JAXROD_XLA_DEFAULTS"] = "0"
    return env


def write_csv(path, rows, verbose=False):
    """One header line (every key of every row, in the order first seen), then one line per
    row (csv.DictWriter: missing keys left empty). Creates the folder; prints the path if
    `verbose`."""
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    if verbose:
        print(f"wrote {path}")


def load_rows(path):
    """Rows of a CSV written by `write_csv`, with numbers and booleans restored (empty cells
    dropped)."""
    def conv(v):
        if v in ("True", "False"):
            return v == "True"
        try:
            return float(v)
        except ValueError:
            return v

    with open(path) as fh:
        return [{k: conv(v) for k, v in r.items() if v != ""} for r in csv.DictReader(fh)]


def best_of(fn, repeats):
    """Minimum wall time [s] of `repeats` calls of `fn()` (no warm-up call)."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def time_jax(fn, args, repeats):
    """(min over `repeats` calls of `jax.block_until_ready(fn(*args))` [s], compile time [s]):
    the first call is timed separately and its excess over the best run counts as compile."""
    import jax

    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    best = best_of(lambda: jax.block_until_ready(fn(*args)), repeats)
    return best, max(first - best, 0.0)


def timed(fn, *args, repeats=3, budget=4.0):
    """(output, first call [s], min over up to `repeats` later calls [s]); the repeats stop once
    they have used `budget` seconds (at least one is made when `repeats` ≥ 1)."""
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    best, spent = math.inf, 0.0
    for i in range(repeats):
        if i and spent > budget:
            break
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn(*args))
        dt = time.perf_counter() - t0
        best, spent = min(best, dt), spent + dt
    return out, first, (best if repeats else first)


def commit(root: str = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))) -> str:
    """The short commit of the tree at `root` (this repository by default), with `+changes`
    where a tracked file differs from it."""
    out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root, capture_output=True,
                           text=True).stdout.strip()
    return out.stdout.strip() + ("+changes" if dirty else "")


def jaxrod_command(argv, cache: str, root: str = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))):
    """`jaxrod ARGV` in a fresh process (`python -m jaxrod`, from `root`) with the compilation cache
    folder `cache`: (wall seconds, stdout); a failed command stops the benchmark with its error."""
    import sys

    env = dict(os.environ, JAXROD_CACHE_DIR=cache)
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "jaxrod", *argv], capture_output=True, text=True, env=env, cwd=root)
    seconds = time.perf_counter() - t
    if out.returncode:
        raise SystemExit(f"jaxrod {' '.join(argv)} failed:\n{out.stderr[-2000:]}")
    return seconds, out.stdout


def device_info(dtype="float64") -> dict:
    """The device, JAX version and dtype a result was measured with (as CSV columns)."""
    import jax

    d = jax.devices()[0]
    kind = d.device_kind if d.platform != "cpu" else f"cpu ({os.cpu_count()} cores)"
    return dict(device=kind, jax=jax.__version__, dtype=dtype)


def run_or_replot(description: str, run, replot, replot_help: str = "redraw the figure from the CSV") -> None:
    """The command line of a work–precision script: `--quick` (about a minute: fewer
    configurations) and `--replot` (`replot(quick)` only); otherwise `run(quick, device_info())`,
    timed."""
    import argparse

    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--quick", action="store_true", help="about a minute: fewer configurations")
    ap.add_argument("--replot", action="store_true", help=replot_help)
    args = ap.parse_args()
    os.makedirs(RESULTS, exist_ok=True)
    if args.replot:
        replot(args.quick)
        return
    t0 = time.perf_counter()
    run(args.quick, device_info())
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")
