"""Throughput of the field model against what a user without jaxrod would write.

The workload of `field_throughput.py`: reference rod, mu = 0.3, dF = 5 N, sine mode-6 lateral
velocity perturbations (v0 spread over 1-50 mm/s across the batch), projected Verlet with the
sharp Coulomb law at 0.4 of the step limit, `--steps` fixed steps (stopping disabled, so every
member takes every step), float64. Side by side, in one run:

- `jaxrod vmap`: one `jit(vmap(simulate))` call over the batch (the package as shipped, FD
  operator).
- `jaxrod vmap, spectral operator`: the same with `operator="spectral"` (two dense n x n
  products per step: the matmul-bound formulation of the same model), at its own step limit.
- `numpy vectorised`: the same scheme written in plain NumPy over a (batch, n) array: same FD
  operator, same kick-prox-drift-kick-prox step, same friction-work and amplitude bookkeeping.
  Checked against jaxrod's final state (q, v and dissipated energy) before it is timed.
- `python loop of jitted runs`: a Python loop calling the jitted single-member run.
- `scipy solve_ivp RK45` / `LSODA`: one trajectory at a time, friction smoothed to
  f tanh(theta_t/eps) with eps = EPS_V/R (lateral speed EPS_V = 0.1 mm/s), rtol 1e-6,
  atol 1e-9, over the same simulated horizon (`--steps` x dt), for v0 = 20, 10, 15 mm/s:
  below the critical speed (about 27 mm/s), so the rod sticks. (Members that buckle run on to
  absurd small-angle amplitudes, 1e45 rad at n = 32, which RK45 takes minutes to follow; jaxrod's
  cost per step does not depend on the values.)

Also measured: the machine's float64 matmul peak (jnp and numpy, 2048^3) and streaming
bandwidth (triad a + s b), for the roofline of the stencil.

Members/s are for the horizon of `--steps` steps (400 by default: 34 ms of simulated time at
n = 128); node-steps/s = n x members x steps / wall time. Wall times: min over repeats after a
separate compilation call.

    python benchmarks/alternatives.py [--quick]

The NumPy replica and the SciPy runs are in `_alternatives_reference.py`, the figure in
`_alternatives_plot.py`.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.integrators.base import save_grid  # noqa: E402

from _alternatives_plot import plot  # noqa: E402
from _alternatives_reference import DF, MU, NumpyField, initial_states, scipy_member  # noqa: E402
from _common import best_of, time_jax, write_csv  # noqa: E402

# float64 arithmetic per node and step of the FD scheme as timed (add, sub, mul, div; abs, sign,
# comparisons and selects not counted): two kicks 2+2, two proximal steps 2+2 (h f, v - h f sgn v),
# drift 2, acceleration 14 (two second differences 4+4, EI d4 + F d2 + (w/R) theta 5, / rho 1).
# The friction-work bookkeeping (5+5 more) is not in the timed runs (see `jaxrod_run`).
FLOPS_PER_NODE_STEP = 2 + 2 + 2 + 2 + 2 + 14
# touched per node and step at least: read q, v, a; write q, v, a (8 bytes each)
BYTES_PER_NODE_STEP = 6 * 8


# -- machine peaks -------------------------------------------------------------------------------

def machine_peaks(size: int, repeats: int) -> dict:
    rng = np.random.default_rng(0)
    a = rng.standard_normal((size, size))
    b = rng.standard_normal((size, size))
    ja, jb = jnp.asarray(a), jnp.asarray(b)
    mm = jax.jit(jnp.matmul)
    jax.block_until_ready(mm(ja, jb))
    t_j = best_of(lambda: jax.block_until_ready(mm(ja, jb)), repeats)
    np.matmul(a, b)
    t_n = best_of(lambda: np.matmul(a, b), repeats)
    flops = 2.0 * size**3
    bw = {}
    for label, m, reps in (("dram", 1 << 24, 5), ("cache", 1 << 17, 200)):  # 128 MB / 1 MB arrays
        y = jnp.full(m, 2.0)
        # the triad x <- 0.5 x + 3 y with x donated: reads x, y, writes x in place, no allocation
        triad = jax.jit(lambda x, y: 0.5 * x + 3.0 * y, donate_argnums=0)
        box = [triad(jnp.ones(m), y)]

        def calls(reps=reps, triad=triad, y=y, box=box):
            for _ in range(reps):
                box[0] = triad(box[0], y)
            jax.block_until_ready(box[0])

        calls()
        bw[label] = 3 * 8 * m * reps / best_of(calls, repeats) / 1e9
    m = 1 << 24
    x, y, out = np.ones(m), np.full(m, 2.0), np.empty(m)
    # numpy makes two passes (y*3 -> out; out + x -> out): 5 array transits of 8 bytes
    t_tn = best_of(lambda: np.add(x, np.multiply(y, 3.0, out=out), out=out), repeats)
    return {
        "matmul_size": size,
        "matmul_gflops_jax": flops / t_j / 1e9,
        "matmul_gflops_numpy": flops / t_n / 1e9,
        "triad_gbytes_per_s_jax": bw["dram"],
        "triad_gbytes_per_s_jax_in_cache": bw["cache"],
        "triad_gbytes_per_s_numpy": 5 * 8 * m / t_tn / 1e9,
    }


# -- the jaxrod runs -----------------------------------------------------------------------------

def setup(n: int, steps: int, operator: str = "fd"):
    rod = jr.RodChannel.reference(mu=MU)
    dt = 0.4 * 2 / float(jr.FieldModel.from_rod(rod, n, dF=0.0, operator=operator).max_frequency())
    t1 = steps * dt
    m, h = save_grid(t1, 2, dt)
    assert m == steps
    return rod, dt, t1, h


def jaxrod_run(n: int, steps: int, operator: str = "fd", full: bool = False, threshold: float = math.inf):
    """The single-member run (unjitted) and its horizon. It returns the final angles, as
    `field_throughput.py` does (XLA then drops the friction-work bookkeeping, which nothing
    reads); `full=True` also returns the final velocities and the dissipated energy. Timed runs
    have no buckling stop (`threshold` = inf): every member takes every step; a member frozen
    at a finite threshold still costs its steps (the loop keeps the old state)."""
    rod, dt, t1, h = setup(n, steps, operator)
    opts = jr.RunOptions(buckle_threshold=threshold, stop_when_stuck=False, early_exit=False, save_state=False)

    def one(v0):
        m = jr.FieldModel.from_rod(rod, n, dF=DF, operator=operator)
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(m)
        sol = jr.simulate(m, jr.ProjectedVerlet(dt), q0, w0, t1, n_save=2, options=opts, throw=False)
        return (sol.q_final, sol.v_final, sol.dissipated[-1]) if full else sol.q_final

    return one, t1, h


def amplitudes(batch: int) -> np.ndarray:
    return np.linspace(0.001, 0.05, batch)


def verify_numpy(n: int, steps: int) -> float:
    """Largest relative difference between the NumPy replica and jaxrod (q, v, dissipated)
    after `steps` steps, both with the package's buckling stop at max|θ| = 0.5 rad (past it the
    unbounded small-angle growth, to 1e45 rad at n = 32, turns one-ulp differences in a stick
    decision into visible ones)."""
    one, _, h = jaxrod_run(n, steps, full=True, threshold=0.5)
    v0 = amplitudes(8)
    qj, vj, Dj = map(np.asarray, jax.jit(jax.vmap(one))(jnp.asarray(v0)))
    q0, w0 = initial_states(n, v0)
    qn, vn, Dn = NumpyField(n, threshold=0.5).run(q0, w0, h, steps)
    rel = lambda x, y: float(np.max(np.abs(x - y)) / np.max(np.abs(y)))
    return max(rel(qn, qj), rel(vn, vj), rel(Dn, Dj))


# -- the benchmark -------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes: about a minute")
    ap.add_argument("--n", type=int, nargs="*", default=None)
    ap.add_argument("--batch", type=int, nargs="*", default=None)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=None,
                    help="CSV path (default benchmarks/results/alternatives.csv, alternatives_quick.csv with --quick)")
    args = ap.parse_args()
    args.out = args.out or f"benchmarks/results/alternatives{'_quick' if args.quick else ''}.csv"
    ns = args.n or ([32, 128] if args.quick else [32, 128, 512])
    batches = args.batch or ([1, 16, 256] if args.quick else [1, 4, 16, 64, 256, 1024, 4096])
    steps = 100 if args.quick and args.steps == 400 else args.steps
    repeats = 2 if args.quick else args.repeats
    # work budgets (node-steps per timed call) for the slow implementations: their per-step cost
    # does not depend on the number of steps, so they are timed over fewer steps where needed
    np_budget = 2e6 if args.quick else 2e7
    spec_budget = 4e9 if args.quick else 4e10  # flops (the spectral step costs ~ 4 n^2 per member)
    scipy_members = 1 if args.quick else 3
    loop_members = 8 if args.quick else 32

    t_start = time.perf_counter()
    dev = jax.devices()[0]
    info = dict(device=dev.device_kind if dev.platform != "cpu" else f"cpu ({platform.processor() or platform.machine()})",
                cores=os.cpu_count(), jax=jax.__version__, numpy=np.__version__, dtype="float64")
    try:
        import scipy

        info["scipy"] = scipy.__version__
    except ImportError:
        info["scipy"] = None
    print("  ".join(f"{k}={v}" for k, v in info.items()))
    peaks = machine_peaks(1024 if args.quick else 2048, repeats)
    print(f"matmul float64 peak: jax {peaks['matmul_gflops_jax']:.1f} GFLOP/s, numpy "
          f"{peaks['matmul_gflops_numpy']:.1f} GFLOP/s; triad bandwidth: jax "
          f"{peaks['triad_gbytes_per_s_jax']:.1f} GB/s (1 MB arrays: {peaks['triad_gbytes_per_s_jax_in_cache']:.1f}), "
          f"numpy {peaks['triad_gbytes_per_s_numpy']:.1f} GB/s")

    rows = []

    def add(impl, n, batch, steps_timed, run_s, compile_s, step, horizon, flops_per_member_step=None,
            check=None, nfev=None):
        """`step` [s] of the implementation; members/s are for the simulated `horizon` [s]."""
        node_steps = n * batch * steps_timed / run_s
        row = dict(impl=impl, n=n, batch=batch, steps_timed=steps_timed, step_s=step, horizon_s=horizon,
                   run_s=run_s, compile_s=compile_s, node_steps_per_s=node_steps,
                   members_per_s=batch * steps_timed * step / horizon / run_s,
                   gflops=(flops_per_member_step * batch * steps_timed / run_s / 1e9
                           if flops_per_member_step else None),
                   check=check, nfev=nfev)
        rows.append(row)
        print(f"  {impl:34s} n={n:4d} batch={batch:5d} steps={steps_timed:4d} run={run_s:9.4f}s "
              f"node-steps/s={node_steps:9.3e} members/s={row['members_per_s']:9.3e}"
              + (f" GFLOP/s={row['gflops']:.2f}" if row["gflops"] else "")
              + (f" [{check}]" if check else ""))

    for n in ns:
        print(f"n = {n}")
        err = verify_numpy(n, steps)
        print(f"  numpy replica vs jaxrod after {steps} steps: max relative difference {err:.2e}")
        if not err < 1e-10:
            raise SystemExit(f"the NumPy replica differs from jaxrod by {err:.2e} at n = {n}: not timed")
        one, t1, h = jaxrod_run(n, steps)
        one_spec, _, h_spec = jaxrod_run(n, steps, "spectral")
        vmapped = jax.jit(jax.vmap(one))
        fd_flops = FLOPS_PER_NODE_STEP * n
        # two n x n products and the modal scaling (about 7 n) replace the 14 n of the stencil
        spec_flops = 4 * n * n + (FLOPS_PER_NODE_STEP - 14 + 7) * n
        nf = NumpyField(n)
        for b in batches:
            v0 = jnp.asarray(amplitudes(b))
            run_s, comp = time_jax(vmapped, (v0,), repeats)
            add("jaxrod vmap (FD)", n, b, steps, run_s, comp, h, t1, fd_flops)
            s_spec = int(min(steps, max(10, spec_budget / (spec_flops * b))))
            if s_spec == steps:
                f_spec = jax.jit(jax.vmap(one_spec))
            else:
                f_spec = jax.jit(jax.vmap(jaxrod_run(n, s_spec, "spectral")[0]))
            run_s, comp = time_jax(f_spec, (v0,), repeats)
            add("jaxrod vmap (spectral, dense)", n, b, s_spec, run_s, comp, h_spec, t1, spec_flops)
            s_np = int(min(steps, max(5, np_budget / (n * b))))
            q0, w0 = initial_states(n, amplitudes(b))
            run_s = best_of(lambda: nf.run(q0, w0, h, s_np, work=False), max(1, repeats - 1))
            add("numpy vectorised (FD)", n, b, s_np, run_s, None, h, t1, fd_flops)
        single = jax.jit(one)
        vs = amplitudes(loop_members)
        jax.block_until_ready(single(jnp.asarray(vs[0])))

        def loop():
            for x in vs:
                jax.block_until_ready(single(jnp.asarray(x)))

        run_s = best_of(loop, max(1, repeats - 1))
        add("python loop of jitted runs", n, loop_members, steps, run_s, None, h, t1, fd_flops)
        # SciPy: whole trajectories; members/s over the same horizon, compared with jaxrod's
        # final state as a sanity check of the smoothed law (v0 = 20 mm/s)
        q_ref = np.asarray(jax.jit(one)(jnp.asarray(0.02)))
        for method in ("RK45", "LSODA"):
            walls, nfev, checked = [], 0, None
            for x in [0.02, 0.01, 0.015][:scipy_members]:  # sub-critical: the rod sticks
                w, qf, nf_, ok = scipy_member(n, x, t1, method)
                walls.append(w)
                nfev += nf_
                checked = checked or (qf, ok)
            qf, ok = checked
            diff = float(np.max(np.abs(qf - q_ref)) / np.max(np.abs(q_ref)))
            total = float(np.sum(walls))
            add(f"scipy solve_ivp {method} (tanh law)", n, scipy_members, steps, total, None, t1 / steps, t1,
                check=f"max|theta - jaxrod| / max|theta| = {diff:.1e}" + ("" if ok else " (failed)"),
                nfev=nfev // scipy_members)

    # the peaks again at the end (the CPU is shared): the best of both measurements counts
    again = machine_peaks(1024 if args.quick else 2048, repeats)
    peaks = {k: max(v, again[k]) for k, v in peaks.items()}
    peaks["matmul_gflops_peak"] = max(peaks["matmul_gflops_jax"], peaks["matmul_gflops_numpy"])
    print(f"matmul float64 peak, best of start and end: jax {peaks['matmul_gflops_jax']:.1f}, numpy "
          f"{peaks['matmul_gflops_numpy']:.1f} GFLOP/s")

    # -- summary against the targets (n = 128, batch 1024) ------------------------------
    def rate(impl, n, b=None, key="members_per_s"):
        sel = [r for r in rows if r["impl"] == impl and r["n"] == n and (b is None or r["batch"] == b)]
        return sel[-1][key] if sel else math.nan

    summary = {"info": info, "peaks": peaks, "flops_per_node_step": FLOPS_PER_NODE_STEP,
               "bytes_per_node_step_min": BYTES_PER_NODE_STEP, "seconds": None}
    n0 = 128 if 128 in ns else ns[-1]
    b0 = 1024 if 1024 in batches else batches[-1]
    jr_m = rate("jaxrod vmap (FD)", n0, b0)
    summary["target_case"] = dict(n=n0, batch=b0)
    summary["node_steps_per_s"] = rate("jaxrod vmap (FD)", n0, b0, "node_steps_per_s")
    summary["vs_numpy"] = jr_m / rate("numpy vectorised (FD)", n0, b0)
    summary["vs_scipy_rk45"] = jr_m / rate("scipy solve_ivp RK45 (tanh law)", n0)
    summary["vs_scipy_lsoda"] = jr_m / rate("scipy solve_ivp LSODA (tanh law)", n0)
    summary["vs_python_loop"] = jr_m / rate("python loop of jitted runs", n0)
    summary["fd_gflops"] = rate("jaxrod vmap (FD)", n0, b0, "gflops")
    summary["fd_fraction_of_matmul_peak"] = summary["fd_gflops"] / peaks["matmul_gflops_peak"]
    summary["fd_gbytes_per_s_min"] = summary["node_steps_per_s"] * BYTES_PER_NODE_STEP / 1e9
    summary["spectral_gflops"] = rate("jaxrod vmap (spectral, dense)", n0, b0, "gflops")
    summary["spectral_fraction_of_matmul_peak"] = summary["spectral_gflops"] / peaks["matmul_gflops_peak"]
    summary["spectral_over_fd_members"] = rate("jaxrod vmap (spectral, dense)", n0, b0) / jr_m
    best = max((r for r in rows if r["gflops"] and r["impl"].startswith("jaxrod vmap (spectral")),
               key=lambda r: r["gflops"], default=None)
    if best:
        summary["spectral_best"] = dict(n=best["n"], batch=best["batch"], gflops=best["gflops"],
                                        fraction=best["gflops"] / peaks["matmul_gflops_peak"])
    summary["seconds"] = round(time.perf_counter() - t_start, 1)
    print(f"\nn = {n0}, batch = {b0}, float64 (targets in brackets):")
    print(f"  jaxrod node-steps/s           {summary['node_steps_per_s']:.3e}  [>= 1e8]")
    print(f"  jaxrod / numpy vectorised     {summary['vs_numpy']:.2f}x  [>= 5x]")
    print(f"  jaxrod / scipy RK45 per member {summary['vs_scipy_rk45']:.3g}x; LSODA "
          f"{summary['vs_scipy_lsoda']:.3g}x  [>= 1000x]")
    print(f"  jaxrod / python loop of jitted runs {summary['vs_python_loop']:.2f}x")
    print(f"  FD stencil: {summary['fd_gflops']:.2f} GFLOP/s = {100 * summary['fd_fraction_of_matmul_peak']:.1f} % "
          f"of the matmul peak ({peaks['matmul_gflops_peak']:.1f}); >= {summary['fd_gbytes_per_s_min']:.1f} GB/s "
          f"of state traffic against a triad bandwidth of {peaks['triad_gbytes_per_s_jax']:.1f} GB/s "
          f"({peaks['triad_gbytes_per_s_jax_in_cache']:.1f} GB/s in cache)")
    print(f"  spectral (dense): {summary['spectral_gflops']:.2f} GFLOP/s = "
          f"{100 * summary['spectral_fraction_of_matmul_peak']:.1f} % of the matmul peak; "
          f"{summary['spectral_over_fd_members']:.2f}x the FD members/s")
    print(f"total {summary['seconds']} s")

    write_csv(args.out, rows)
    with open(os.path.splitext(args.out)[0] + "_summary.json", "w") as fh:
        json.dump(summary, fh, indent=1)
    plot(rows, ns, os.path.splitext(args.out)[0] + ".png", info, steps)


if __name__ == "__main__":
    main()
