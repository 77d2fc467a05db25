"""Distributed sweeps: members/s on 1 and 2 processes of one CPU device each (`jax.distributed`,
coordinator on 127.0.0.1), and what the coordination costs per chunk, side by side in one run.

Scenes (reference rod, μ = 0.3, sine mode-6 perturbation, horizon 2 s, chunks of 64 members,
the chunk the unit of work dealt to the processes):

- `map`: the field model at 384 nodes (the default map's resolution) over a 32 x 32 (dF, v0)
  grid spanning the default map (1024 members, 16 chunks); `--quick`: 128 nodes, 16 x 16.
- `bookkeeping`: 64 chunks (`--quick`: 16) of single-mode members with a 10 ms horizon: the
  members cost next to nothing, so a chunk's time is its bookkeeping (host transfers, the
  atomic chunk file) and, on two processes, the coordination.

Per process count P: `seconds` (min over repeats of one sweep into a fresh folder, compilation
excluded: each process first runs one chunk of the same width), members/s, speedup over one
process; `collective_s`, the time process 0 spent in the sweep's collectives (two broadcasts at
the start, one gather at the end: it includes waiting for the slower process); `rerun_s`, a
rerun over the finished folder (nothing left to run: reading the chunks and the collectives),
the fixed cost of a call; and `overhead_per_chunk_s` = (P · seconds_P − seconds_1) / chunks,
the process-seconds two processes spend beyond one, per chunk (0 for perfect scaling; on `map`
it also counts the imbalance between the processes).

    python benchmarks/distributed_throughput.py [--repeats 3] [--quick]

Each process gets XLA_FLAGS=--xla_force_host_platform_device_count=1; run it on a quiet machine
with at least 2 cores. Writes benchmarks/results/distributed_throughput.csv (`--quick`:
distributed_throughput_quick.csv).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import subprocess
import sys
import tempfile
import time

from _common import RESULTS, device_info, write_csv

CHUNK = 64


def scenes(quick: bool):
    import numpy as np

    from jaxrod.sweeps import SweepSpec

    k = 16 if quick else 32
    grid = {"dF": np.geomspace(0.5, 64, k), "amplitude": np.geomspace(1e-3, 0.2, k)}
    chunks = 16 if quick else 64
    return {
        "map": (SweepSpec(model="field", n=128 if quick else 384, mu=0.3), grid),
        "bookkeeping": (SweepSpec(model="mode", mu=0.3, t1=0.01),
                        {"dF": [5.0], "amplitude": [0.01], "realization": np.arange(chunks * CHUNK)}),
    }


def worker(pid: int, processes: int, port: int, folder: str, quick: bool, repeats: int) -> dict:
    import jax

    jax.config.update("jax_enable_x64", True)
    if processes > 1:
        from jaxrod.distributed import initialize

        initialize(f"127.0.0.1:{port}", processes, pid)
    import jaxrod.sweeps.run as run
    from jaxrod.sweeps import sweep

    spent = {"t": 0.0}

    def timed(fn):
        def wrapped(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                spent["t"] += time.perf_counter() - t0
        return wrapped

    run.broadcast, run.gather = timed(run.broadcast), timed(run.gather)
    out = {}
    for name, (spec, inputs) in scenes(quick).items():
        # compile: one chunk of the same width per process
        sweep(spec, inputs, chunk_size=CHUNK, members=range(CHUNK * processes), progress=False)
        best, coll, rerun = math.inf, math.inf, math.inf
        for r in range(repeats):
            path = os.path.join(folder, f"{name}_{r}")
            spent["t"] = 0.0
            t0 = time.perf_counter()
            res = sweep(spec, inputs, chunk_size=CHUNK, path=path, progress=False)
            t = time.perf_counter() - t0
            if t < best:
                best, coll = t, spent["t"]
            t0 = time.perf_counter()
            sweep(spec, inputs, chunk_size=CHUNK, path=path, progress=False)
            rerun = min(rerun, time.perf_counter() - t0)
        out[name] = dict(members=len(res), chunks=math.ceil(len(res) / CHUNK), seconds=best, collective_s=coll,
                         rerun_s=rerun, n=res.meta["n"], buckled=int(res.outputs["buckled"].sum()))
    return out


def launch(processes: int, quick: bool, repeats: int) -> dict:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, JAX_PLATFORMS="cpu", XLA_FLAGS="--xla_force_host_platform_device_count=1")
    with tempfile.TemporaryDirectory() as folder:
        cmd = lambda pid: [sys.executable, __file__, "--_worker", str(pid), "--_processes", str(processes),
                           "--_port", str(port), "--_folder", folder, "--repeats", str(repeats)] + (
                               ["--quick"] if quick else [])
        procs = [subprocess.Popen(cmd(pid), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
                 for pid in range(processes)]
        outs = [p.communicate() for p in procs]
    for p, (_, err) in zip(procs, outs):
        if p.returncode != 0:
            sys.exit(err[-3000:])
    return json.loads(outs[0][0].split("RESULT ", 1)[1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="a smaller map (128 nodes, 256 members), 2 repeats")
    ap.add_argument("--_worker", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--_processes", type=int, default=1, help=argparse.SUPPRESS)
    ap.add_argument("--_port", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--_folder", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.quick:
        args.repeats = 2
    if args._worker is not None:
        res = worker(args._worker, args._processes, args._port, args._folder, args.quick, args.repeats)
        print("RESULT " + json.dumps(res))
        return
    t_start = time.perf_counter()
    by_p = {p: launch(p, args.quick, args.repeats) for p in (1, 2)}
    info = device_info()
    print(f"{info['device']}, jax {info['jax']}, {info['dtype']}, one device per process, chunks of {CHUNK}")
    rows = []
    for scene in by_p[1]:
        one = by_p[1][scene]
        for p, res in by_p.items():
            r = res[scene]
            rows.append(dict(
                scene=scene, processes=p, n=r["n"], members=r["members"], chunk_size=CHUNK, chunks=r["chunks"],
                seconds=round(r["seconds"], 4), members_per_s=round(r["members"] / r["seconds"], 1),
                speedup=round(one["seconds"] / r["seconds"], 2), collective_s=round(r["collective_s"], 4),
                rerun_s=round(r["rerun_s"], 4),
                overhead_per_chunk_s=round((p * r["seconds"] - one["seconds"]) / r["chunks"], 5),
                buckled=r["buckled"], **info))
            print({k: v for k, v in rows[-1].items() if k not in info})
    assert all(by_p[2][s]["buckled"] == by_p[1][s]["buckled"] for s in by_p[1]), "1 and 2 processes disagree"
    write_csv(os.path.join(RESULTS, "distributed_throughput" + ("_quick" if args.quick else "") + ".csv"), rows,
              verbose=True)
    print(f"total {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
