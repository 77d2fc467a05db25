"""The implicit leapfrog's two friction solves side by side in one process: the local pass after
the kick (each contact's own mass, `coupled=False`) and the kick and friction solved together on
the step's operator (`coupled=True`, `jaxrod.rod3d.coupled`), with the explicit leapfrog at half
its limit as the reference, on E3's run (reference rod, μ = 0.3, dead load F⁰₆ + ΔF, sine mode-6
lateral velocity, no stop) for one rod, after compilation (min of two repeats): µs per step, wall
seconds per simulated second, the friction solve's iterations, and the amplitude max|θ| at the
end against the explicit scheme's.

    python benchmarks/rod3d_coupled.py [--n 60 500] [--horizon 0.05] [--dF 5 60]

Rows go to `benchmarks/results/rod3d_coupled.csv` (commit, date, machine in each row). Run it on
a quiet machine: the figures are wall-clock times.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import theory  # noqa: E402
from jaxrod.rod3d import IMPLICIT_DT, Rod3D, sine_velocity, step_limit  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_coupled.csv")


def _run(model, integrator, horizon, v0):
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=False)

    def run(v0):
        q0, u0 = model.initial_state(None, lateral_velocity=sine_velocity(model, v0))
        sol = jr.simulate(model, integrator, q0, u0, horizon, n_save=11, options=opts, throw=False)
        return sol.amplitude[-1], sol.n_steps, sol.result, jnp.mean(sol.observables["friction_sweeps"][1:])

    f = jax.jit(run)
    out = jax.block_until_ready(f(v0))
    best = float("inf")
    for _ in range(2):
        t0 = time.perf_counter()
        out = jax.block_until_ready(f(v0))
        best = min(best, time.perf_counter() - t0)
    return best, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[60, 500])
    ap.add_argument("--dF", type=float, nargs="+", default=[5.0, 60.0])
    ap.add_argument("--horizon", type=float, default=0.05)
    ap.add_argument("--v0", type=float, default=20e-3)
    args = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    stamp = dict(commit=commit, date=datetime.date.today().isoformat(),
                 machine=f"{platform.machine()} {os.cpu_count()} cores")
    rod = jr.RodChannel.reference(0.3)
    rows = []
    for n in args.n:
        for dF in args.dF:
            model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + dF)
            ref = None
            for scheme, integrator in (("explicit", jr.ProjectedLeapfrog(0.5 * float(step_limit(model)))),
                                       ("implicit, local pass", jr.ImplicitLeapfrog(IMPLICIT_DT)),
                                       ("implicit, coupled", jr.ImplicitLeapfrog(IMPLICIT_DT, coupled=True))):
                sec, (amp, steps, result, iters) = _run(model, integrator, args.horizon, jnp.asarray(args.v0))
                amp = float(amp)
                ref = amp if ref is None else ref
                row = dict(n=n, dF=dF, scheme=scheme, dt=float(integrator.dt), steps=int(steps),
                           us_per_step=round(1e6 * sec / max(int(steps), 1), 1),
                           s_per_simulated_s=round(sec / args.horizon, 3), friction_iterations=round(float(iters), 2),
                           amplitude=amp, amplitude_rel_diff=(amp - ref) / ref if ref else float("nan"),
                           result=int(result), horizon=args.horizon, v0=args.v0, **stamp)
                rows.append(row)
                print(row, flush=True)
    write_csv(OUT, rows)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
