"""Throughput of the field model under projected Verlet: node-steps per second.

Runs `steps` fixed steps of a vmapped batch of rods (reference rod, mu = 0.3, dF = 5 N, sine
mode-6 perturbations) with stopping disabled, so every member takes every step. Compile time is
measured separately; the steady-state figure is the minimum over repeats.

    python benchmarks/field_throughput.py [--dtype float64|float32|both] [--n 128] [--batch 1024]
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import time


def measure(dtype: str, n: int, batch: int, steps: int, repeats: int) -> dict:
    import jax

    jax.config.update("jax_enable_x64", dtype == "float64")
    import jax.numpy as jnp

    import jaxrod as jr

    rod = jr.RodChannel.reference(mu=0.3)
    dt = 0.4 * 2 / float(jr.FieldModel.from_rod(rod, n, dF=0.0).max_frequency())
    opts = jr.RunOptions(buckle_threshold=1e9, stop_when_stuck=False, early_exit=False, save_state=False)

    def one(v0):
        m = jr.FieldModel.from_rod(rod, n, dF=5.0)
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(m)
        sol = jr.simulate(m, jr.ProjectedVerlet(dt), q0, w0, steps * dt, n_save=2, options=opts, throw=False)
        return sol.q_final

    f = jax.jit(jax.vmap(one))
    v0 = jnp.linspace(0.001, 0.05, batch)
    t0 = time.perf_counter()
    jax.block_until_ready(f(v0))
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(f(v0))
        best = min(best, time.perf_counter() - t0)
    rate = n * batch * steps / best
    return dict(
        device=jax.devices()[0].device_kind if jax.devices()[0].platform != "cpu" else "cpu",
        jax=jax.__version__, dtype=dtype, n=n, batch=batch, steps=steps,
        compile_s=round(first - best, 3), run_s=round(best, 4), node_steps_per_s=rate,
        member_steps_per_s=batch * steps / best,
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dtype", default="both", choices=["float64", "float32", "both"])
    ap.add_argument("--n", type=int, nargs="*", default=[128])
    ap.add_argument("--batch", type=int, nargs="*", default=[1024])
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default="benchmarks/results/field_throughput.csv")
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:  # one dtype per process: x64 is a global switch
        rows = [measure(args.dtype, n, b, args.steps, args.repeats) for n in args.n for b in args.batch]
        import json

        print("ROWS " + json.dumps(rows))
        return
    import json

    rows = []
    for dt in (["float64", "float32"] if args.dtype == "both" else [args.dtype]):
        cmd = [sys.executable, __file__, "--_child", "--dtype", dt, "--steps", str(args.steps),
               "--repeats", str(args.repeats), "--n", *map(str, args.n), "--batch", *map(str, args.batch)]
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
        rows += json.loads(out.split("ROWS ", 1)[1])
    print(f"{'device':8s} {'dtype':8s} {'n':>5s} {'batch':>6s} {'compile s':>9s} {'node-steps/s':>13s}")
    for r in rows:
        print(f"{r['device']:8s} {r['dtype']:8s} {r['n']:5d} {r['batch']:6d} {r['compile_s']:9.2f} "
              f"{r['node_steps_per_s']:13.3e}")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
