"""The 3D rod's step: its cost today against an earlier revision of jaxrod, side by side.

Issue [rod3d] asks for a step ≥ 10× cheaper. This script times, in one run, the compiled step of
`jaxrod.rod3d.Rod3D` of the working tree and of a git revision (`--ref`, checked out in a
temporary worktree and run in its own process; the two alternate size by size so that both see
the same machine): the reference rod in the channel, μ = 0.3, dead load F⁰₆ + 5 N, sine mode-6
lateral velocity 20 mm/s (contacts slide, then stick), a fixed number of steps at 0.5 of the
step limit through `jaxrod.simulate` (`experiments.rod3d.run`), min over repeats after
compilation:

- single rod, the default converged friction pass (`friction_tol` 1e-4) and one sweep
  (`friction_sweeps=1`);
- a `jax.vmap` batch of 64 rods (amplitudes 5–40 mm/s; a quarter of the steps), per rod.

Both revisions are checked to reach the same amplitude (printed). Rows go to
`benchmarks/results/rod3d_step.csv`.

    python benchmarks/rod3d_step.py --ref a5f4fbf~1          # n = 60, 120, 240, 500 (~6 min)
    python benchmarks/rod3d_step.py --ref a5f4fbf~1 --quick  # n = 30, 60
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)


def worker(n: int, steps: int, batch: int, repeats: int) -> list[dict]:
    """Time one size in this process (imports jaxrod from sys.path)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from _common import timed
    from jaxrod import theory
    from jaxrod.experiments.rod3d import run
    from jaxrod.params import RodChannel
    from jaxrod.rod3d import Rod3D, sine_velocity, step_limit

    rod = RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    rows = []
    for label, kw in (("converged", {}), ("1 sweep", dict(friction_sweeps=1))):
        model = Rod3D(rod, n, control="load", end_load=F, **kw)
        q0, _ = model.initial_state(F)
        dt = 0.5 * step_limit(model, q0)

        def one(a, k):
            q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, a))
            sol = run(model, q, v, k * dt, 3, dt, stop_on_buckle=False, stop_when_stuck=False)
            return sol.amplitude[-1], sol.n_steps

        cases = [("single", 1, jax.jit(lambda a: one(a, steps)), jnp.asarray(20e-3))]
        if batch > 1 and label == "converged":  # a quarter of the steps: the batch is 64 runs
            cases.append(("batch", batch, jax.jit(jax.vmap(lambda a: one(a, max(100, steps // 4)))),
                          jnp.linspace(5e-3, 40e-3, batch)))
        for kind, B, f, arg in cases:
            (amp, k), compile_s, best = timed(f, arg, repeats=repeats, budget=float("inf"))
            k = int(jnp.max(k))
            rows.append(dict(n=n, setting=label, kind=kind, batch=B, steps=k, dt=dt, seconds=best,
                             us_per_rod_step=best / k / B * 1e6, compile_s=compile_s,
                             amplitude=float(jnp.ravel(amp)[0])))
    return rows


def _run(tree: str, n: int, steps: int, batch: int, repeats: int) -> list[dict]:
    code = (f"import sys, json; sys.path.insert(0, {tree!r}); sys.path.insert(1, {HERE!r}); "
            f"import rod3d_step as b; print(json.dumps(b.worker({n}, {steps}, {batch}, {repeats})))")
    env = dict(os.environ, PYTHONPATH=tree)
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tree, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"the run at {tree} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default=None, help="git revision to compare with (default: none)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "rod3d_step.csv"))
    args = ap.parse_args()
    sizes = [(30, 1000), (60, 1000)] if args.quick else [(60, 2000), (120, 1500), (240, 1000), (500, 400)]
    batch, repeats = (8, 1) if args.quick else (64, 2)
    trees = [("working tree", ROOT)]
    tmp = None
    if args.ref:
        tmp = tempfile.mkdtemp(prefix="jaxrod_ref_")
        subprocess.run(["git", "-C", ROOT, "worktree", "add", "--detach", tmp, args.ref], check=True,
                       capture_output=True)
        trees.append((args.ref, tmp))
    rows = []
    try:
        for n, steps in sizes:
            for name, tree in trees:
                for r in _run(tree, n, steps, batch, repeats):
                    r["revision"] = name
                    rows.append(r)
                    print(f"n = {n:4d}  {name:14s} {r['setting']:9s} {r['kind']:6s} x{r['batch']:<3d} "
                          f"{r['us_per_rod_step']:9.1f} us per rod-step   amplitude {r['amplitude']:.9e}", flush=True)
    finally:
        if tmp:
            subprocess.run(["git", "-C", ROOT, "worktree", "remove", "--force", tmp], capture_output=True)
    from _common import write_csv

    write_csv(args.out, rows)
    if args.ref:
        for n, _ in sizes:
            for setting, kind in (("converged", "single"), ("1 sweep", "single"), ("converged", "batch")):
                sel = {r["revision"]: r["us_per_rod_step"] for r in rows
                       if r["n"] == n and r["setting"] == setting and r["kind"] == kind}
                if len(sel) == 2:
                    print(f"n = {n:4d}  {setting:9s} {kind:6s}: {sel[args.ref] / sel['working tree']:.2f}x faster than {args.ref}")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
