"""The 3D rod's friction pass: what converging the coupled contact impulses costs per step.

Issue [rod3d] found that a held rod crept because one cold Gauss–Seidel sweep per friction pass
left the coupled impulses unconverged (residual 0.5–0.9 of the bound). Each pass now starts
from the last pass's forces and sweeps until no impulse changes by more than `friction_tol`
of the largest bound (at most `friction_sweeps`). This script times, side by side in one run,
one 3D run per setting at n segments in the channel (reference rod, μ = 0.3, dead load
F⁰₆ + 5 N, sine mode-6 lateral velocity 20 mm/s: contacts slide, then stick), and reports the
time per step, the residual at the saves and the amplitude reached:

- `friction_sweeps = 1`: one warm-started sweep per pass (the old default's work, which had
  no warm start);
- `friction_sweeps = 2, 4` with `friction_tol = 0`: exactly that many sweeps (the cost of a
  sweep, by difference);
- the default (`friction_tol = 1e-4`, up to 64 sweeps) and `friction_tol = 1e-6`.

Mean sweeps per pass of a converged setting ≈ 1 + (its time − one sweep's) / (cost of a sweep).

    python benchmarks/rod3d_friction_pass.py             # n = 60 and 120, about 2 min
    python benchmarks/rod3d_friction_pass.py --quick     # n = 30, shorter
"""

from __future__ import annotations

import argparse
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from _common import RESULTS, write_csv  # noqa: E402
from jaxrod import theory  # noqa: E402
from jaxrod.experiments.rod3d import run  # noqa: E402
from jaxrod.params import RodChannel  # noqa: E402
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit  # noqa: E402

SETTINGS = [("1 sweep", 1, 1e-4), ("2 sweeps", 2, 0.0), ("4 sweeps", 4, 0.0),
            ("converged, tol 1e-4 (default)", 64, 1e-4), ("converged, tol 1e-6", 64, 1e-6)]


def one(n, sweeps, tol, t1, repeats):
    rod = RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    model = Rod3D(rod, n, control="load", end_load=F, friction_sweeps=sweeps, friction_tol=tol)
    q0, v0 = model.initial_state(F, lateral_velocity=sine_velocity(model, 20e-3))
    dt = 0.5 * step_limit(model, q0)
    f = jax.jit(lambda q, v: run(model, q, v, t1, 5, dt, stop_on_buckle=False, stop_when_stuck=False))
    t0 = time.perf_counter()
    sol = jax.block_until_ready(f(q0, v0))
    compile_s = time.perf_counter() - t0
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = jax.block_until_ready(f(q0, v0))
        best = min(best, time.perf_counter() - t0)
    steps = int(sol.n_steps)
    return dict(n=n, friction_sweeps=sweeps, friction_tol=tol, t1=t1, dt=dt, steps=steps,
                seconds=best, us_per_step=best / steps * 1e6, compile_s=compile_s,
                residual_max=float(np.max(np.asarray(sol.observables["friction_residual"]))),
                amplitude_end=float(sol.amplitude[-1]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(RESULTS, "rod3d_friction_pass.csv"))
    args = ap.parse_args()
    ns, t1, repeats = ((30,), 0.02, 2) if args.quick else ((60, 120), 0.05, 3)
    rows = []
    for n in ns:
        for label, sweeps, tol in SETTINGS:
            r = one(n, sweeps, tol, t1, repeats)
            r["setting"] = label
            rows.append(r)
            print(f"n = {n:4d}  {label:32s} {r['us_per_step']:8.1f} us/step  residual {r['residual_max']:.1e}  "
                  f"amplitude {r['amplitude_end']:.6e}", flush=True)
        by = {r["setting"]: r["us_per_step"] for r in rows if r["n"] == n}
        sweep = (by["4 sweeps"] - by["2 sweeps"]) / 2
        for label in ("converged, tol 1e-4 (default)", "converged, tol 1e-6"):
            print(f"n = {n:4d}  {label}: {(by[label] - by['1 sweep']) / sweep + 1:.2f} sweeps per pass on average "
                  f"(a sweep {sweep:.1f} us; {by[label] / by['1 sweep']:.2f}x one sweep's step)")
    write_csv(args.out, rows)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
