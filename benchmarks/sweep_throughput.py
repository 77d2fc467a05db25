"""Sweep throughput: members/s against chunk size, the sharded sweep against a Python loop of
single jitted runs of the same member (ratio measured in the same run), and memory per member.

Scene: the E3 stability-map member — reference rod, field model, mu = 0.3, sine mode-6
perturbation, runs stop when stuck or buckled (horizon 2 s). A fixed set of 256 (dF, v0) points
spanning the map is used for every configuration.

    python benchmarks/sweep_throughput.py [--n 128] [--devices 2]

`--devices D` re-runs itself with XLA_FLAGS=--xla_force_host_platform_device_count=D (one XLA
CPU device per core), as `jaxrod map` does.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time


def child(n: int, chunks: list[int], loop_members: int) -> list[dict]:
    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from jaxrod.sweeps import SweepSpec, _make_member, _static_resolution, sweep

    spec = SweepSpec(model="field", n=n, mu=0.3)
    dF = np.geomspace(0.5, 64, 16)
    v0 = np.geomspace(1e-3, 0.2, 16)
    inputs = {"dF": dF, "amplitude": v0}
    rows = []
    dev = jax.local_device_count()
    for cs in chunks:
        t0 = time.perf_counter()
        sweep(spec, inputs, chunk_size=cs, progress=False)  # includes the one compilation
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        sweep(spec, inputs, chunk_size=cs, progress=False)
        t = time.perf_counter() - t0
        rows.append(dict(method="sweep", devices=dev, n=n, chunk=cs, members=256,
                         seconds=round(t, 3), compile_s=round(first - t, 3), members_per_s=256 / t))
    # Python loop over single jitted runs of the same member function
    flat = {"dF": np.repeat(dF, 16), "amplitude": np.tile(v0, 16)}
    n_, dt, grid_dt = _static_resolution(spec, flat)
    member = jax.jit(_make_member(spec, n_, dt, grid_dt))
    key = jax.random.key(0)
    pick = np.linspace(0, 255, loop_members).astype(int)
    p0 = {k: np.float64(v[0]) for k, v in flat.items()}
    jax.block_until_ready(member(p0, 0, key))  # compile
    t0 = time.perf_counter()
    for i in pick:
        jax.block_until_ready(member({k: np.float64(v[i]) for k, v in flat.items()}, int(i), key))
    t = time.perf_counter() - t0
    rows.append(dict(method="python loop of jitted single runs", devices=dev, n=n, chunk=1,
                     members=loop_members, seconds=round(t, 3), compile_s=None, members_per_s=loop_members / t))
    # memory per member from XLA's buffer assignment of a 256-member chunk
    run = jax.jit(jax.vmap(_make_member(spec, n_, dt, grid_dt), in_axes=(0, 0, None)))
    args = ({k: np.asarray(v) for k, v in flat.items()}, np.arange(256), jax.random.key(0))
    mem = run.lower(*args).compile().memory_analysis()
    if mem is not None:
        per = (mem.temp_size_in_bytes + mem.argument_size_in_bytes + mem.output_size_in_bytes) / 256
        rows.append(dict(method="memory per member (XLA buffers, chunk 256)", devices=dev, n=n, chunk=256,
                         members=256, seconds=None, compile_s=None, members_per_s=None, bytes_per_member=per))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=128)
    ap.add_argument("--devices", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--chunks", type=int, nargs="*", default=[16, 64, 256])
    ap.add_argument("--loop-members", type=int, default=32)
    ap.add_argument("--out", default="benchmarks/results/sweep_throughput.csv")
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:
        print("ROWS " + json.dumps(child(args.n, args.chunks, args.loop_members)))
        return
    rows = []
    for d in args.devices:
        env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={d}")
        cmd = [sys.executable, __file__, "--_child", "--n", str(args.n), "--loop-members",
               str(args.loop_members), "--chunks", *map(str, args.chunks)]
        out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True).stdout
        rows += json.loads(out.split("ROWS ", 1)[1])
    loop = {r["devices"]: r["members_per_s"] for r in rows if r["method"].startswith("python")}
    for r in rows:
        if r["method"] == "sweep":
            r["ratio_vs_loop"] = r["members_per_s"] / loop[r["devices"]]
    keys = sorted({k for r in rows for k in r}, key=lambda k: list(rows[0]).index(k) if k in rows[0] else 99)
    for r in rows:
        print({k: (round(v, 2) if isinstance(v, float) else v) for k, v in r.items()})
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
