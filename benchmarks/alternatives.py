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
"""

from __future__ import annotations

import argparse
import csv
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

DF = 5.0
MU = 0.3
EPS_V = 1e-4  # m/s: the tanh regularisation as a lateral speed (1/200 of a 20 mm/s perturbation)
# float64 arithmetic per node and step of the FD scheme as timed (add, sub, mul, div; abs, sign,
# comparisons and selects not counted): two kicks 2+2, two proximal steps 2+2 (h f, v - h f sgn v),
# drift 2, acceleration 14 (two second differences 4+4, EI d4 + F d2 + (w/R) theta 5, / rho 1).
# The friction-work bookkeeping (5+5 more) is not in the timed runs (see `jaxrod_run`).
FLOPS_PER_NODE_STEP = 2 + 2 + 2 + 2 + 2 + 14
# touched per node and step at least: read q, v, a; write q, v, a (8 bytes each)
BYTES_PER_NODE_STEP = 6 * 8


# -- machine peaks -------------------------------------------------------------------------------

def best_of(fn, repeats):
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


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


def time_jax(fn, args, repeats):
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    best = best_of(lambda: jax.block_until_ready(fn(*args)), repeats)
    return best, max(first - best, 0.0)


# -- the NumPy replica ---------------------------------------------------------------------------

class NumpyField:
    """Projected Verlet on the FD field model, vectorised over a (batch, n) array in NumPy:
    the scheme of `jaxrod.ProjectedVerlet` + `jaxrod.FieldModel(operator="fd")` + `Coulomb`,
    operation for operation."""

    def __init__(self, n: int, threshold: float = math.inf):
        rod = jr.RodChannel.reference(mu=MU)
        model = jr.FieldModel.from_rod(rod, n, dF=DF)
        self.n = n
        self.EI = float(rod.EI)
        self.rho = float(rod.rho)
        self.wR = float(rod.w / rod.R)
        self.F = float(model.load(0.0))
        self.inv_h2 = 1.0 / float(model.spacing) ** 2
        self.spacing2 = float(model.spacing) ** 2
        fs, fd = model.friction_bounds(0.0)
        self.fs, self.fd = float(fs), float(fd)
        self.ke = float(rod.rho * rod.R**2 * model.spacing)  # kinetic energy = ke/2 |v|^2
        self.thr = threshold  # buckling stop: max|θ| past it freezes the member, as in jaxrod

    def d2(self, x):
        out = -2.0 * x
        out[:, 1:] += x[:, :-1]
        out[:, :-1] += x[:, 1:]
        return out / self.spacing2

    def acceleration(self, q):
        d2 = self.d2(q)
        return -(self.EI * self.d2(d2) + self.F * d2 + self.wR * q) / self.rho

    def prox(self, v_trial, v_prev, h):
        threshold = h * np.where(v_prev == 0, self.fs, self.fd)
        slips = np.abs(v_trial) > threshold
        return np.where(slips, v_trial - h * self.fd * np.sign(v_trial), 0.0)

    def work(self, v_prev, v_trial, v_after):
        return self.ke * np.sum(0.5 * (v_prev + v_after) * (v_trial - v_after), axis=-1)

    def run(self, q, v, h, steps, work=True):
        """`steps` steps of size `h` from (q, v) [rad, rad/s], shape (batch, n). With
        `work=False` the dissipated energy is not accumulated (timed runs: the jaxrod run timed
        returns only the final angles, so XLA drops that bookkeeping too)."""
        q, v = q.copy(), v.copy()
        a = self.acceleration(q)
        D = np.zeros(q.shape[0])
        done = np.zeros((q.shape[0], 1), bool)
        freeze = math.isfinite(self.thr)  # a NumPy user without a stop would not write it
        half = 0.5 * h
        for _ in range(steps):
            v_trial = v + half * a
            v_half = self.prox(v_trial, v, half)
            dD = self.work(v, v_trial, v_half) if work else 0.0
            q1 = q + h * v_half
            a1 = self.acceleration(q1)
            v_trial = v_half + half * a1
            v1 = self.prox(v_trial, v_half, half)
            if work:
                dD = dD + self.work(v_half, v_trial, v1)
            if freeze:
                q, v, a = (np.where(done, x, x1) for x, x1 in ((q, q1), (v, v1), (a, a1)))
                D = np.where(done[:, 0], D, D + dD)
                done = done | (np.max(np.abs(q1), axis=-1, keepdims=True) > self.thr)
            else:
                q, v, a, D = q1, v1, a1, D + dD
                np.max(np.abs(q), axis=-1) > self.thr  # the amplitude test jaxrod makes every step
        return q, v, D


def initial_states(n: int, v0: np.ndarray):
    rod = jr.RodChannel.reference(mu=MU)
    m = jr.FieldModel.from_rod(rod, n, dF=DF)
    q0, w0 = jax.vmap(lambda a: jr.SineVelocity(a, 6).initial_state(m))(jnp.asarray(v0))
    return np.asarray(q0), np.asarray(w0)


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


# -- SciPy solve_ivp with the smoothed law -------------------------------------------------------

def scipy_member(n: int, v0: float, t1: float, method: str):
    from scipy.integrate import solve_ivp

    f = NumpyField(n)
    eps = EPS_V / float(jr.RodChannel.reference(mu=MU).R)
    q0, w0 = initial_states(n, np.array([v0]))

    def rhs(t, y):
        q, v = y[:n], y[n:]
        d2 = np.empty(n)
        d2[:] = -2.0 * q
        d2[1:] += q[:-1]
        d2[:-1] += q[1:]
        d2 /= f.spacing2
        d4 = -2.0 * d2
        d4[1:] += d2[:-1]
        d4[:-1] += d2[1:]
        d4 /= f.spacing2
        a = -(f.EI * d4 + f.F * d2 + f.wR * q) / f.rho - f.fd * np.tanh(v / eps)
        return np.concatenate([v, a])

    t0 = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t1), np.concatenate([q0[0], w0[0]]), method=method, rtol=1e-6, atol=1e-9)
    wall = time.perf_counter() - t0
    return wall, sol.y[:n, -1], int(sol.nfev), bool(sol.success)


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

    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(os.path.splitext(args.out)[0] + "_summary.json", "w") as fh:
        json.dump(summary, fh, indent=1)
    plot(rows, ns, os.path.splitext(args.out)[0] + ".png", info, steps)


def plot(rows, ns, path, info, steps):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = {
        "jaxrod vmap (FD)": dict(color="C0", marker="o", lw=2),
        "jaxrod vmap (spectral, dense)": dict(color="C0", marker="s", ls="--"),
        "numpy vectorised (FD)": dict(color="C1", marker="^"),
        "python loop of jitted runs": dict(color="C2", ls=":"),
        "scipy solve_ivp RK45 (tanh law)": dict(color="C3", ls="-."),
        "scipy solve_ivp LSODA (tanh law)": dict(color="C4", ls="-."),
    }
    fig, axes = plt.subplots(1, len(ns), figsize=(5.2 * len(ns), 4.6), squeeze=False)
    for ax, n in zip(axes[0], ns):
        batches = sorted({r["batch"] for r in rows if r["n"] == n and r["impl"].startswith("jaxrod vmap")})
        for impl, st in styles.items():
            sel = [r for r in rows if r["impl"] == impl and r["n"] == n]
            if not sel:
                continue
            if impl.startswith(("jaxrod vmap", "numpy")):
                ax.plot([r["batch"] for r in sel], [r["members_per_s"] for r in sel], label=impl, **st)
            else:  # one member at a time: a constant rate
                ax.plot([batches[0], batches[-1]], [sel[-1]["members_per_s"]] * 2, label=impl, **st)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("batch size (members per call)")
        ax.set_ylabel(f"members/s ({steps}-step horizon)")
        ax.set_title(f"n = {n}", fontsize=10)
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Field model throughput, float64, {info['device']}, {info['cores']} cores, "
                 f"JAX {info['jax']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main()
