"""3D rod, E1: is the explicit step limited by accuracy or by stability, and what would an
implicit step have to beat?

Measured in one run (float64, this machine's CPU):

1. the E1 critical force (μ = 0.3, v₀ = 15 mm/s, pushed at 1 mm/s) at dt = 0.9, 0.5 and 0.25 of
   the explicit limit 2/ω_max, and the wall time of each run (compile excluded: the same call
   is made twice and the second is timed);
2. the cost of one explicit step (kick–prox–drift–kick–prox, from the timed runs, over the
   steps actually taken) against the cost of one Newton iteration of an implicit step on the
   same rod, without the friction solve it would also need: the Jacobian of the forces with
   respect to the 3(n+1) positions and 3n rotations (`jax.jacfwd`) and one dense LU solve with
   it (`jnp.linalg.solve`), jitted, min over repeats; the Jacobian alone is timed too;
3. the contact vibration a step must still resolve (or damp): the Hertz spring under the rod's
   own weight, ω_c = √(1.5 k δ^{1/2} l̄ / m) at the static sag δ, and its period.

The break-even step ratio is (Newton iteration cost / explicit step cost): an implicit scheme
taking that many times the explicit step with a single Newton iteration per step would only
tie. Writes `benchmarks/results/rod3d_step_choice.csv` and prints a Markdown table.

    python benchmarks/rod3d_step_choice.py            # ~3.5 min on 2 CPU cores
    python benchmarks/rod3d_step_choice.py --quick    # 30 segments
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.rod3d import Rod3D, step_limit  # noqa: E402
from jaxrod.rod3d import sine_velocity  # noqa: E402
from jaxrod.experiments.rod3d import e1_curves  # noqa: E402
from jaxrod.rod3d.so3 import skew  # noqa: E402


def newton_iteration_cost(model, state, repeats=5):
    """Wall time [s] of the Jacobian of the forces in (x, φ) plus one dense solve with the
    backward-Euler matrix M/h² − ∂f/∂q (the least one Newton iteration of an implicit step costs)."""
    n1 = model.n + 1
    q, v = state

    def residual(q):
        x = q[: 3 * n1].reshape(n1, 3)
        phi = q[3 * n1:].reshape(model.n, 3)
        Q = q.Q - jnp.einsum("jab,jbc->jac", skew(phi), q.Q)
        f, tau, _, _ = model.forces(x, Q, v.v)
        return jnp.concatenate([f.ravel(), tau.ravel()])

    h = 10.0 * step_limit(model, q)  # the step size does not change the cost
    M = jnp.concatenate([jnp.repeat(model.mass, 3), jnp.tile(model.inertia, model.n)])

    @jax.jit
    def iteration(q):
        # backward Euler on M q̈ = f(q): (M/h² − ∂f/∂q) Δq = f(q) + (inertial terms, omitted)
        J = jax.jacfwd(residual)(q)
        A = jnp.diag(M / h**2) - J
        return jnp.linalg.solve(A, residual(q))

    @jax.jit
    def jacobian_only(q):
        return jax.jacfwd(residual)(q)

    q0 = jnp.concatenate([q.x.ravel(), jnp.zeros(3 * model.n, q.x.dtype)])

    def best_of(fn):
        jax.block_until_ready(fn(q0))
        best = math.inf
        for _ in range(repeats):
            t = time.perf_counter()
            jax.block_until_ready(fn(q0))
            best = min(best, time.perf_counter() - t)
        return best

    return best_of(iteration), best_of(jacobian_only), int(q0.size)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    n = 30 if args.quick else 60
    rod = jr.RodChannel.reference(0.3)
    rows = []
    for frac in (0.9, 0.5, 0.25):
        # warm-up: the same call (steps per save and saves are static: any other call compiles anew)
        t = time.perf_counter()
        e1_curves(0.3, (15e-3,), n=n, t1=0.4, n_save=401, dt_fraction=frac)
        first = time.perf_counter() - t
        t = time.perf_counter()
        r = e1_curves(0.3, (15e-3,), n=n, t1=0.4, n_save=401, dt_fraction=frac)
        wall = time.perf_counter() - t
        steps = int(r["steps"][0])  # steps taken (the run stops once the rod has buckled)
        rows.append(dict(n=n, dt_fraction=frac, dt=r["dt"], critical_force_N=float(r["critical_force"][0]),
                         wall_s=wall, first_call_s=first, steps=steps, us_per_step=1e6 * wall / steps))
        print(f"dt = {frac} x limit: F_cr = {rows[-1]['critical_force_N']:.6f} N, {wall:.1f} s", flush=True)
    model = Rod3D(rod, n, control="displacement", speed=1e-3)
    s0 = model.initial_state(0.0, lateral_velocity=sine_velocity(model, 15e-3))
    t_newton, t_jac, dof = newton_iteration_cost(model, s0)
    sag = float(model.static_sag())
    k = float(model.contact_stiffness)
    omega_c = math.sqrt(1.5 * k * math.sqrt(sag) * float(model.l0) / float(model.mass[1]))
    ref = rows[-1]["critical_force_N"]
    step_us = min(r["us_per_step"] for r in rows)
    for r in rows:
        r.update(F_error_vs_quarter_limit_N=r["critical_force_N"] - ref, newton_iteration_us=1e6 * t_newton,
                 jacobian_us=1e6 * t_jac, dof=dof,
                 break_even_step_ratio=1e6 * t_newton / step_us, contact_omega_rad_s=omega_c,
                 contact_period_s=2 * math.pi / omega_c, explicit_limit_s=float(step_limit(model, s0[0])))
    os.makedirs(os.path.join(os.path.dirname(__file__), "results"), exist_ok=True)
    path = os.path.join(os.path.dirname(__file__), "results", "rod3d_step_choice.csv")
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\n{n} segments, {dof} unknowns; explicit limit {rows[0]['explicit_limit_s']:.3g} s; "
          f"contact vibration {omega_c:.4g} rad/s (period {2 * math.pi / omega_c:.3g} s)")
    print("| dt / limit | dt [s] | E1 critical force [N] | − value at 0.25 [N] | wall [s] | µs/step |")
    print("|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['dt_fraction']} | {r['dt']:.3g} | {r['critical_force_N']:.6f} | {r['F_error_vs_quarter_limit_N']:+.2e} "
              f"| {r['wall_s']:.1f} | {r['us_per_step']:.1f} |")
    print(f"\nOne Newton iteration (Jacobian by jacfwd + dense solve, {dof} unknowns): {1e6 * t_newton:.0f} µs "
          f"(the Jacobian alone {1e6 * t_jac:.0f} µs) = {rows[0]['break_even_step_ratio']:.0f} explicit steps; "
          f"a contact period is {2 * math.pi / omega_c / rows[0]['explicit_limit_s']:.0f} explicit limits; wrote {path}")


if __name__ == "__main__":
    main()
