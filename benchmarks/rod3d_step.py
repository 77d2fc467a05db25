"""The 3D rod's step: its cost today against an earlier revision of jaxrod, side by side.

Issue [rod3d] asks for a step ≥ 10× cheaper. This script times, in one run, the compiled step of
`jaxrod.rod3d.Rod3D` of the working tree and of a git revision (`--ref`, checked out in a
temporary worktree and run in its own process; the two alternate size by size so that both see
the same machine): the reference rod in the channel, μ = 0.3, dead load F⁰₆ + 5 N, sine mode-6
lateral velocity 20 mm/s (contacts slide, then stick), a fixed number of steps at 0.5 of the
step limit through `jaxrod.simulate` (`experiments.rod3d.run`), min over repeats after
compilation:

- single rod, the default converged friction pass (`friction_tol` 1e-4) and one sweep
  (`friction_sweeps=1`), each tree with its default scheme (since an earlier revision the 3D
  rod's is projected leapfrog, one friction pass per step; earlier trees run projected Verlet,
  two);
- a `jax.vmap` batch of 64 rods (amplitudes 5–40 mm/s; a quarter of the steps), per rod;
- the same 64 rods through the common sweep, `jaxrod.sweep` (`sweep_worker`: each tree's default
  scheduling and lanes, one XLA device per core as `jaxrod map` sets it; members stop when they
  buckle or stick), per rod-step taken (`--no-sweep` skips it).

Both revisions are checked to reach the same amplitude (printed). Rows go to
`benchmarks/results/rod3d_step.csv`.

    python benchmarks/rod3d_step.py --ref a5f4fbf~1 07402aa  # n = 60, 120, 240, 500 (~12 min)
    python benchmarks/rod3d_step.py --ref 07402aa --n 60 120 500 --pairs 4  # paired rounds (~15 min)
    python benchmarks/rod3d_step.py --ref a5f4fbf~1 --quick  # n = 30, 60

`--xla` chooses how XLA compiles the loops of every tree (rows carry it in `xla`):
`shipped` (default: each tree as a user gets it; jaxrod since cc664ba adds
`xla_cpu_small_while_loop_byte_threshold` to `XLA_FLAGS` on import, see `jaxrod/_xla.py`, older
revisions do not), `on` (every tree with that option) and `off` (no tree with it).

    python benchmarks/rod3d_step.py --ref a5f4fbf~1 c32af52 --n 60 500 --pairs 2 --xla shipped on

Each single-rod row also counts the kernels (fusions and unfused ops of the optimised HLO) that
one step's loop body and one friction sweep execute; each batch row, for revisions that report
it (`Rod3DVelocity.sweeps`), the friction sweeps per pass per rod and the batch's largest (the
batched loop sweeps until its slowest rod converges).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)


def hlo_computations(compiled_text: str) -> dict[str, list[str]]:
    """The optimised HLO's computations: name → its instructions (the text right of " = ")."""
    import re

    comps, cur = {}, None
    for line in compiled_text.splitlines():
        m = re.match(r"^(?:ENTRY )?%?([\w.\-]+) .*\{$", line)
        if m and not line.startswith(" "):
            cur = comps[m.group(1)] = []
        elif cur is not None and line.startswith("  ") and " = " in line:
            cur.append(line.split(" = ", 1)[1])
    return comps


def kernels(comps: dict[str, list[str]], computation: str) -> int:
    """The instructions of `computation` (of `hlo_computations`) that execute as kernels: fusions and unfused ops (not
    parameters, constants, tuples, bitcasts)."""
    import re

    skip = {"parameter", "constant", "get-tuple-element", "tuple", "bitcast"}
    ops = [re.search(r"\s([a-z\-]+)\(", " " + ins.split(" ", 1)[1]).group(1)
           for ins in comps[computation]]
    return sum(o not in skip for o in ops)


def loop_kernels(compiled_text: str) -> dict:
    """Kernels one pass of each loop runs, from the optimised HLO: for the step loop and one
    friction sweep, the count of its body's
    instructions that execute (fusions and unfused ops; not parameters, constants, tuples,
    bitcasts). Zero where the compiled step has no friction loop (one sweep). The step loop is the
    loop whose body holds the friction loops and nothing else: one (projected leapfrog) or two
    (projected Verlet)."""
    import re

    comps = hlo_computations(compiled_text)

    # with XLA's loop option a loop is wrapped in a call of its own (`xla_cpu_small_call`):
    # a loop's parent is the loop body that (through such calls) contains it
    def called(pattern):
        """{computation called by an instruction matching `pattern`: the computation holding it}"""
        return {m.group(1): comp for comp in comps for ins in comps[comp] if (m := re.search(pattern, ins))}

    caller = called(r"\scall\(.*to_apply=%?([\w.\-]+)")
    loops = called(r"while\(.*body=%?([\w.\-]+)")
    for b in loops:
        while loops[b] in caller:
            loops[b] = caller[loops[b]]
    inner = {b: [c for c, parent in loops.items() if parent == b] for b in loops}
    out = dict(step_kernels=0, sweep_kernels=0)
    count = lambda b: kernels(comps, b)
    for b in loops:
        # Verlet: two friction loops; leapfrog: one, smaller than the step around it (a one-sweep
        # step is itself a leaf loop, inside the saves' loop, which is smaller than it)
        if all(not inner[c] for c in inner[b]) and (
                len(inner[b]) == 2 or (len(inner[b]) == 1 and count(inner[b][0]) < count(b))):
            out["step_kernels"] = count(b)
            out["sweep_kernels"] = count(inner[b][0])
    if not out["step_kernels"]:  # one sweep: the step is the innermost loop with a friction pass inline
        leaf = [b for b in loops if not inner[b]]
        out["step_kernels"] = max(count(b) for b in leaf)
    return out


def sweep_use(model, F, amplitudes, dt, steps):
    """Friction sweeps per pass in a vmapped batch (the last pass of every step, `v.sweeps`):
    the mean over rods and steps, and the mean over steps of the batch's largest (a batched
    while loop runs until its slowest rod has converged). (0, 0) where the revision does not
    report sweeps."""
    import jax
    import jax.numpy as jnp

    from jaxrod.integrators import ProjectedVerlet
    from jaxrod.rod3d import sine_velocity

    try:  # each tree's default scheme (projected leapfrog for the 3D rod since an earlier revision)
        from jaxrod.integrators import default_for

        integ = default_for(model, float(dt))
    except ImportError:
        integ = ProjectedVerlet(float(dt))

    def one(a):
        q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, a))

        def body(c, t):
            q, v, acc, _ = integ.step(model, *c, t, dt)
            return (q, v, acc), v.sweeps

        ts = dt * jnp.arange(steps)
        return jax.lax.scan(body, (q, v, model.accelerations(q, v, 0.0)), ts)[1]

    if not hasattr(model.initial_state(F)[1], "sweeps"):
        return 0.0, 0.0
    k = jax.jit(jax.vmap(one))(amplitudes)
    return float(jnp.mean(k)), float(jnp.mean(jnp.max(k, axis=0)))


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
    hoisted = "xla_cpu_small_while_loop_byte_threshold" in os.environ.get("XLA_FLAGS", "")
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
            t0 = time.perf_counter()
            compiled = f.lower(arg).compile()  # once: timed, and its kernels counted
            compile_s = time.perf_counter() - t0
            (amp, k), _, best = timed(compiled, arg, repeats=repeats, budget=float("inf"))
            k = int(jnp.max(k))
            counts = loop_kernels(compiled.as_text()) if kind == "single" else {}
            if kind == "batch":
                counts["sweeps_mean"], counts["sweeps_batch_max"] = sweep_use(model, F, arg, dt, k)
            rows.append(dict(**counts, loops_one_function=hoisted, n=n, setting=label, kind=kind, batch=B, steps=k, dt=dt, seconds=best,
                             us_per_rod_step=best / k / B * 1e6, compile_s=compile_s,
                             amplitude=float(jnp.ravel(amp)[0])))
    return rows


def sweep_worker(n: int, steps: int, batch: int, repeats: int) -> list[dict]:
    """`batch` rods through the common sweep (`jaxrod.sweep`, model "rod3d", each tree's default
    scheduling and lanes) on every XLA device of this process: dead load F⁰₆ + 5 N, sine mode-6
    velocity amplitudes 5–40 mm/s, horizon a quarter of `steps` steps of 0.5 of the step limit;
    members stop when they buckle or stick, as in any sweep. Per rod-step = wall time / the steps
    the members took (`meta["member_steps"]`, printed: both trees must agree)."""
    import jax
    import numpy as np

    jax.config.update("jax_enable_x64", True)
    from jaxrod import SweepSpec, sweep, theory
    from jaxrod.params import RodChannel
    from jaxrod.rod3d import Rod3D, step_limit

    rod = RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    model = Rod3D(rod, n, control="load", end_load=F)
    dt = 0.5 * float(step_limit(model, model.initial_state(F)[0]))
    spec = SweepSpec(model="rod3d", n=n, mu=0.3, dF=5.0, t1=max(100, steps // 4) * dt)
    inputs = {"amplitude": np.linspace(5e-3, 40e-3, batch)}
    t0 = time.perf_counter()
    res = sweep(spec, inputs, progress=False)  # compiles
    compile_s = time.perf_counter() - t0
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = sweep(spec, inputs, progress=False)
        best = min(best, time.perf_counter() - t0)
    k = int(res.meta["member_steps"])
    return [dict(n=n, setting="converged", kind="sweep", batch=batch, steps=k, dt=float(res.meta["dt"]), seconds=best,
                 us_per_rod_step=best / k * 1e6, compile_s=compile_s, devices=jax.local_device_count(),
                 lanes=int(res.meta["lanes"]), buckled=int(np.sum(res.outputs["buckled"])),
                 amplitude=float(np.max(res.outputs["max_theta"])))]


def _run(tree: str, n: int, steps: int, batch: int, repeats: int, xla: str = "shipped", kind: str = "worker") -> list[dict]:
    code = (f"import sys, json; sys.path.insert(0, {tree!r}); sys.path.insert(1, {HERE!r}); "
            f"import rod3d_step as b; print(json.dumps(b.{kind}({n}, {steps}, {batch}, {repeats})))")
    from _common import with_devices, xla_env

    env = dict(xla_env(xla), PYTHONPATH=tree)
    if kind == "sweep_worker":  # one XLA device per core, as `jaxrod map` sets it
        env["XLA_FLAGS"] = with_devices(env.get("XLA_FLAGS", ""))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tree, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"the run at {tree} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", nargs="*", default=[], help="git revisions to compare with (default: none)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", type=int, nargs="*", default=[], help="segment counts (default 60 120 240 500)")
    ap.add_argument("--pairs", type=int, default=1,
                    help="rounds: each round runs every size in every tree in turn (A B A B ...); "
                         "speed-ups are the median over rounds of the ratio within a round")
    ap.add_argument("--xla", nargs="*", default=["shipped"], choices=["shipped", "on", "off"],
                    help="how XLA compiles loops, per tree (see the module docstring)")
    ap.add_argument("--sweep", action=argparse.BooleanOptionalAction, default=True,
                    help="also time the batch through jaxrod.sweep on one XLA device per core (kind `sweep`)")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "rod3d_step.csv"))
    args = ap.parse_args()
    sizes = [(30, 1000), (60, 1000)] if args.quick else [(60, 2000), (120, 1500), (240, 1000), (500, 400)]
    if args.n:
        sizes = [(n, max(400, 120000 // n)) for n in args.n]
    batch, repeats = (8, 1) if args.quick else (64, 3)
    trees = [("working tree", ROOT)]
    for ref in args.ref:
        tmp = tempfile.mkdtemp(prefix="jaxrod_ref_")
        subprocess.run(["git", "-C", ROOT, "worktree", "add", "--detach", tmp, ref], check=True,
                       capture_output=True)
        trees.append((ref, tmp))
    rows = []
    try:
        for round_, (n, steps), xla, (name, tree) in ((k, size, x, t) for k in range(args.pairs) for size in sizes
                                                      for x in args.xla for t in trees):
            out = _run(tree, n, steps, batch, repeats, xla)
            if batch > 1 and args.sweep:
                out += _run(tree, n, steps, batch, repeats, xla, kind="sweep_worker")
            for r in out:
                r["revision"], r["round"], r["xla"] = name, round_, xla
                rows.append(r)
                kern = f"   kernels: step {r['step_kernels']}, sweep {r['sweep_kernels']}" if "step_kernels" in r else ""
                if r["kind"] == "sweep":
                    kern = f"   {r['devices']} devices, {r['lanes']} lane(s) each, {r['steps']} member steps, {r['buckled']} buckled"
                if r.get("sweeps_mean"):
                    kern = (f"   sweeps per pass: {r['sweeps_mean']:.2f} per rod, {r['sweeps_batch_max']:.2f} "
                            f"batch max ({r['sweeps_mean'] / r['sweeps_batch_max']:.0%} of lanes busy)")
                print(f"n = {n:4d}  xla {xla:7s} {name:14s} {r['setting']:9s} {r['kind']:6s} x{r['batch']:<3d} "
                      f"{r['us_per_rod_step']:9.1f} us per rod-step   amplitude {r['amplitude']:.9e}{kern}", flush=True)
    finally:
        for _, tree in trees[1:]:
            subprocess.run(["git", "-C", ROOT, "worktree", "remove", "--force", tree], capture_output=True)
    from _common import write_csv

    write_csv(args.out, rows)
    # the working tree under each condition against each tree under each condition, round by round
    for n, _ in sizes:
        for setting, kind in (("converged", "single"), ("1 sweep", "single"), ("converged", "batch"),
                              ("converged", "sweep")):
            sel = {(r["revision"], r["xla"], r["round"]): r["us_per_rod_step"] for r in rows
                   if r["n"] == n and r["setting"] == setting and r["kind"] == kind}
            for mine in args.xla:
                for ref in args.ref:
                    for theirs in args.xla:
                        ratios = [sel[ref, theirs, k] / sel["working tree", mine, k] for k in range(args.pairs)
                                  if (ref, theirs, k) in sel and ("working tree", mine, k) in sel]
                        if ratios:
                            print(f"n = {n:4d}  {setting:9s} {kind:6s}: working tree (xla {mine}) "
                                  f"{statistics.median(ratios):.2f}x faster than {ref} (xla {theirs}) "
                                  f"(rounds: {', '.join(f'{x:.2f}' for x in ratios)})")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
