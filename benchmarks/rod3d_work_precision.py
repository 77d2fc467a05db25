"""Work against precision for the 3D rod: the explicit leapfrog over its range of step and the
implicit leapfrog over its own, on θ(s, t) against a fine reference, at 60, 120 and 500
segments; and where each fails (the explicit scheme just above its limit; the implicit one at
10×, 100× and 1000× the explicit limit).

The run: E3's scene (reference rod, μ = 0.3, dead load F⁰₆ + 5 N, sine mode-6 lateral velocity
20 mm/s: every contact slides, then most stick), `--horizon` seconds, 11 saves of θ at every
node. Reference: the explicit leapfrog at 1/8 of its limit. Error: the largest |θ − θ_ref| over
saves and nodes, relative to the largest |θ_ref|. Wall time: the second call (after
compilation). Rows to `benchmarks/results/rod3d_work_precision.csv`, the figure to
`.png` (and docs/rod3d_work_precision.png).

    python benchmarks/rod3d_work_precision.py             # n = 60, 120, 500 (~6 min)
    python benchmarks/rod3d_work_precision.py --n 60      # one size
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import theory  # noqa: E402
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_work_precision")
EXPLICIT_FRACTIONS = (1.05, 0.9, 0.5, 0.25)
IMPLICIT_STEPS = (1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4)
LIMIT_MULTIPLES = (10, 100, 1000)


def _theta_run(model, integrator, horizon):
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=False)

    @jax.jit
    def run(v0):
        q0, u0 = model.initial_state(None, lateral_velocity=sine_velocity(model, v0))
        sol = jr.simulate(model, integrator, q0, u0, horizon, n_save=11, options=opts, throw=False)
        return sol.observables["theta"], sol.result, sol.n_steps

    run(jnp.asarray(20e-3))
    t0 = time.perf_counter()
    theta, result, steps = jax.block_until_ready(run(jnp.asarray(20e-3)))
    return np.asarray(theta), int(result), int(steps), time.perf_counter() - t0


def measure(n, horizon):
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + 5.0)
    limit = step_limit(model)
    ref, _, _, ref_s = _theta_run(model, jr.ProjectedLeapfrog(limit / 8), horizon)
    scale = float(np.max(np.abs(ref)))
    rows = []
    cases = [("explicit", f * limit, jr.ProjectedLeapfrog(f * limit)) for f in EXPLICIT_FRACTIONS]
    steps = sorted(set(IMPLICIT_STEPS) | {k * limit for k in LIMIT_MULTIPLES})
    cases += [("implicit", h, jr.ImplicitLeapfrog(h)) for h in steps]
    for scheme, h, integrator in cases:
        if scheme == "explicit" and h >= limit:  # simulate refuses it: run the loop unchecked
            integrator = _Unchecked(h)
        theta, result, nsteps, sec = _theta_run(model, integrator, horizon)
        err = float(np.nanmax(np.abs(theta - ref))) / scale if np.all(np.isfinite(theta)) else float("nan")
        rows.append(dict(n=n, scheme=scheme, dt=h, dt_over_limit=round(h / limit, 3), steps=nsteps, seconds=round(sec, 4),
                         error=err, result=result, reference_seconds=round(ref_s, 2)))
        print(rows[-1], flush=True)
    return rows


class _Unchecked(jr.ProjectedLeapfrog):
    """The explicit leapfrog without the step-limit check (to show what happens above it)."""

    def step_limit(self, model):
        return jnp.inf


def figure(rows, path):
    from jaxrod.output import subplots

    ns = sorted({r["n"] for r in rows})
    fig, axes = subplots(1, len(ns), figsize=(4.2 * len(ns), 3.8))
    axes = np.atleast_1d(axes)
    for ax, n in zip(axes, ns):
        for scheme, style in (("explicit", "o-"), ("implicit", "s-")):
            pts = [r for r in rows if r["n"] == n and r["scheme"] == scheme and np.isfinite(r["error"]) and r["result"] == 0]
            ax.loglog([r["seconds"] for r in pts], [max(r["error"], 1e-16) for r in pts], style, label=scheme)
            for r in pts:
                ax.annotate(f"{r['dt']:.0e}", (r["seconds"], max(r["error"], 1e-16)), fontsize=6)
        bad = [r for r in rows if r["n"] == n and not (np.isfinite(r["error"]) and r["result"] == 0)]
        for k, r in enumerate(bad):
            ax.annotate(f"{r['scheme']} at {float(r['dt_over_limit']):g}× the explicit limit: non-finite",
                        (0.02, 0.04 + 0.06 * k), xycoords="axes fraction", fontsize=6, color="C3")
        ax.set_title(f"{int(n)} segments", fontsize=9)
        ax.set_xlabel("wall time [s]")
        ax.xaxis.set_minor_formatter(__import__("matplotlib").ticker.NullFormatter())
        ax.set_ylabel("max |θ − θ_ref| / max |θ_ref|")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[60, 120, 500])
    ap.add_argument("--horizon", type=float, default=0.05)
    ap.add_argument("--plot-only", action="store_true", help="redraw the figure from the CSV")
    args = ap.parse_args(argv)
    if args.plot_only:
        with open(OUT + ".csv", newline="") as fh:
            rows = [{k: (v if k in ("commit", "scheme") else float(v)) for k, v in r.items()} for r in csv.DictReader(fh)]
        figure(rows, OUT + ".png")
        shutil.copy(OUT + ".png", os.path.join(os.path.dirname(HERE), "docs", "rod3d_work_precision.png"))
        return
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rows = []
    for n in args.n:
        rows += [{"commit": commit, **r} for r in measure(n, args.horizon)]
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    write_csv(OUT + ".csv", rows)
    figure(rows, OUT + ".png")
    shutil.copy(OUT + ".png", os.path.join(os.path.dirname(HERE), "docs", "rod3d_work_precision.png"))


if __name__ == "__main__":
    main()
