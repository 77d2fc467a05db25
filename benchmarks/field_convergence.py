"""Convergence of the field model's critical sine velocity in n (nodes) and dt (step).

For the reference rod at mu = 0.3 and dF in {1, 5, 20, 60} N with the sine mode-6 velocity
perturbation, finds the critical v0 (smallest lateral speed that buckles the rod within the
horizon) by vmapped bisection, at successive n and dt, and compares with the single-mode theory
(P6: v_cr = R f / sqrt|k|). Writes benchmarks/results/field_convergence.csv and prints a table.

    python benchmarks/field_convergence.py [--quick]
"""

from __future__ import annotations

import argparse
import csv
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.boundary.roots import bisection  # noqa: E402

DFS = jnp.array([1.0, 5.0, 20.0, 60.0])
T1 = 2.0


def critical_v0(n, dt, dFs, mu=0.3, operator="fd", n_iter=26):
    rod = jr.RodChannel.reference(mu=mu)
    integ = jr.ProjectedVerlet(dt)
    opts = jr.RunOptions(save_state=False)

    def one(dF):
        model = jr.FieldModel.from_rod(rod, n, dF=dF, operator=operator)

        def buckles(v0):
            q0, w0 = jr.SineVelocity(v0, 6).initial_state(model)
            sol = jr.simulate(model, integ, q0, w0, T1, n_save=3, options=opts, throw=False)
            return sol.buckled

        r = bisection(buckles, 1e-4, 1.0, rtol=0.0, max_iter=n_iter)
        return 0.5 * (r.lo + r.hi), r.hi - r.lo

    return jax.jit(jax.vmap(one))(dFs)


def theory_v0(dFs, mu=0.3):
    rod = jr.RodChannel.reference(mu=mu)
    m = jr.theory.critical_mode(rod)
    k = jr.theory.stiffness(rod, m, jr.theory.frictionless_load(rod, m) + dFs)
    return rod.R * jr.theory.velocity_intercept(k, jr.theory.friction_amplitude(rod))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", default=None, help="comma-separated node counts")
    ap.add_argument("--dF", default=None, help="comma-separated loads above F0_6 [N]")
    ap.add_argument("--out", default="benchmarks/results/field_convergence.csv")
    args = ap.parse_args()
    global DFS
    if args.dF:
        DFS = jnp.array([float(x) for x in args.dF.split(",")])
    rows = []
    th = np.asarray(theory_v0(DFS))
    ns = [32, 64, 128] if args.quick else [32, 48, 64, 96, 128, 192, 256, 384]
    if args.n:
        ns = [int(x) for x in args.n.split(",")]
    print(f"device={jax.devices()[0].platform} dtype=float64 T1={T1}s; theory v_cr [mm/s]: "
          + ", ".join(f"{1e3 * x:.3f}" for x in th))
    for n in ns:
        rod = jr.RodChannel.reference()
        limit = 2.0 / float(jr.FieldModel.from_rod(rod, n, dF=-1.0).max_frequency())
        for frac in ([0.8] if n not in (64, 256) else [0.8, 0.4, 0.2, 0.1]):
            dt = frac * limit
            t0 = time.perf_counter()
            v, w = critical_v0(n, dt, DFS)
            v = np.asarray(v)
            el = time.perf_counter() - t0
            for dF, vi, wi, ti in zip(np.asarray(DFS), v, np.asarray(w), th):
                rows.append(dict(n=n, dt=dt, dt_over_limit=frac, dF=dF, v0_crit=vi, bracket=wi,
                                 v0_theory=ti, field_over_theory=vi / ti, seconds=el))
            print(f"n={n:4d} dt={dt:.3e} ({frac:.2f} of limit)  v0* [mm/s] = "
                  + "  ".join(f"{1e3 * x:8.4f}" for x in v) + f"   ({el:.1f}s)")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
