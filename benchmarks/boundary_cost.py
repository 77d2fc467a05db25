"""Cost of one boundary point: safeguarded Newton vs bisection vs a grid of equal resolution.

Single-mode model (exact solution, P6 root) and field model (n = 64, sine mode 6), reference
rod, mu = 0.3, from the bracket [v/2.7, 3.6v] around the answer v (a factor 9.7, asymmetric so that no
bisection step lands on v by construction). "Equal resolution"
means every method ends with the root known to the same relative width `rtol`; a grid needs
ln(9.7)/rtol log-spaced points for that. Model evaluations are counted (a Newton evaluation is
one forward-mode run) and wall time measured after compilation (min of 3).

    python benchmarks/boundary_cost.py
"""

from __future__ import annotations

import csv
import math
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402
from jaxrod import theory as th  # noqa: E402


def timed(fn):
    jax.block_until_ready(fn())
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return out, best


def main():
    rod = jr.RodChannel.reference(mu=0.3)
    rows = []
    for model, rtol in (("mode", 1e-6), ("mode", 1e-9), ("field", 1e-4), ("field", 1e-6)):
        for dF in (5.0, 20.0):
            if model == "mode":
                k = th.stiffness(rod, 6, th.frictionless_load(rod, 6) + dF)
                f = th.friction_amplitude(rod)
                v = float(rod.R * th.velocity_intercept(k, f))
                g = lambda x, k=k, f=f: bd.single_mode_indicator(x / rod.R, k, f, f)
            else:
                sc = lambda x, dF=dF: jr.scene.Scene(rod, dF, jr.SineVelocity(x, 6.0), "field", 64, 6, 2.6e-4)
                g = lambda x, sc=sc: bd.rod_indicator(sc(x))
                v = float(bd.bisection(g, 1e-3, 0.2, rtol=1e-12).root)
            lo, hi = v / 2.7, 3.6 * v  # a factor 9.7, asymmetric: no bisection lands on v
            newton = jax.jit(lambda: bd.safeguarded_newton(g, lo, hi, rtol, 200))
            bis = jax.jit(lambda: bd.bisection(g, lo, hi, rtol=rtol))
            n_grid = math.ceil(math.log(9.72) / rtol)
            r_n, t_n = timed(newton)
            r_b, t_b = timed(bis)
            # the grid: evaluate a chunk of it and scale (a full grid at 1e-6 is 2.2e6 runs)
            chunk = jnp.geomspace(lo, hi, min(n_grid, 256))
            _, t_chunk = timed(jax.jit(lambda: jax.vmap(g)(chunk)))
            t_grid = t_chunk * n_grid / len(chunk)
            for meth, evals, t, root in (("newton", int(r_n.evaluations), t_n, float(r_n.root)),
                                         ("bisection", int(r_b.evaluations), t_b, float(r_b.root)),
                                         ("grid (extrapolated)", n_grid, t_grid, math.nan)):
                rows.append(dict(model=model, dF=dF, rtol=rtol, method=meth, evaluations=evals,
                                 seconds=t, root_rel_err=abs(root / v - 1) if root == root else None))
                print(f"{model:5s} dF={dF:4g} rtol={rtol:.0e} {meth:20s} evals={evals:8d} time={t:9.4f}s")
    os.makedirs("benchmarks/results", exist_ok=True)
    with open("benchmarks/results/boundary_cost.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
