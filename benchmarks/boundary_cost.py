"""Cost of the boundary: the departure-rate search against label bisection and the grid map.

Field model, reference rod, μ = 0.3, sine mode-6 velocity perturbation (the E3 scene), run on
this machine side by side in one process, wall times after compilation (best of 3):

- **evaluations**: runs per boundary point at rtol 1e-6 for 20 loads from 1 to 60 N — the
  departure search along the curve (each point started from its neighbours' prediction, in a
  bracket of a factor 4 either side of it), label bisection from a bracket as wide, and the departure search with no prediction from the wide
  bracket [1e-4, 1] m/s;
- **wall time**: the E3 boundary curve (20 loads, 1 to 64 N, rtol 1e-3) with and without the
  IFT sensitivities, against the 480-point grid map of `jaxrod map` (20 × 24, one μ);
- **E4**: the critical-load curve of 8 μ × 8 random velocity perturbations (15 mm/s, n = 128)
  by the departure search, against the previous release's Newton iteration on max|θ(0.5 s)|;
- **the 3D rod** (`--rod3d N ...`, alone): v₀* at ΔF = 5 N, rtol 1e-2, by the departure search on
  its node positions and by label bisection, at N segments, from [1e-4, 1] m/s and from the
  field model's v₀* (bracket a factor 2 either side): runs, root, bracket and wall time
  (`benchmarks/results/boundary_cost_rod3d.csv`).

Writes `benchmarks/results/boundary_cost.csv` (plain numbers).

    python benchmarks/boundary_cost.py [--skip-e4]
    python benchmarks/boundary_cost.py --rod3d 12 60 120 [--method bisection]  # other rows are kept
"""

from __future__ import annotations

import argparse
import math
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402
from jaxrod.output import write_csv  # noqa: E402
from jaxrod.stability_map import stability_map  # noqa: E402

ROD = jr.RodChannel.reference(mu=0.3)
OUT = os.path.join(os.path.dirname(__file__), "results")


def best_of(fn, repeats=3):
    out = fn()
    jax.block_until_ready(out)
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return out, best


def evaluations(rows):
    dFs = np.geomspace(1.0, 60.0, 20)
    t0 = time.perf_counter()
    curve, _ = bd.boundary_curve(ROD, dFs, rtol=1e-6, sensitivities=())
    t_curve = time.perf_counter() - t0
    wide, _ = bd.boundary_curve(ROD, dFs, rtol=1e-6, sensitivities=(), continuation=False)
    # label bisection from the bracket the continuation used (a factor 4 around the prediction)
    bis_evals, bis_err = [], []
    for i, dF in enumerate(dFs):
        sc = jr.scene.Scene(ROD, float(dF), kind="field")
        n, dt = sc.size(), sc.step()
        label = lambda v, dF=dF, n=n, dt=dt: bd.crossing_state(
            jr.scene.Scene(ROD, dF, jr.SineVelocity(v, 6.0), "field", n, 6, dt))[1]
        pred = float(curve.root[i])  # a bracket as wide as the search's (a factor 16), asymmetric
        lo, hi = pred / 2.7, pred * 16 / 2.7
        b = jax.jit(lambda lo, hi: bd.bisection(label, lo, hi, rtol=1e-6))(lo, hi)
        bis_evals.append(int(b.evaluations))
        bis_err.append(abs(float(b.root) / pred - 1))
    for i, dF in enumerate(dFs):
        rows.append(dict(part="evaluations", dF=dF, v0_star=float(curve.root[i]),
                         departure_curve=int(curve.evaluations[i]), departure_wide=int(wide.evaluations[i]),
                         bisection=bis_evals[i], relative_gap_to_bisection=bis_err[i]))
    print(f"evaluations per point at rtol 1e-6, mean over {len(dFs)} loads 1..60 N: departure along the "
          f"curve {np.mean(curve.evaluations):.2f} (max {int(np.max(curve.evaluations))}), departure from "
          f"[1e-4, 1] {np.mean(wide.evaluations):.2f}, label bisection {np.mean(bis_evals):.2f}; "
          f"largest gap between the two roots {max(bis_err):.1e} (curve {t_curve:.1f} s incl. compilation)")


def wall_time(rows):
    dFs = np.geomspace(1.0, 64.0, 20)
    bare, t_bare = best_of(lambda: bd.boundary_curve(ROD, dFs, rtol=1e-3, sensitivities=())[0].root)
    _, t_sens = best_of(lambda: bd.boundary_curve(ROD, dFs, rtol=1e-3)[0].root)
    args = dict(mus=(0.3,), dF=np.geomspace(0.5, 64.0, 20), v0=np.geomspace(1e-3, 0.2, 24), out=None,
                progress=False, curve_rtol=None)  # the grid alone
    _, t_map = best_of(lambda: stability_map(**args))
    rows += [dict(part="wall", what="boundary curve, 20 loads, rtol 1e-3", seconds=t_bare),
             dict(part="wall", what="boundary curve + sensitivities (mu, dF)", seconds=t_sens),
             dict(part="wall", what="grid map 20 x 24 (jaxrod map, one mu)", seconds=t_map)]
    print(f"E3 boundary, after compilation: curve {t_bare:.2f} s ({t_sens:.2f} s with dv0*/dmu, dv0*/ddF); "
          f"grid map 480 points {t_map:.2f} s (its boundary known to a grid cell, a factor "
          f"{(0.2 / 1e-3) ** (1 / 23):.2f} in v0)")


def e4(rows):
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    mus = np.geomspace(0.05, 0.9, 8)
    R, n, amp = 8, 128, 15e-3
    dt = Scene(ROD.with_friction(0.9), 100.0, kind="field", n=n).step()
    kw = dict(perturbation="random-velocity", realizations=R, seed=4, n=n, dt=dt, rtol=1e-4, bracket=(1e-2, 100.0),
              sensitivities=())
    new, t_new = best_of(lambda: bd.critical_load_curve(mus, amp, **kw)[0], repeats=1)

    def old_one(mu, r, i):  # the previous release: Newton on log max|θ(0.5 s)| in log ΔF
        rod = jr.RodChannel.reference(mu=mu)
        key = jax.random.fold_in(jax.random.key(4), i * R + r)
        pert = make_perturbation("random-velocity", amp, 6, key)
        g = lambda y: bd.rod_indicator(Scene(rod, jnp.exp(y), pert, "field", n, 6, dt), 0.5)
        return bd.safeguarded_newton(g, jnp.log(1e-2), jnp.log(100.0), 1e-4, 60, geometric=False)

    run = jax.jit(jax.vmap(jax.vmap(old_one, (None, 0, None)), (0, None, 0)))
    old, t_old = best_of(lambda: run(jnp.asarray(mus), jnp.arange(R), jnp.arange(len(mus))), repeats=1)
    ok = (np.asarray(new.result) == 0) & (np.asarray(old.result) == 0)
    gap = np.abs(np.log(np.asarray(new.root)[ok]) - np.asarray(old.root)[ok])
    rows += [dict(part="e4", what="departure", seconds=t_new, mean_evaluations=float(np.mean(new.evaluations)),
                  converged=int(np.sum(np.asarray(new.result) == 0))),
             dict(part="e4", what="newton on max|theta(0.5 s)|", seconds=t_old,
                  mean_evaluations=float(np.mean(old.evaluations)), converged=int(np.sum(np.asarray(old.result) == 0)),
                  median_log_gap=float(np.median(gap)) if gap.size else math.nan)]
    print(f"E4 critical-load curve 8 mu x 8 realizations (n = {n}, rtol 1e-4), after compilation: departure "
          f"{t_new:.1f} s ({np.mean(new.evaluations):.1f} runs per point), previous Newton {t_old:.1f} s "
          f"({np.mean(old.evaluations):.1f} runs per point); median |log ratio| of their roots "
          f"{np.median(gap) if gap.size else math.nan:.1e} (the old indicator's root lies above the 2 s label boundary)")


def rod3d(segments, methods=("bisection", "departure")):
    """The 3D rod's v₀* at ΔF = 5 N, rtol 1e-2, by both methods, from the wide bracket and from
    the field model's v₀* (a prediction: bracket a factor 2 either side, first run there)."""
    vf = float(bd.critical_velocity(ROD, 5.0, model="field", rtol=1e-4, sensitivities=())[0].root)
    print(f"field model v0* = {1e3 * vf:.3f} mm/s (the prediction)", flush=True)
    rows = []
    for n in segments:
        for method in methods:  # one compiled search per method and n
            for name, bracket, start in (("wide", (1e-4, 1.0), None), ("predicted", (vf / 2, 2 * vf), vf)):
                t0 = time.perf_counter()
                r = jax.block_until_ready(bd.critical_velocity(
                    ROD, 5.0, model="rod3d", n=n, rtol=1e-2, method=method, bracket=bracket, start=start,
                    sensitivities=())[0])
                dt = time.perf_counter() - t0
                rows.append(dict(dF=5.0, mu=0.3, rtol=1e-2, segments=n, method=method, bracket=name, result=int(r.result), runs=int(r.evaluations),
                                 root=float(r.root), lo=float(r.lo), hi=float(r.hi), wall_s=dt, v0_field=vf))
                print(f"3D rod, {n} segments, {method}, {name} bracket: {int(r.evaluations)} runs, "
                      f"v0* = {1e3 * float(r.root):.3f} mm/s in [{1e3 * float(r.lo):.3f}, {1e3 * float(r.hi):.3f}], "
                      f"{dt:.1f} s" + (" (with the method's compilation)" if name == "wide" else ""), flush=True)
    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, "boundary_cost_rod3d.csv")
    if os.path.exists(path):  # the rows of other segment counts and methods are kept
        import csv

        with open(path) as fh:
            rows = [r for r in csv.DictReader(fh) if int(r["segments"]) not in segments or r["method"] not in methods] + rows
    write_csv(path, sorted(rows, key=lambda r: int(r["segments"])))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--skip-e4", action="store_true")
    p.add_argument("--rod3d", type=int, nargs="+", metavar="N", help="only the 3D rod's search, at N segments")
    p.add_argument("--method", choices=("bisection", "departure"), help="with --rod3d: only this method")
    a = p.parse_args()
    print(f"{jax.local_device_count()} device(s), {jax.devices()[0].platform}")
    if a.rod3d:
        return rod3d(a.rod3d, (a.method,) if a.method else ("bisection", "departure"))
    rows = []
    evaluations(rows)
    wall_time(rows)
    if not a.skip_e4:
        e4(rows)
    os.makedirs(OUT, exist_ok=True)
    keys = sorted({k for r in rows for k in r})
    write_csv(os.path.join(OUT, "boundary_cost.csv"), [{k: r.get(k, math.nan) for k in keys} for r in rows])
    print("wrote benchmarks/results/boundary_cost.csv")


if __name__ == "__main__":
    main()
