"""Batched 3D rods: what a rod costs per step in a vmap of B rods, and in `jaxrod.sweep` with
L lanes per device (benchmarks/README.md, "3D rod: batched rods").

- `width`: 64 rods (reference rod, μ = 0.3, dead load F⁰₆ + 5 N, sine mode-6 velocities 5–40
  mm/s, 0.5 of the step limit, max(100, 30000 / n) steps, no stopping) run as 64/B chunks one
  after another, each a `jax.vmap` of B rods (`lax.map` of `vmap`), on one device; min of 2 after
  compilation.
- `lanes`: 64 members through `jaxrod.sweep(SweepSpec(model="rod3d", n, mu=0.3, t1))`, an 8 × 8
  grid of ΔF 1–20 N and amplitudes 2–100 mm/s (members stop when they buckle or stick), for each
  lane count; the time of the second call (compiled) over the steps the members took.

    python benchmarks/rod3d_lanes.py width --n 60 --widths 1 4 16 64
    python benchmarks/rod3d_lanes.py lanes --n 60 --lanes 1 2 4 16 --t1 0.05 --devices 2

`--devices D` (lanes) sets XLA_FLAGS=--xla_force_host_platform_device_count=D before JAX
starts, as `jaxrod map` does with one device per core.
"""

from __future__ import annotations

import argparse
import math
import os
import time


def width(n: int, widths: list[int]) -> None:
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from jaxrod import theory
    from jaxrod.experiments.rod3d import run
    from jaxrod.params import RodChannel
    from jaxrod.rod3d import Rod3D, sine_velocity, step_limit

    rod = RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    model = Rod3D(rod, n, control="load", end_load=F)
    dt = 0.5 * step_limit(model, model.initial_state(F)[0])
    steps = max(100, 30000 // n)

    def one(a):
        q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, a))
        return run(model, q, v, steps * dt, 3, dt, stop_on_buckle=False, stop_when_stuck=False).amplitude[-1]

    amps = jnp.linspace(5e-3, 40e-3, 64)
    for B in widths:
        if 64 % B:
            raise SystemExit(f"--widths: {B} does not divide 64")
        f = jax.jit(lambda a, B=B: jax.lax.map(jax.vmap(one), a.reshape(64 // B, B))).lower(amps).compile()
        jax.block_until_ready(f(amps))
        best = math.inf
        for _ in range(2):
            t0 = time.perf_counter()
            jax.block_until_ready(f(amps))
            best = min(best, time.perf_counter() - t0)
        print(f"n = {n}  vmap width {B:3d}: {best / 64 / steps * 1e6:8.1f} us per rod-step ({steps} steps)", flush=True)


def lanes(n: int, lane_counts: list[int], t1: float) -> None:
    import jax
    import numpy as np

    from jaxrod import SweepSpec, sweep

    spec = SweepSpec(model="rod3d", n=n, mu=0.3, t1=t1)
    inputs = {"dF": np.geomspace(1.0, 20.0, 8), "amplitude": np.geomspace(2e-3, 0.1, 8)}
    for L in lane_counts:
        sweep(spec, inputs, lanes=L, progress=False)  # compiles
        t0 = time.perf_counter()
        res = sweep(spec, inputs, lanes=L, progress=False)
        t = time.perf_counter() - t0
        k = int(res.meta["member_steps"])
        print(f"n = {n}  {jax.local_device_count()} device(s)  {L:3d} lane(s): {t / k * 1e6:8.1f} us per rod-step "
              f"({k} member steps, lanes busy {k / res.meta['lane_steps']:.0%}, "
              f"{int(res.outputs['buckled'].sum())} buckled)", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=["width", "lanes"])
    ap.add_argument("--n", type=int, default=60, help="segments")
    ap.add_argument("--widths", type=int, nargs="*", default=[1, 4, 16, 64])
    ap.add_argument("--lanes", type=int, nargs="*", default=[1, 2, 4, 16])
    ap.add_argument("--t1", type=float, default=0.05, help="sweep horizon [s]")
    ap.add_argument("--devices", type=int, default=None, help="XLA CPU devices (lanes; default: one per core)")
    a = ap.parse_args()
    if a.what == "lanes":
        from _common import with_devices

        os.environ["XLA_FLAGS"] = with_devices(os.environ.get("XLA_FLAGS", ""), a.devices)
        lanes(a.n, a.lanes, a.t1)
    else:
        width(a.n, a.widths)


if __name__ == "__main__":
    main()
