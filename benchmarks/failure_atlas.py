"""Failure atlas: where each tempting way of simulating dry friction goes wrong, measured.

One entry per failure, each with the measurement that shows it and the method to use instead:

1. `chatter`   explicit sharp sign (`SymplecticEuler`): velocity sign flips per second where the
               exact solution sticks, and false stable/buckled labels on a phase-plane grid,
               growing with the horizon.
2. `creep`     tanh law (`DiffraxSmooth`, Kvaerno5): a state on the stick line drifts and runs
               away after a time ∝ 1/ε; the critical velocity v₀* against ε and the horizon.
3. `gradient`  tanh law under explicit fixed steps (`ProjectedVerlet(dt, Tanh(ε))`): dA(T)/dȦ₀
               by `jax.grad` against central finite differences and against the exact
               (sharp-law) derivative, as h·f/ε grows.
4. `split`     `SplitLinearFriction` against `ProjectedVerlet`: a stuck state creeping at high
               load (single mode and field model).
5. `steplimit` steps beyond 2/ω_max: the growth of a raw loop of Verlet steps, and the package
               refusing them (`ValueError`, `RESULTS.step_limit` under vmap).
6. `float32`   float32 against float64: stable/buckled labels on a map-like (ΔF, v₀) batch of the
               field model and v₀* (field and single mode).
7. `broadband` the single-mode model outside its validity: a random lateral velocity field;
               the field model's critical load against the single-mode predictions (P7 for the
               projected mode-6 amplitude, and the minimum of P7 over all modes).

Reference rod, μ = 0.3 throughout; ΔF is measured from F⁰₆ = 1.308 N.

    python benchmarks/failure_atlas.py [--quick] [--only chatter,creep,...]

Writes benchmarks/results/atlas_<entry>.csv, atlas_summary.csv and atlas_panels.png (the
`--quick` run writes `atlas_quick_*` instead). Each entry is a module of `benchmarks/atlas/`
(`atlas/<entry>.py`, function `entry_<entry>(quick)`); the figure is `atlas/plot.py`.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import jax

if "--_float32" not in sys.argv:  # the float32 child process runs with x64 off
    jax.config.update("jax_enable_x64", True)
# the entries build arrays at import (the reference rod): only after the dtype is set
from _common import RESULTS as OUT, write_csv  # noqa: E402
from atlas.broadband import entry_broadband  # noqa: E402
from atlas.chatter import entry_chatter  # noqa: E402
from atlas.creep import entry_creep  # noqa: E402
from atlas.float32 import entry_float32, float32_child  # noqa: E402
from atlas.gradient import entry_gradient  # noqa: E402
from atlas.plot import plot  # noqa: E402
from atlas.split import entry_split  # noqa: E402
from atlas.steplimit import entry_steplimit  # noqa: E402

ENTRIES = {"chatter": entry_chatter, "creep": entry_creep, "gradient": entry_gradient, "split": entry_split,
           "steplimit": entry_steplimit, "float32": entry_float32, "broadband": entry_broadband}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", default=",".join(ENTRIES))
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--_float32", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:
        print("CHILD " + json.dumps(float32_child(args.quick)))
        return
    os.makedirs(OUT, exist_ok=True)
    tag = "atlas_quick_" if args.quick else "atlas_"
    d = jax.devices()[0]
    print(f"device {d.platform} ({os.cpu_count()} CPU cores), jax {jax.__version__}, float64 unless stated")
    summaries, outs = [], {}
    t_all = time.perf_counter()
    for name in args.only.split(","):
        t0 = time.perf_counter()
        print(f"\n[{name}]")
        rows, summary, out = ENTRIES[name](args.quick)
        summary["entry"] = name
        summary["seconds"] = round(time.perf_counter() - t0, 1)
        summaries.append(summary)
        outs[name] = out
        write_csv(os.path.join(OUT, f"{tag}{name}.csv"), rows)
        print(f"  -> {summary['number']}  ({summary['seconds']} s)")
    write_csv(os.path.join(OUT, f"{tag}summary.csv"), summaries)
    plot(outs, os.path.join(OUT, f"{tag}panels.png"))
    print("\n| failure | measurement | number | use instead |\n|---|---|---|---|")
    for s in summaries:
        print(f"| {s['failure']} | {s['measurement']} | {s['number']} | {s['use_instead']} |")
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s")


if __name__ == "__main__":
    main()
