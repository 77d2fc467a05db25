"""XLA's CPU fusion emitters on and off (`--xla_cpu_use_fusion_emitters=false`), side by side.

The default test suite compiles thousands of small programs (each operation run outside `jit`
compiles one per shape and dtype), and at XLA's optimisation level 0 (`tests/conftest.py`) the
cost of a program is mostly fixed: code generation. XLA's CPU backend generates fused kernels
with its newer "fusion emitters" by default; the flag above selects the older ones. This script
measures what the flag does, in pairs of fresh processes (emitters on, off; alternating order
between rounds), and reports the median over rounds of the ratio within a round:

- `eager`: 30 array sizes × 5 operations run outside `jit` (150 small programs): compile time;
- the workloads of `xla_loops.py` (`field-1`, `field-1024`, `rod3d-1`, `rod3d-64`,
  `single-mode`, `field-vstar`): the steady run time and the compile time.

`--level0` runs every process with `JAX_DISABLE_MOST_OPTIMIZATIONS=1`, as the tests compile.
Rows go to `benchmarks/results/fusion_emitters[_level0].csv`.

    python benchmarks/fusion_emitters.py --level0 --only eager field-1 rod3d-1   # the tests' case
    python benchmarks/fusion_emitters.py                                          # users' case
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

FLAG = "--xla_cpu_use_fusion_emitters=false"
WORKLOADS = ("eager", "field-1", "field-1024", "rod3d-1", "rod3d-64", "single-mode", "field-vstar")


def worker(name: str) -> dict:
    """One workload in this process: run and compile seconds (`eager`: 0 and the compile time)."""
    if name != "eager":
        import xla_loops

        r = xla_loops.worker(name)
        return dict(workload=name, run_s=r["run_s"], compile_s=r["compile_s"])
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    import jaxrod  # noqa: F401  (its XLA option, as in every jaxrod process)

    jnp.zeros(1).block_until_ready()  # the backend's start, not counted
    t0 = time.perf_counter()
    for n in range(1, 31):
        x = jnp.ones(n)
        jnp.sum(jnp.sin(x) + x * 2.0).block_until_ready()
    return dict(workload=name, run_s=0.0, compile_s=time.perf_counter() - t0)


def _run(name: str, emitters: bool, level0: bool) -> dict:
    from _common import worker_in_process, xla_env

    env = xla_env("shipped")
    if not emitters:
        env["XLA_FLAGS"] = FLAG
    if level0:
        env["JAX_DISABLE_MOST_OPTIMIZATIONS"] = "1"
    return worker_in_process("fusion_emitters", name, env, f"emitters {'on' if emitters else 'off'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", nargs="*", default=list(WORKLOADS), choices=WORKLOADS)
    ap.add_argument("--level0", action="store_true", help="JAX_DISABLE_MOST_OPTIMIZATIONS=1, as the tests")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    out = args.out or os.path.join(HERE, "results", f"fusion_emitters{'_level0' if args.level0 else ''}.csv")
    rows = []
    for k in range(args.rounds):
        for name in args.only:
            for on in (True, False) if k % 2 == 0 else (False, True):
                r = _run(name, on, args.level0)
                r.update(round=k, emitters="on" if on else "off", level0=args.level0)
                rows.append(r)
                print(f"round {k}  {name:12s} emitters {r['emitters']:3s}  run {r['run_s']:8.4f} s  "
                      f"compile {r['compile_s']:6.2f} s", flush=True)
    from _common import write_csv

    write_csv(out, rows)
    print()
    for name in args.only:
        sel = {(r["emitters"], r["round"]): r for r in rows if r["workload"] == name}
        comp = [sel["off", k]["compile_s"] / max(sel["on", k]["compile_s"], 1e-9) for k in range(args.rounds)]
        line = (f"{name:12s} compile {statistics.median(comp):.2f}x as long with the emitters off "
                f"(rounds {', '.join(f'{x:.2f}' for x in comp)})")
        if name != "eager":
            run = [sel["off", k]["run_s"] / sel["on", k]["run_s"] for k in range(args.rounds)]
            line += f"; run {statistics.median(run):.2f}x as long (rounds {', '.join(f'{x:.2f}' for x in run)})"
        print(line)
    print("wrote", out)


if __name__ == "__main__":
    main()
