"""E4 with the 3D rod on this CPU: ΔF* of a sine (E4 A, 15 mm/s, mode 6) and a random velocity
(E4 B, ±15 mm/s on the scene's 500-segment noise grid, realization 0 of `critical_load_curve`'s
keys, or `--realization r`) at the segment counts given, by label bisection to rtol 1e-2 in a
bracket a factor `--width` (8) either side of the field model's ΔF* (first and last runs are its ends). Every point is appended to
`resolution.csv` as it finishes (commit, date, wall time with compilation).

    python studies/paper/e4/rod3d/resolution.py --mu 0.05 --cases A B --n 60 120 240

The question (issue [paper3d], reason (A)): at small μ the field model's random-velocity ΔF* is
4.4× the sine's, where the paper finds them close. Does the 3D rod close that gap, and how many
segments does its ΔF* need?"""

from __future__ import annotations

import argparse
import csv
import datetime
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
PERTURBATION = {"A": "sine", "B": "random-velocity"}
COLUMNS = ["case", "mu", "realization", "model", "n", "dF_star", "lo", "hi", "runs", "result", "wall_s", "commit", "date"]


def _commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    except OSError:
        return ""


def point(case, mu, model, n, bracket, method, realization=0):
    key = jax.random.fold_in(jax.random.key(0), realization)  # critical_load_curve's realization r of μ index 0
    rod = jr.RodChannel.reference(mu=mu)
    t0 = time.perf_counter()
    r, _ = bd.critical_load(rod, 15e-3, model=model, perturbation=PERTURBATION[case], key=key, n=n, bracket=bracket,
                            rtol=1e-2 if model == "rod3d" else 1e-4, method=method, sensitivities=())
    r = jax.block_until_ready(r)
    return r, time.perf_counter() - t0


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mu", type=float, default=0.05)
    p.add_argument("--cases", nargs="+", choices=("A", "B"), default=["A", "B"])
    p.add_argument("--n", type=int, nargs="+", default=[60, 120, 240])
    p.add_argument("--realization", type=int, default=0, help="the random velocity's realization r (key fold_in(key(0), r))")
    p.add_argument("--width", type=float, default=8.0, help="the 3D bracket: the field model's ΔF* divided and multiplied by it")
    a = p.parse_args()
    path = os.path.join(HERE, "resolution.csv")
    new = not os.path.exists(path)
    with open(path, "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        if new:
            w.writeheader()
        for case in a.cases:
            field, sec = point(case, a.mu, "field", None, (0.01, 100.0), None, a.realization)
            f = float(field.root)
            print(f"E4 {case}, mu = {a.mu:g}: field model dF* = {f:.4g} N ({sec:.0f} s)", flush=True)
            rows = [dict(case=case, mu=a.mu, realization=a.realization, model="field", n="", dF_star=f, lo=float(field.lo),
                         hi=float(field.hi), runs=int(field.evaluations), result=int(field.result), wall_s=round(sec, 1))]
            for n in a.n:
                r, sec = point(case, a.mu, "rod3d", n, (f / a.width, a.width * f), "bisection", a.realization)
                print(f"  3D rod, {n} segments: dF* = {float(r.root):.4g} N in [{float(r.lo):.4g}, {float(r.hi):.4g}], "
                      f"{int(r.evaluations)} runs, result {int(r.result)}, {sec:.0f} s", flush=True)
                rows.append(dict(case=case, mu=a.mu, realization=a.realization, model="rod3d", n=n, dF_star=float(r.root),
                                 lo=float(r.lo), hi=float(r.hi), runs=int(r.evaluations), result=int(r.result),
                                 wall_s=round(sec, 1)))
                for row in rows:
                    w.writerow({**row, "commit": _commit(), "date": datetime.date.today().isoformat()})
                fh.flush()
                rows = []
            for row in rows:
                w.writerow({**row, "commit": _commit(), "date": datetime.date.today().isoformat()})


if __name__ == "__main__":
    main()
