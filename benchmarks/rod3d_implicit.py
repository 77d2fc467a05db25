"""The 3D rod's implicit leapfrog against its explicit leapfrog, side by side in one process.

Issue [implicit3d]: the explicit step is set by the axial, shear, twist and wall stiffness
(half the limit 2/ω_max: 7.4e-7 s at 500 segments); `jaxrod.ImplicitLeapfrog` solves with the
rod's block-tridiagonal stiffness each step and runs at `jaxrod.rod3d.IMPLICIT_DT` (5e-5 s).
For n = 60, 120, 240, 500 segments this times, after compilation (min over repeats):

- one rod: wall time per simulated second of E3's run (reference rod, μ = 0.3, dead load
  F⁰₆ + 5 N, sine mode-6 lateral velocity 20 mm/s, no stop) over `--horizon` seconds, and the
  relative difference of the amplitude max|θ| at the end (the same answer?);
- a `jax.vmap` batch of 64 rods (amplitudes 5–40 mm/s) over half that horizon, per rod;
- with `--boundary`, one 3D boundary point (E3, ΔF = 5 N, `boundary_3d`: label bisection from
  the field model's v₀* ± 4 % to rtol 1e-2) at 500 segments with the implicit scheme, wall time
  including compilation;
- with `--search`, `jaxrod.boundary.critical_velocity` of the 3D rod (60 segments, ΔF = 20 N,
  rtol 1e-3, the implicit default) by the departure search (forward-mode tangents through the
  implicit step) and by bisection, wall time including compilation
  (`benchmarks/results/rod3d_implicit_search.csv`).

Rows go to `benchmarks/results/rod3d_implicit.csv` and a table to `.md`.

    python benchmarks/rod3d_implicit.py                  # n = 60, 120, 240, 500 (~10 min)
    python benchmarks/rod3d_implicit.py --n 60 --quick   # a check
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import theory  # noqa: E402
from jaxrod.rod3d import IMPLICIT_DT, Rod3D, sine_velocity, step_limit  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results")


def _timed(f, *args, repeats=2):
    out = jax.block_until_ready(f(*args))
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(f(*args))
        best = min(best, time.perf_counter() - t0)
    return best, out


def _case(n, integrator, horizon, batch):
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + 5.0)
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=False)

    def run(v0):
        q0, u0 = model.initial_state(None, lateral_velocity=sine_velocity(model, v0))
        sol = jr.simulate(model, integrator, q0, u0, horizon, n_save=3, options=opts, throw=False)
        return sol.amplitude[-1], sol.n_steps, sol.result

    if batch:
        return jax.jit(jax.vmap(run)), jnp.linspace(5e-3, 40e-3, batch)
    return jax.jit(run), jnp.asarray(20e-3)


def measure(n, horizon, batch):
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + 5.0)
    rows = []
    for scheme, integrator in (("explicit", jr.ProjectedLeapfrog(0.5 * step_limit(model))),
                               ("implicit", jr.ImplicitLeapfrog(IMPLICIT_DT))):
        t_c = time.perf_counter()
        f, arg = _case(n, integrator, horizon, batch)
        sec, (amp, steps, res) = _timed(f, arg, repeats=1 if batch else 2)
        compile_s = time.perf_counter() - t_c - sec * (2 if batch else 3)
        lanes = batch or 1
        rows.append(dict(n=n, scheme=scheme, batch=lanes, dt=integrator.dt, horizon=horizon,
                         steps=int(jnp.max(steps)), seconds=round(sec, 3),
                         s_per_sim_s=round(sec / horizon / lanes, 3),
                         us_per_step=round(1e6 * sec / int(jnp.max(steps)) / lanes, 1),
                         amplitude=float(jnp.mean(amp)), ok=bool(jnp.all(res == 0)), compile_s=round(max(compile_s, 0.0), 1)))
        print(rows[-1], flush=True)
    rows[1]["speedup"] = round(rows[0]["s_per_sim_s"] / rows[1]["s_per_sim_s"], 1)
    rows[1]["amplitude_rel_diff"] = round(rows[1]["amplitude"] / rows[0]["amplitude"] - 1, 5)
    return rows


def boundary_point(n=500):
    from jaxrod.experiments.e3.rod3d import boundary_3d

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = boundary_3d([5.0], n=n, rtol=1e-2, runs_csv=os.path.join(tmp, "runs.csv"), scheme="implicit",
                          dt=IMPLICIT_DT, progress=True)
        sec = time.perf_counter() - t0
    p = res["points"][0]
    return dict(n=n, scheme="implicit", batch=1, dt=IMPLICIT_DT, horizon=0.4, steps="", seconds=round(sec, 1),
                s_per_sim_s="", us_per_step="", amplitude="", ok=True, compile_s="",
                boundary_mm_s=round(1e3 * p["rod3d"], 3), bracket_mm_s=[round(1e3 * b, 3) for b in p["bracket"]],
                runs=p["runs"])


def search_methods(n=60, dF=20.0):
    rows = []
    rod = jr.RodChannel.reference(0.3)
    for method in ("departure", "bisection"):
        t0 = time.perf_counter()
        r, _ = jr.boundary.critical_velocity(rod, dF, model="rod3d", n=n, method=method, rtol=1e-3, t1=0.4,
                                             sensitivities=())
        rows.append(dict(n=n, dF=dF, method=method, v_star_mm_s=round(1e3 * float(r.root), 4),
                         lo_mm_s=round(1e3 * float(r.lo), 4), hi_mm_s=round(1e3 * float(r.hi), 4),
                         runs=int(r.evaluations), result=int(r.result), seconds=round(time.perf_counter() - t0, 1)))
        print(rows[-1], flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[60, 120, 240, 500])
    ap.add_argument("--horizon", type=float, default=0.02, help="simulated seconds per single run [s]")
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--boundary", action="store_true", help="also one 3D boundary point at 500 segments")
    ap.add_argument("--quick", action="store_true", help="horizon 5 ms, batch 8")
    ap.add_argument("--search", action="store_true", help="only: departure against bisection for the 3D v0*")
    args = ap.parse_args(argv)
    if args.search:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
        rows = [{"commit": commit, **r} for r in search_methods()]
        write_csv(os.path.join(OUT, "rod3d_implicit_search.csv"), rows)
        return
    if args.quick:
        args.horizon, args.batch = 0.005, 8
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rows = []
    for n in args.n:
        rows += measure(n, args.horizon, 0)
        rows += measure(n, args.horizon / 2, args.batch)
    if args.boundary:
        rows.append(boundary_point())
        print(rows[-1], flush=True)
    os.makedirs(OUT, exist_ok=True)
    write_csv(os.path.join(OUT, "rod3d_implicit.csv"), rows)
    head = f"### Implicit against explicit leapfrog ({commit}, {time.strftime('%Y-%m-%d')}, {platform.machine()}, {os.cpu_count()} cores)\n\n"
    lines = [head, "Wall time per simulated second [s] of E3's run (ΔF = 5 N, μ = 0.3, sine 20 mm/s; batch: per rod, "
             "amplitudes 5–40 mm/s), after compilation; the amplitude at the end, implicit against explicit.\n\n",
             "| n | lanes | explicit: dt [s], µs/step, s per sim. s | implicit: dt [s], µs/step, s per sim. s | faster | amplitude, rel. diff. |\n",
             "|---:|---:|---|---|---:|---:|\n"]
    for e, i in zip(rows[0::2], rows[1::2]):
        if e.get("scheme") != "explicit":
            break
        lines.append(f"| {e['n']} | {e['batch']} | {e['dt']:.2e}, {e['us_per_step']}, {e['s_per_sim_s']} | "
                     f"{i['dt']:.0e}, {i['us_per_step']}, {i['s_per_sim_s']} | {i['speedup']}× | {i['amplitude_rel_diff']:+.1e} |\n")
    for r in rows:
        if "boundary_mm_s" in r:
            lines.append(f"\nOne 3D boundary point at {r['n']} segments (ΔF = 5 N, rtol 1e-2, implicit): "
                         f"{r['boundary_mm_s']} mm/s, bracket {r['bracket_mm_s']}, {r['runs']} runs, "
                         f"{r['seconds']} s wall including compilation.\n")
    with open(os.path.join(OUT, "rod3d_implicit.md"), "w") as fh:
        fh.writelines(lines)
    print("".join(lines))


if __name__ == "__main__":
    sys.exit(main())
