"""Sweep throughput: continuous batching against the single-chunk scheduling it replaces and
against a Python loop of single jitted runs, with the lane utilisation of each, side by side in
one run.

Scenes (reference rod, field model, sine mode-6 perturbation, runs stop when stuck or buckled,
horizon 2 s):

- `map`: the default E3 map of `jaxrod map` / `make demo`: 20 x 24 (dF, v0) points per mu,
  mu = 0.3 and 0, n = 384 nodes (the default for dF up to 64 N).
- `e3`: the E3 member at n = 128 on 256 (dF, v0) points spanning the map (16 x 16).
- `rod3d`: 64 3D rods (30 segments, dead load F0_6 + dF, 8 x 8 (dF, v0) points, horizon
  0.1 s) through the same sweep path.

Lane utilisation = member steps / lane steps: the steps the members needed over the steps the
lanes computed. For the pool, lane steps = rounds x lanes x refill_every per device; for the
single chunk, each device's vmapped loop runs its share of the chunk until the slowest member
of that share stops (whole save intervals of m steps).

    python benchmarks/sweep_throughput.py [--devices 1 2] [--repeats 2] [--quick]

`--devices D` re-runs itself with XLA_FLAGS=--xla_force_host_platform_device_count=D (one XLA
CPU device per core), as `jaxrod map` does. Writes benchmarks/results/sweep_throughput.csv.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time

from _common import write_csv


def _chunk_lane_steps(steps, m: int, devices: int) -> int:
    """Lane steps of the single-chunk scheduling: every device's share runs whole intervals of
    m steps until its slowest member stops."""
    import numpy as np

    total = 0
    for part in np.array_split(np.asarray(steps), devices):
        if len(part):
            total += len(part) * m * math.ceil(int(part.max()) / m)
    return total


def child(scenes: list[str], repeats: int, loop_members: int) -> list[dict]:
    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from jaxrod.integrators.base import save_grid
    from jaxrod.sweeps import N_SAVE, SweepSpec, sweep
    from jaxrod.sweeps.member import _make_member, _static_resolution

    dev = jax.local_device_count()
    rows = []

    def timed(spec, inputs, repeats, **kw):
        t0 = time.perf_counter()
        res = sweep(spec, inputs, progress=False, **kw)  # includes the one compilation
        first = time.perf_counter() - t0
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = sweep(spec, inputs, progress=False, **kw)
            best = min(best, time.perf_counter() - t0)
        return res, best, first - best

    for scene in scenes:
        if scene == "map":
            cases = [(SweepSpec(model="field", mu=mu),
                      {"dF": np.geomspace(0.5, 64, 20), "amplitude": np.geomspace(1e-3, 0.2, 24)})
                     for mu in (0.3, 0.0)]
        elif scene == "e3":
            cases = [(SweepSpec(model="field", n=128, mu=0.3),
                      {"dF": np.geomspace(0.5, 64, 16), "amplitude": np.geomspace(1e-3, 0.2, 16)})]
        else:
            cases = [(SweepSpec(model="rod3d", n=30, mu=0.3, t1=0.1),
                      {"dF": np.geomspace(1.0, 20.0, 8), "amplitude": np.geomspace(2e-3, 0.1, 8)})]
        for spec, inputs in cases:
            labels = {}
            for sched in ("chunk", "pool"):
                # the e3 sweep takes milliseconds: more repeats for a stable minimum
                reps = {"map": repeats, "e3": 5 * repeats, "rod3d": 1}[scene]
                res, t, compile_s = timed(spec, inputs, reps, scheduling=sched)
                m, _ = save_grid(spec.t1, N_SAVE, res.meta["dt"])
                lane_steps = (res.meta["lane_steps"] if sched == "pool"
                              else _chunk_lane_steps(res.outputs["steps"], m, dev))
                labels[sched] = res.outputs["buckled"].copy()
                rows.append(dict(
                    scene=scene, mu=spec.mu, n=res.meta["n"], devices=dev, method=sched,
                    members=len(res), seconds=round(t, 3), compile_s=round(compile_s, 2),
                    members_per_s=round(len(res) / t, 1),
                    utilisation=round(res.meta["member_steps"] / lane_steps, 3),
                    buckled=int(res.outputs["buckled"].sum()),
                ))
            assert (labels["chunk"] == labels["pool"]).all(), "pool and chunk disagree"
            if scene == "e3":
                # Python loop of single jitted runs of the same member function
                flat = {k: np.repeat(v, 16) if k == "dF" else np.tile(v, 16) for k, v in inputs.items()}
                n_, dt, grid_dt, scheme = _static_resolution(spec, flat)
                member = jax.jit(_make_member(spec, n_, dt, grid_dt, scheme))
                key = jax.random.key(0)
                pick = np.linspace(0, len(flat["dF"]) - 1, loop_members).astype(int)
                jax.block_until_ready(member({k: np.float64(v[0]) for k, v in flat.items()}, 0, key))
                t = math.inf
                for _ in range(3):
                    t0 = time.perf_counter()
                    for i in pick:
                        jax.block_until_ready(member({k: np.float64(v[i]) for k, v in flat.items()}, int(i), key))
                    t = min(t, time.perf_counter() - t0)
                rows.append(dict(scene=scene, mu=spec.mu, n=n_, devices=dev,
                                 method="python loop of single jitted runs", members=loop_members,
                                 seconds=round(t, 3), members_per_s=round(loop_members / t, 1)))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--devices", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--scenes", nargs="*", default=["map", "e3", "rod3d"], choices=["map", "e3", "rod3d"])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--loop-members", type=int, default=64)
    ap.add_argument("--quick", action="store_true", help="e3 scene only, 2 devices, 1 repeat")
    ap.add_argument("--out", default="benchmarks/results/sweep_throughput.csv")
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.quick:
        args.devices, args.scenes, args.repeats, args.loop_members = [2], ["e3"], 2, 64
    if args._child:
        print("ROWS " + json.dumps(child(args.scenes, args.repeats, args.loop_members)))
        return
    rows = []
    for d in args.devices:
        env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={d}")
        cmd = [sys.executable, __file__, "--_child", "--repeats", str(args.repeats),
               "--loop-members", str(args.loop_members), "--scenes", *args.scenes]
        out = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if out.returncode != 0:
            sys.exit(out.stderr[-3000:])
        rows += json.loads(out.stdout.split("ROWS ", 1)[1])
    import jax

    print(f"jax {jax.__version__}, {jax.devices()[0].platform}, float64, {os.cpu_count()} cores")
    for r in rows:
        same = [o for o in rows if (o["scene"], o["mu"], o["devices"]) == (r["scene"], r["mu"], r["devices"])]
        chunk = next((o for o in same if o["method"] == "chunk"), None)
        loop = next((o for o in same if o["method"].startswith("python")), None)
        if r["method"] == "pool":
            r["x_chunk"] = round(chunk["seconds"] / r["seconds"], 2)
            if loop is not None:
                r["x_loop"] = round(r["members_per_s"] / loop["members_per_s"], 2)
        if r["method"] == "chunk" and loop is not None:
            r["x_loop"] = round(r["members_per_s"] / loop["members_per_s"], 2)
        print(r)
    write_csv(args.out, rows)


if __name__ == "__main__":
    main()
