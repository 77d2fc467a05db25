"""Convergence of the 3D rod's critical sine velocity in its number of segments (issue [rod3d]).

v₀* of the 3D rod (dead load F⁰₆ + ΔF, μ = 0.3, friction at the contact point, pinned ends) by
`jaxrod.experiments.rod3d.crosscheck_critical_velocity` (two vmapped rounds of 9 amplitudes,
the second zoomed into the first's bracket), next to the field model's converged boundary
search, for each (ΔF, n) given. Appends one row per case to `v0_segments.csv` beside this file
(plain numbers; the parameters in the columns).

    python studies/paper/e6/v0_segments.py --dF 5 20 --n 120
"""

from __future__ import annotations

import argparse
import csv
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

from jaxrod.experiments.rod3d import crosscheck_critical_velocity  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
COLUMNS = ["dF", "n_segments", "mu", "friction_at", "ends", "t1", "field_mm_s", "rod3d_mm_s", "bracket_lo_mm_s",
           "bracket_hi_mm_s", "difference_percent", "monotonic", "rod3d_runs", "seconds_rod3d"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dF", type=float, nargs="+", required=True)
    ap.add_argument("--n", type=int, nargs="+", required=True)
    ap.add_argument("--out", default=os.path.join(HERE, "v0_segments.csv"))
    args = ap.parse_args()
    new = not os.path.exists(args.out)
    for n in args.n:
        for dF in args.dF:
            t0 = time.perf_counter()
            (r,) = crosscheck_critical_velocity([dF], n=n)
            lo, hi = r["rod3d_bracket"] or (float("nan"), float("nan"))
            v3 = r["rod3d"] if r["rod3d"] is not None else float("nan")
            row = dict(dF=dF, n_segments=n, mu=0.3, friction_at="surface", ends="pinned", t1=0.4,
                       field_mm_s=1e3 * r["field"], rod3d_mm_s=1e3 * v3, bracket_lo_mm_s=1e3 * lo,
                       bracket_hi_mm_s=1e3 * hi, difference_percent=100 * (v3 / r["field"] - 1),
                       monotonic=int(r["monotonic"]), rod3d_runs=r["rod3d_runs"], seconds_rod3d=r["seconds_rod3d"])
            with open(args.out, "a", newline="") as fh:
                w = csv.DictWriter(fh, COLUMNS)
                if new:
                    w.writeheader()
                    new = False
                w.writerow(row)
            print(f"ΔF = {dF} N, n = {n}: 3D {row['rod3d_mm_s']:.3f} mm/s (bracket {row['bracket_lo_mm_s']:.3f}–"
                  f"{row['bracket_hi_mm_s']:.3f}), field {row['field_mm_s']:.3f}, {row['difference_percent']:+.1f} % "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
