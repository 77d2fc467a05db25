"""The 3D rod's step as arithmetic: XLA's operation count per node, the rate the step runs at, and
the rate XLA's fused elementwise code reaches on this CPU — the ceiling behind issue [rod3d]'s
≥ 10× for one rod.

For each size: the operations (`compiled.cost_analysis()["flops"]`: every elementwise operation
counts one) per node of each piece of the step (forces, contact fields, one friction pass of one
sweep, kick, drift, stop test, work) and of the whole one-sweep step of the default scheme
(projected leapfrog); the step timed in a loop of 500 steps (one process, min of 5) from a state
100 steps into the benchmark case of `rod3d_step.py` (reference rod, μ = 0.3, dead load
F⁰₆ + 5 N, sine mode-6 velocity 20 mm/s, 0.5 of the step limit); the rate = operations / time.
Then the friction pass alone at a converged pass's state, timed with 1 sweep (no loop), and with
2 and 4 sweeps forced (`friction_tol` 0): the cost of one sweep, of the rest of the pass, and
the kernels (fusions and unfused operations of the optimised HLO) one sweep runs. Then two
probes of this CPU: Horner polynomials (8 and 32 terms, 2 operations each) on float64 arrays of
64–4096 elements in a loop of 2000, the rate XLA's fused elementwise code reaches; and a chain
of kernels that XLA may not merge (`optimization_barrier` between two operations on arrays of
64–4000 elements), what one kernel costs at the sizes of the 3D rod's arrays (251 entries per
colour and 501 nodes at 500 segments).

    python benchmarks/rod3d_flops.py            # n = 60, 120, 500 (~1 min)
    python benchmarks/rod3d_flops.py --n 500
"""

from __future__ import annotations

import argparse
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402


def _ops(f, *args) -> float:
    ca = jax.jit(f).lower(*args).compile().cost_analysis()
    ca = ca[0] if isinstance(ca, list) else ca
    return float(ca.get("flops", 0.0))


def _loop_time(body, init, K: int) -> float:
    """Seconds per iteration of `body` in a compiled loop of K (min of 5 after a warm-up)."""
    f = jax.jit(lambda c: jax.lax.fori_loop(0, K, lambda i, c: body(c), c))
    jax.block_until_ready(f(init))
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        jax.block_until_ready(f(init))
        best = min(best, time.perf_counter() - t0)
    return best / K


def _case(n: int, **model_kw):
    """The benchmark case of `rod3d_step.py` at `n` segments, 100 steps in (the model made with
    `model_kw`): `(make, q, v, a, dt, integ)`, `make(**kw)` a model of the case."""
    from jaxrod import theory
    from jaxrod.integrators import ProjectedLeapfrog
    from jaxrod.params import RodChannel
    from jaxrod.rod3d import Rod3D, sine_velocity, step_limit

    rod = RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0

    def make(**kw):
        return Rod3D(rod, n, control="load", end_load=F, **kw)

    model = make(**model_kw)
    q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, 20e-3))
    dt = 0.5 * float(step_limit(model, q))
    integ = ProjectedLeapfrog(dt)
    a = model.accelerations(q, v, 0.0)
    stepj = jax.jit(lambda q, v, a: integ.step(model, q, v, a, 1.0, dt)[:3])
    for _ in range(100):
        q, v, a = stepj(q, v, a)
    return make, q, v, a, dt, integ


def step_rows(n: int) -> list[dict]:
    from jaxrod.rod3d.contact import friction_table

    make, q, v, a, dt, integ = _case(n, friction_sweeps=1)
    model = make(friction_sweeps=1)
    pieces = {
        "forces": (lambda q, v: model.forces(q.x, q.Q, v.v), q, v),
        "contact fields": (lambda q: friction_table(model, q.x, q.Q, a.N), q),
        "friction pass (1 sweep)": (lambda v, a: model.friction_update(integ.friction, v, v, dt, 0.0, q, a), v, a),
        "kick": (lambda v, a: model.kick(q, v, a, dt), v, a),
        "drift": (lambda q, v: model.drift(q, v, dt), q, v),
        "stop test": (lambda q, v: model.stop_measures(q, v, a), q, v),
        "work": (lambda v: model.impulse_work(v, v, v, a, dt), v),
    }
    rows = [dict(n=n, piece=k, ops_per_node=_ops(f, *args) / (n + 1)) for k, (f, *args) in pieces.items()]
    ops = _ops(lambda q, v, a: integ.step(model, q, v, a, 1.0, dt)[:3], q, v, a)
    sec = _loop_time(lambda c: integ.step(model, *c, 1.0, dt)[:3], (q, v, a), 500)
    rows.append(dict(n=n, piece="whole step", ops_per_node=ops / (n + 1), us=sec * 1e6, gflops=ops / sec / 1e9))
    return rows


def pass_rows(n: int) -> list[dict]:
    """The friction pass at the benchmark case's state after 100 steps: µs for 1 (no loop), 2
    and 4 sweeps (forced) and the kernels of one sweep."""
    import re

    from rod3d_step import hlo_computations, kernels

    make, q, v, a, dt, integ = _case(n)
    us = {}
    for sweeps in (1, 2, 4):
        m = make(friction_sweeps=sweeps, friction_tol=0.0)
        body = lambda c, m=m: (c[0], m.friction_update(integ.friction, c[1], c[1], dt, 0.0, c[0], c[2]), c[2])
        us[sweeps] = _loop_time(body, (q, v, a), 500) * 1e6
    text = jax.jit(lambda v, a: m.friction_update(integ.friction, v, v, dt, 0.0, q, a)).lower(v, a).compile().as_text()
    sweep_body = re.search(r"while\(.*body=%?([\w.\-]+)", text).group(1)  # the one loop: the sweeps
    per_sweep = (us[4] - us[2]) / 2
    return [dict(n=n, us_1=us[1], us_2=us[2], us_4=us[4], per_sweep=per_sweep, rest=us[2] - 2 * per_sweep,
                 sweep_kernels=kernels(hlo_computations(text), sweep_body))]


def kernel_rows() -> list[dict]:
    """What one kernel costs: chains of 10 and 110 kernels (x·a + b, then a barrier XLA may not
    fuse across) on float64 arrays, the difference per kernel."""
    rows = []
    for size in (64, 251, 501, 1000, 4000):
        def chain(count, size=size):
            def body(x):
                for _ in range(count):
                    x = jax.lax.optimization_barrier(x * 1.0000001 + 1e-9)
                return x
            return _loop_time(body, jnp.ones(size), 2000)

        rows.append(dict(size=size, ns=(chain(110) - chain(10)) / 100 * 1e9))
    return rows


def probe_rows() -> list[dict]:
    rows = []
    for size in (64, 128, 512, 4096):
        for terms in (8, 32):
            def body(x, terms=terms):
                y = jnp.zeros_like(x)
                for k in range(terms):
                    y = y * x + (1.0 / (k + 1))
                return x + 1e-30 * y

            sec = _loop_time(body, jnp.linspace(0.1, 0.9, size), 2000)
            rows.append(dict(size=size, terms=terms, gflops=size * (2 * terms + 2) / sec / 1e9))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="*", default=[60, 120, 500])
    args = ap.parse_args()
    for n in args.n:
        for r in step_rows(n):
            extra = f"   {r['us']:.1f} us per step, {r['gflops']:.1f} GFlop/s" if "us" in r else ""
            print(f"n = {n:4d}  {r['piece']:24s} {r['ops_per_node']:7.0f} operations per node{extra}", flush=True)
    for n in args.n:
        for r in pass_rows(n):
            print(f"n = {n:4d}  friction pass: {r['us_1']:.1f} us with 1 sweep (no loop), {r['us_2']:.1f} with 2, "
                  f"{r['us_4']:.1f} with 4: {r['per_sweep']:.1f} us per sweep ({r['sweep_kernels']} kernels), "
                  f"{r['rest']:.1f} us for the rest of a looped pass", flush=True)
    for r in probe_rows():
        print(f"probe: {r['terms']:2d}-term Horner on {r['size']:5d} float64: {r['gflops']:5.1f} GFlop/s", flush=True)
    for r in kernel_rows():
        print(f"probe: one kernel (2 operations) on {r['size']:5d} float64: {r['ns']:5.0f} ns", flush=True)


if __name__ == "__main__":
    main()
