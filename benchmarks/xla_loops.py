"""XLA's loop option (`jaxrod/_xla.py`): every workload with and without it, side by side.

jaxrod adds `xla_cpu_small_while_loop_byte_threshold=1e8` to `XLA_FLAGS` when it is imported,
so that XLA on the CPU compiles each loop of a run as one function instead of dispatching its
fused kernels one by one. This script measures what that does to each kind of work, in pairs
of processes (one with the option, one with `JAXROD_XLA_DEFAULTS=0`), alternating, and reports
the median over rounds of the ratio within a round (the machine's noise is up to 2× here):

- `field-1`, `field-1024`: the field model (n = 128), projected Verlet, 400 steps, batch 1 and a
  vmapped batch of 1024 (`field_throughput.measure`);
- `rod3d-1`, `rod3d-64`: the 3D rod (60 segments), the case of `rod3d_step.py`, 1000 steps, one
  rod and a vmapped batch of 64 (250 steps);
- `single-mode`, `field-vstar`: the critical velocity v₀* at ΔF = 5 N of the single-mode and
  the field model (`jaxrod.critical_velocity`, default search), drivers of many small runs
  (the second call of the process: compiled code reused).

Rows (seconds of the steady run, compile seconds, both settings) go to
`benchmarks/results/xla_loops.csv`.

    python benchmarks/xla_loops.py              # 3 rounds, about 6 min
    python benchmarks/xla_loops.py --rounds 1   # about 2 min
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

WORKLOADS = ("field-1", "field-1024", "rod3d-1", "rod3d-64", "single-mode", "field-vstar")


def worker(name: str) -> dict:
    """One workload in this process: the steady run time [s] and the compile time [s]."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    import jaxrod as jr
    from jaxrod import _xla

    if name in ("field-1", "field-1024"):
        from field_throughput import measure

        r = measure("float64", 128, int(name.split("-")[1]), 400, 3)
        run_s, compile_s = r["run_s"], r["compile_s"]
    elif name.startswith("rod3d"):
        from jaxrod import theory
        from jaxrod.experiments.rod3d import run
        from jaxrod.rod3d import Rod3D, sine_velocity, step_limit

        rod = jr.RodChannel.reference(0.3)
        F = float(theory.reference_load(rod)) + 5.0
        model = Rod3D(rod, 60, control="load", end_load=F)
        dt = 0.5 * step_limit(model, model.initial_state(F)[0])
        B = int(name.split("-")[1])
        steps = 1000 if B == 1 else 250

        def one(a):
            q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, a))
            return run(model, q, v, steps * dt, 3, dt, stop_on_buckle=False, stop_when_stuck=False).amplitude[-1]

        f, arg = (jax.jit(one), jnp.asarray(20e-3)) if B == 1 else (jax.jit(jax.vmap(one)), jnp.linspace(5e-3, 40e-3, B))
        from _common import time_jax

        run_s, compile_s = time_jax(f, (arg,), 3)
    else:  # a boundary search: single mode, or the field model at its default resolution
        rod = jr.RodChannel.reference(0.3)
        kind = "mode" if name == "single-mode" else "field"
        t0 = time.perf_counter()
        jr.critical_velocity(rod, 5.0, model=kind)
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        jr.critical_velocity(rod, 5.0, model=kind)
        run_s = time.perf_counter() - t0
        compile_s = first - run_s
    return dict(workload=name, loops_one_function=_xla.in_effect(), run_s=run_s, compile_s=compile_s)


def _run(name: str, on: bool) -> dict:
    from _common import worker_in_process, xla_env

    return worker_in_process("xla_loops", name, xla_env("shipped" if on else "off"), f"option {'on' if on else 'off'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", nargs="*", default=list(WORKLOADS), choices=WORKLOADS)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "xla_loops.csv"))
    args = ap.parse_args()
    rows = []
    for k in range(args.rounds):
        for name in args.only:
            for on in (True, False) if k % 2 == 0 else (False, True):
                r = _run(name, on)
                r.update(round=k, option="on" if on else "off")
                rows.append(r)
                print(f"round {k}  {name:12s} option {r['option']:3s} (in effect: {r['loops_one_function']})  "
                      f"run {r['run_s']:8.4f} s  compile {r['compile_s']:6.2f} s", flush=True)
    from _common import write_csv

    write_csv(args.out, rows)
    print()
    for name in args.only:
        sel = {(r["option"], r["round"]): r for r in rows if r["workload"] == name}
        speed = [sel["off", k]["run_s"] / sel["on", k]["run_s"] for k in range(args.rounds)]
        comp = [sel["on", k]["compile_s"] / max(sel["off", k]["compile_s"], 1e-9) for k in range(args.rounds)]
        print(f"{name:12s} run {statistics.median(speed):5.2f}x faster with the option "
              f"(rounds {', '.join(f'{x:.2f}' for x in speed)}); compile {statistics.median(comp):.2f}x as long")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
