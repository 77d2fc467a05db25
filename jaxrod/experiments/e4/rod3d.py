"""E4 with the full model: the critical load ΔF*(μ) of the 3D rod at the paper's 500 segments, beside the field model's (`jaxrod reproduce e4 --model rod3d`); the settings are in `jaxrod.experiments.paper3d`. docs/paper.md, "The experiments with the 3D rod", gives the method and the results."""

from __future__ import annotations

import math
import os
import time

import numpy as np

from ...output import subplots, write_csv
from ..paper3d import (WIDTH, E4_CASES, FIELD_TOP, FIELD_NODES, E4_COLUMNS, E5_COLUMNS, E6_COLUMNS, _settings, _Points, _critical_load, _best, _modes, _theta_3d, _final_theta, _found, _e4_points)

def e4_point(case, mu, realization, n, t1=0.5, width=WIDTH, rtol=1e-2) -> dict:
    """One E4 point: ΔF* [N] of the field model (to 1e-4) and of the 3D rod of `n` segments (label
    bisection to `rtol`, bracket a factor `width` either side of the field model's), for the sine
    15 mm/s (`case` "A"), the random velocity ±15 mm/s ("B") or the random position (forces
    ±2 N/m for 1 ms, "C") of `realization`; a row of `E4_COLUMNS` without commit and date."""
    import jax

    from ...params import RodChannel

    rod = RodChannel.reference(mu=mu)
    kind, amplitude = E4_CASES[case]
    key = jax.random.fold_in(jax.random.key(0), realization)
    f, sec_f = _critical_load(rod, amplitude, kind, key, "field", FIELD_NODES[case], t1, (0.01, FIELD_TOP[case]), 1e-4)
    f = float(f.root)
    r, sec = _critical_load(rod, amplitude, kind, key, "rod3d", n, t1, (f / width, f * width), rtol, "bisection")
    return dict(case=case, mu=float(mu), realization=realization, n=n, t1=float(t1), width=width, dF_star_field=f,
                dF_star=float(r.root), lo=float(r.lo), hi=float(r.hi), runs=int(r.evaluations), result=int(r.result),
                wall_s=round(sec + sec_f, 1))


def e4(out, quick=False, progress=True, n=None, mus=None) -> dict:
    """E4 A, B and C with the 3D rod at `n` segments: `rod3d_n{n}.csv` (one row per point) and
    `.png` (ΔF* against μ, both models) under `out`; `mus` a subset of the setting's μ to run.

    A point found in the CSV on the setting's horizon or a longer one is not run again (a run
    stable for the longer horizon is stable for the shorter; each point is reported on the
    longest horizon it has). A point whose 3D search found both ends of its bracket on one side
    (`invalid_bracket`) is run again with the bracket's width squared, up to `WIDTH`⁴."""
    from ...boundary.roots import ROOT_RESULTS

    s = _settings(quick, n)
    path = os.path.join(out, f"rod3d_n{s['n']}.csv")
    os.makedirs(out, exist_ok=True)
    done = _e4_points(path)
    cases = [("A", 0)] + [(c, r) for c in ("B", "C") for r in range(s["realizations"])]
    rows = []
    for mu in s["mus"] if mus is None else mus:
        for case, real in cases:
            row = _found(done, float(s["t1_e4"]), case, float(mu), real, s["n"])
            outside = row is not None and row["result"] == str(ROOT_RESULTS.invalid_bracket)
            if row is not None and not (outside and float(row["width"] or 0) < WIDTH ** 4):
                rows.append(row)
                continue
            width = float(row["width"]) ** 2 if outside else WIDTH
            while True:
                row = e4_point(case, mu, real, s["n"], s["t1_e4"], width, s["rtol"])
                done.add(row)
                if row["result"] != ROOT_RESULTS.invalid_bracket or width >= WIDTH ** 4:
                    break
                width **= 2  # the 3D rod's ΔF* outside the bracket: the bracket squared
            rows.append(done.rows[-1])
            if progress:
                print(f"  E4 {case}, mu = {mu:g}, realization {real}: 3D dF* = {row['dF_star']:.4g} N "
                      f"({row['runs']} runs, {row['wall_s']:.0f} s), field {row['dF_star_field']:.4g} N", flush=True)
    _plot_e4(rows, path[:-4] + ".png", s["n"])
    summary = {}
    for case in ("A", "B", "C"):
        for mu in s["mus"]:
            pts = [r for r in rows if r["case"] == case and float(r["mu"]) == float(mu) and int(r["result"]) == 0]
            if pts:
                summary[f"{case} mu={mu:g}"] = dict(rod3d=[float(r["dF_star"]) for r in pts],
                                                    field=[float(r["dF_star_field"]) for r in pts])
    return dict(n=s["n"], width=WIDTH, points=summary)


def _plot_e4(rows, path, n):
    fig, ax = subplots(figsize=(6.4, 4.2))
    for case, color in (("A", "C0"), ("B", "C3"), ("C", "C2")):
        pts = [r for r in rows if r["case"] == case and int(r["result"]) == 0]
        if not pts:
            continue
        mu = np.array([float(r["mu"]) for r in pts])
        ax.loglog(mu, [float(r["dF_star_field"]) for r in pts], "s", mfc="none", color=color,
                  label=f"E4 {case}: field model")
        ax.loglog(mu, [float(r["dF_star"]) for r in pts], "o", color=color, ms=4, label=f"E4 {case}: 3D rod, {n} segments")
    ax.set_xlabel("μ")
    ax.set_ylabel("ΔF* [N]")
    ax.set_title("E4 with the 3D rod: sine 15 mm/s (A), random velocity ±15 mm/s (B), random position (C)", fontsize=8)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "no finished point", transform=ax.transAxes, ha="center")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
