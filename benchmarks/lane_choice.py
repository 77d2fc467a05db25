"""How the pool's lane count B and steps between refills K were chosen: seconds and lane
utilisation of the default E3 map (mu = 0.3, 20 x 24 points, field model, n = 384) for each
(B, K), on the devices `jaxrod map` uses (one per core).

More lanes share each vectorised step among more members, but the last members of a chunk leave
more lanes idle (the tail) and the lanes' state outgrows the caches; more steps between refills
cut the refill work but leave a stopped member's lane idle longer.

    python benchmarks/lane_choice.py [--lanes 4 8 16 32 64] [--every 4 16 64] [--devices 2]

Writes benchmarks/results/lane_choice.csv.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time


def child(lanes: list[int], every: list[int], repeats: int) -> list[dict]:
    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from jaxrod.sweeps import SweepSpec, sweep

    spec = SweepSpec(model="field", mu=0.3)
    inputs = {"dF": np.geomspace(0.5, 64, 20), "amplitude": np.geomspace(1e-3, 0.2, 24)}
    rows = []
    for B in lanes:
        for K in every:
            res = sweep(spec, inputs, lanes=B, refill_every=K, progress=False)  # compile
            best = min(_time(lambda: sweep(spec, inputs, lanes=B, refill_every=K, progress=False))
                       for _ in range(repeats))
            rows.append(dict(lanes=B, refill_every=K, devices=jax.local_device_count(),
                             n=res.meta["n"], seconds=round(best, 3),
                             utilisation=round(res.meta["member_steps"] / res.meta["lane_steps"], 3),
                             buckled=int(res.outputs["buckled"].sum())))
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def _time(f) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lanes", type=int, nargs="*", default=[4, 8, 16, 32, 64])
    ap.add_argument("--every", type=int, nargs="*", default=[4, 16, 64])
    ap.add_argument("--devices", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default="benchmarks/results/lane_choice.csv")
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:
        print("ROWS " + json.dumps(child(args.lanes, args.every, args.repeats)))
        return
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={args.devices}")
    cmd = [sys.executable, __file__, "--_child", "--repeats", str(args.repeats), "--lanes",
           *map(str, args.lanes), "--every", *map(str, args.every)]
    out = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, env=env)
    if out.returncode != 0:
        sys.exit(out.returncode)
    rows = json.loads(out.stdout.split("ROWS ", 1)[1])
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"{'B':>4} {'K':>4} {'seconds':>8} {'utilisation':>11}")
    for r in rows:
        print(f"{r['lanes']:>4} {r['refill_every']:>4} {r['seconds']:>8.3f} {r['utilisation']:>11.3f}")


if __name__ == "__main__":
    main()
