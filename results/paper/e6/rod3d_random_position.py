"""E6C with the 3D rod on this CPU: the paper's random position perturbation (lateral forces
±2 N/m on the scene's noise grid for 1 ms, key 6 as `jaxrod reproduce e6`), μ = 0.9: ΔF* of that
realization by label bisection (rtol 1e-2, horizon 0.5 s as E6's field model, bracket a factor 4
around the field model's ΔF*), then 0.5-s runs at 1.05 ΔF* and at the paper's 40 N, and the
dominant mode of θ before (the first save) and at buckling, with its share of the power of the
first 40 modes (as `jaxrod.experiments.e6`). Every row is appended to
`rod3d_random_position.csv` with its commit, date and wall time.

    python results/paper/e6/rod3d_random_position.py --n 120 240

The question (issue [paper3d], reason (D)): the paper sees a single mode, m = 21; the field
model's buckled state is broadband (mode 21 with 21 % of the power at 1.05 ΔF*)."""

from __future__ import annotations

import argparse
import csv
import datetime
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402
from jaxrod.modal import modal_spectrum  # noqa: E402
from jaxrod.scene import Scene, make_perturbation  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
COLUMNS = ["n", "case", "dF", "dF_star", "dF_star_lo", "dF_star_hi", "search_runs", "search_result", "buckled",
           "t_stop", "mode_before", "mode_at_buckling", "power_share", "second_mode", "second_share", "wall_s",
           "commit", "date"]
T1 = 0.5


def _modes(theta, n_modes=40):
    p = np.asarray(modal_spectrum(jnp.asarray(theta), n_modes))
    order = np.argsort(p)[::-1]
    return int(order[0]) + 1, float(p[order[0]]), int(order[1]) + 1, float(p[order[1]])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[120])
    a = ap.parse_args()
    rod = jr.RodChannel.reference(mu=0.9)
    key = jax.random.key(6)
    pert = make_perturbation("random-position", 2.0, 6, key)
    field, _ = bd.critical_load(rod, 2.0, perturbation="random-position", key=key, t1=T1, bracket=(1e-3, 300.0),
                                rtol=1e-4, sensitivities=())
    f = float(field.root)
    print(f"field model dF* = {f:.4g} N", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    path = os.path.join(HERE, "rod3d_random_position.csv")
    new = not os.path.exists(path)
    with open(path, "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        if new:
            w.writeheader()
        for n in a.n:
            t0 = time.perf_counter()
            r, _ = bd.critical_load(rod, 2.0, model="rod3d", perturbation="random-position", key=key, n=n, t1=T1,
                                    bracket=(f / 4, 4 * f), rtol=1e-2, method="bisection", sensitivities=())
            dF_star, sec = float(r.root), time.perf_counter() - t0
            print(f"  {n} segments: dF* = {dF_star:.4g} N in [{float(r.lo):.4g}, {float(r.hi):.4g}], "
                  f"{int(r.evaluations)} runs, result {int(r.result)}, {sec:.0f} s", flush=True)
            for case, dF in (("1.05 dF*", 1.05 * dF_star), ("paper's 40 N", 40.0)):
                if not np.isfinite(dF):
                    continue
                t0 = time.perf_counter()
                sol = Scene(rod, dF, pert, "rod3d", n).run(t1=T1, n_save=501)
                theta = np.asarray(sol.observables["theta"])[:, 1:-1]
                ts = np.asarray(sol.ts)
                i = min(int(np.searchsorted(ts, float(sol.t_stop))), len(ts) - 1)
                before = _modes(theta[0])[0]
                m, share, m2, share2 = _modes(theta[i])
                row = dict(n=n, case=case, dF=dF, dF_star=dF_star, dF_star_lo=float(r.lo), dF_star_hi=float(r.hi),
                           search_runs=int(r.evaluations), search_result=int(r.result), buckled=int(sol.buckled),
                           t_stop=float(sol.t_stop), mode_before=before, mode_at_buckling=m, power_share=share,
                           second_mode=m2, second_share=share2, wall_s=round(sec + time.perf_counter() - t0, 1),
                           commit=commit, date=datetime.date.today().isoformat())
                w.writerow(row)
                fh.flush()
                print(f"    {case} = {dF:.4g} N: {'buckled' if sol.buckled else 'stable'} at {float(sol.t_stop):.3f} s, "
                      f"mode {before} -> {m} ({share:.2f}; next {m2}: {share2:.2f})", flush=True)


if __name__ == "__main__":
    main()
