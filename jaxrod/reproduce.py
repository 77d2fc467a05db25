"""Reproduce the reference paper's experiments: E2–E5 with the reduced models, E1 and the
full-model part of E6 with the 3D rod ([`jaxrod.rod3d`][]), and the post-buckling experiment
(`helix`: the frictionless helix against docs/physics.md §6, a loading–unloading cycle with friction),
and beyond it the lock-up of a rod injected into a long channel (`lockup`, docs/physics.md §8).

`jaxrod reproduce {e1,e2,e3,e4,e5,e6,helix,lockup,all} [--out DIR] [--quick]` writes, per experiment, PNG
figures laid out like a paper's panels and CSV data under `DIR/eN/`, and merges every fitted
number into `DIR/results.json` (with the settings that made it). Critical values come from the
boundary search ([`jaxrod.boundary`][]), not from grids; E3 is a map by definition.
"""

from __future__ import annotations

import json
import os
import time

import numpy as np


__all__ = ["reproduce", "EXPERIMENTS", "PAPER"]

PAPER = ("e1", "e2", "e3", "e4", "e5", "e6", "helix")
"""What `"all"` runs: the paper's experiments and the post-buckling one."""
EXPERIMENTS = PAPER + ("lockup",)


def _runners() -> dict:
    """Each experiment's `run(out, quick, progress) -> dict` (imported on use: E1 and helix
    compile the 3D rod)."""
    from .experiments import e2, e3, e4, e5, e6
    from .experiments.helix import post_buckling
    from .experiments.e1 import e1
    from .experiments.lockup import lockup

    return {"e1": e1, "e2": e2.e2, "e3": e3.e3, "e4": e4.e4, "e5": e5.e5, "e6": e6.e6, "helix": post_buckling,
            "lockup": lockup}


def _runners_3d(n) -> dict:
    """The parts run with the 3D rod (`model="rod3d"`): each experiment's `rod3d` module."""
    from .experiments.e3 import rod3d as e3
    from .experiments.e4 import rod3d as e4
    from .experiments.e5 import rod3d as e5
    from .experiments.e6 import rod3d as e6

    return {name: (lambda out, quick, progress, f=f: f(out, quick, progress, n=n))
            for name, f in (("e3", e3.e3), ("e4", e4.e4), ("e5", e5.e5), ("e6", e6.e6c))}


def reproduce(which, out: str = "results/paper", quick=False, progress: bool = True, model: str = "field",
              n: int | None = None) -> dict:
    """Run the experiments in `which` (names from `EXPERIMENTS`, or `"all"`: those of `PAPER`;
    `lockup`, beyond the paper and hours long in its full setting, only by name), write figures, CSV
    and `results.json` under `out`; returns the dict written. `quick`: `False` (the full run),
    `True` (coarser, fewer realizations: minutes) or `"tiny"` (the test suite's structure check).
    `model="rod3d"`: E3, E4, E5 and E6 (its part C) with the 3D rod of `n` segments (default
    500; [`jaxrod.experiments.paper3d`][], each experiment's `rod3d` module), recorded as `e3_rod3d`, ... in `results.json`."""
    import jax

    which = [which] if isinstance(which, str) else list(which)
    # the experiments each model reproduces: (their names, their runners, the suffix of their entries, "all")
    sets = {"field": (lambda: EXPERIMENTS, _runners, "", True),
            "rod3d": (lambda: tuple(_runners_3d(n)), lambda: _runners_3d(n), "_rod3d", False)}
    if model not in sets:
        raise ValueError(f"model = {model!r} is invalid: expected one of {tuple(sets)}.")
    if n is not None and not (isinstance(n, int) and n >= 4):
        raise ValueError(f"n = {n!r} is invalid: expected an int >= 4 (segments of the 3D rod).")
    allowed_of, runners, suffix, paper = sets[model]  # paper: whether "all" (the paper's) is offered
    allowed = allowed_of()
    names = tuple(dict.fromkeys(x for w in which for x in (PAPER if w == "all" else (w,))))  # "all" and others
    bad = [w for w in names if w not in allowed]
    if bad:
        raise ValueError(f"unknown experiment(s) {bad} for model {model!r}: expected {allowed}"
                         + (" or 'all'." if paper else "."))
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "results.json")
    results = {}
    fns = runners()
    for name in names:
        sub = os.path.join(out, name)
        os.makedirs(sub, exist_ok=True)
        t0 = time.perf_counter()
        if progress:
            print(f"[{name}] running ({'quick' if quick else 'full'}) ...", flush=True)
        r = fns[name](sub, quick, progress)
        r["seconds"] = round(time.perf_counter() - t0, 1)
        r["quick"] = quick
        r["jax"] = jax.__version__
        r["devices"] = jax.local_device_count()
        entry = name + suffix
        results[entry] = r
        # merge into what is on disk now (another run may have written other experiments since)
        on_disk = json.load(open(path)) if os.path.exists(path) else {}
        on_disk[entry] = r
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w") as fh:
            json.dump(on_disk, fh, indent=1, default=_json_default)
        os.replace(tmp, path)
        results = on_disk
        if progress:
            print(f"[{name}] done in {r['seconds']} s", flush=True)
    return results


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)
