"""How the implicit leapfrog's answer moves with its step: E3's v₀* of the 3D rod by label
bisection (reference rod, μ = 0.3, dead load F⁰₆ + ΔF, sine mode 6, 0.4 s horizon) for each
(segments, ΔF, step, γ), against the explicit scheme's committed value
(results/paper/e3/rod3d_boundary_n{60,500}*.csv). The accuracy half of the work–precision
question of issue [implicit3d]; wall time of each search (compilation included) beside it.

Rows go to `benchmarks/results/rod3d_implicit_vstar.csv`.

    python benchmarks/rod3d_implicit_vstar.py            # the committed table (~6 min)
    python benchmarks/rod3d_implicit_vstar.py --only 60  # the 60-segment rows
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import jaxrod as jr  # noqa: E402
from jaxrod.experiments.e3.rod3d import label_3d  # noqa: E402
from jaxrod.integrators import SCHEMES, ImplicitLeapfrog  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_implicit_vstar.csv")

# the explicit leapfrog's v₀* [mm/s] (results/paper/e3/rod3d_boundary_n60_leapfrog.csv, _n500.csv)
EXPLICIT = {(60, 5.0): 26.192, (60, 20.0): 8.318, (500, 5.0): 27.125, (500, 20.0): 8.235,
            (500, 60.0): 4.260}  # 60 N at 500 segments: rod3d_boundary_n500_leapfrog.csv

CASES = [  # (segments, ΔF [N], step [s], γ)
    *((60, 5.0, dt, 0.0) for dt in (1.5e-5, 3e-5, 6e-5, 1e-4, 3e-4)),
    *((60, 5.0, dt, 0.1) for dt in (1e-4, 3e-4)),
    *((60, 5.0, dt, 0.5) for dt in (3e-5, 1e-4, 3e-4)),
    *((60, 20.0, dt, 0.1) for dt in (5e-5, 1e-4, 3e-4)),
    *((500, 5.0, dt, 0.1) for dt in (1e-4, 5e-5)),
    *((500, 20.0, dt, 0.1) for dt in (1e-4, 5e-5, 3e-5)),
    (500, 20.0, 1e-4, 0.5),
    (500, 60.0, 2e-5, 0.1),  # past the wall's wrinkling load (at 5e-5 s every amplitude buckles)
]


def bisect(label, dF, lo, hi, rtol=2e-3):
    """A bracket [a, b] of v₀* (label 0 at a, 1 at b) to b/a − 1 ≤ rtol, widened by 10 % steps as
    needed; `None` if a run failed (non-finite)."""
    runs = 0

    def lab(v):
        nonlocal runs
        runs += 1
        return float(label(dF, v))

    a, b = lo, hi
    la, lb = lab(a), lab(b)
    while la == 1.0:
        b, a = a, a / 1.1
        la = lab(a)
    while lb == 0.0:
        a, b = b, b * 1.1
        lb = lab(b)
    if la != la or lb != lb:
        return None, runs
    while b / a - 1 > rtol:
        m = (a * b) ** 0.5
        lm = lab(m)
        if lm != lm:
            return None, runs
        a, b = (a, m) if lm == 1.0 else (m, b)
    return (a, b), runs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", type=int, nargs="*", help="segment counts to run")
    ap.add_argument("--dF", type=float, nargs="*", help="loads to run [N]")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rod = jr.RodChannel.reference(0.3)
    rows = []
    for n, dF, dt, gamma in CASES:
        if (args.only and n not in args.only) or (args.dF and dF not in args.dF):
            continue
        SCHEMES["implicit_g"] = lambda h, g=gamma: ImplicitLeapfrog(h, gamma=g)
        label = label_3d(rod, n, dt, 0.4, scheme="implicit_g")
        ref = EXPLICIT[n, dF]
        t0 = time.perf_counter()
        br, runs = bisect(label, dF, 0.97e-3 * ref, 1.02e-3 * ref)
        sec = time.perf_counter() - t0
        mid = (br[0] * br[1]) ** 0.5 * 1e3 if br else float("nan")
        rows.append(dict(commit=commit, n_segments=n, dF=dF, dt=dt, gamma=gamma, explicit_mm_s=ref,
                         lo_mm_s=round(1e3 * br[0], 3) if br else "", hi_mm_s=round(1e3 * br[1], 3) if br else "",
                         v_star_mm_s=round(mid, 3), difference_percent=round(100 * (mid / ref - 1), 2),
                         failed=br is None, runs=runs, seconds=round(sec, 1)))
        print(rows[-1], flush=True)
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    if os.path.exists(OUT):  # rows of other cases are kept; a rerun replaces its own
        key = lambda r: (int(r["n_segments"]), float(r["dF"]), float(r["dt"]), float(r["gamma"]))
        with open(OUT, newline="") as fh:
            done = {key(r) for r in rows}
            rows = [r for r in csv.DictReader(fh) if key(r) not in done] + rows
    write_csv(OUT, rows)


if __name__ == "__main__":
    main()
