"""What a 3D run costs through a sweep against the same run through a `Scene`: the explicit leapfrog at
500 segments, 64 N past F⁰₆, μ = 0.3, the sine velocity at 3.164 mm/s (a stable cell of the E3
map's 64 N column, which runs to the map's horizon), each path compiled once and then timed warm,
side by side in one process on one device.

    XLA_FLAGS=--xla_force_host_platform_device_count=1 python benchmarks/rod3d_sweep_step.py [--t1 0.01]

Writes `rod3d_sweep_step.json` (commit, date, machine, µs a step by each path) under
benchmarks/results/ (or `--out`).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import time

import jax

jax.config.update("jax_enable_x64", True)

from _common import commit  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    import jaxrod as jr
    from jaxrod.registry import make_perturbation
    from jaxrod.sweeps import SweepSpec, sweep

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t1", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results", "rod3d_sweep_step.json"))
    a = ap.parse_args()
    dF, v0, n = 64.0, 3.164e-3, 500
    spec = SweepSpec(model="rod3d", perturbation="sine", mu=0.3, mode=6, n=n, t1=a.t1)
    scene = jr.Scene(jr.RodChannel.reference(0.3), dF, make_perturbation("sine", v0, 6), "rod3d", n, 6)

    def by_sweep():
        return sweep(spec, {"dF": [dF], "amplitude": [v0]}, combine="zip", progress=False)

    def by_scene():
        return jax.block_until_ready(scene.run(t1=a.t1, save_state=False).buckled)

    res = by_sweep()
    by_scene()
    dt = res.meta["dt"]
    steps = round(a.t1 / dt)
    walls = {"sweep": [], "scene": []}
    for _ in range(a.repeats):  # alternated, so that both see the same machine
        for name, f in (("sweep", by_sweep), ("scene", by_scene)):
            t = time.perf_counter()
            f()
            walls[name].append(time.perf_counter() - t)
    record = dict(commit=commit(ROOT), date=datetime.date.today().isoformat(), machine=f"{platform.machine()}, {os.cpu_count()} cores",
                  devices=jax.local_device_count(), scheme=res.meta["scheme"], dt=dt, steps=steps, t1=a.t1,
                  us_per_step={k: 1e6 * min(v) / steps for k, v in walls.items()}, walls_s=walls)
    with open(a.out, "w") as fh:
        json.dump(record, fh, indent=1)
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
