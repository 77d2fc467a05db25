"""E5 with the full model: the dominant mode of the 3D rod at buckling on E4's points, beside the field model's (`jaxrod reproduce e5 --model rod3d`). docs/paper.md, "The experiments with the 3D rod", gives the method and the results."""

from __future__ import annotations

import math
import os
import time

import numpy as np

from ...output import subplots, write_csv
from ..paper3d import (WIDTH, E4_CASES, FIELD_TOP, FIELD_NODES, E4_COLUMNS, E5_COLUMNS, E6_COLUMNS, _settings, _Points, _critical_load, _best, _modes, _theta_3d, _final_theta, _found, _e4_points)
from ..e4.rod3d import e4

def e5(out, quick=False, progress=True, n=None, mus=None) -> dict:
    """E5 with the 3D rod at `n` segments, on E4's points (run first where missing, under
    `out`/../e4): for each random perturbation (E4's B and C), μ and realization, one run of each
    model at 1.05 times its own ΔF*, on the point's horizon, and the dominant mode of θ at the stop
    with its share of the power of every mode; `rod3d_n{n}.csv` and `.png` under `out`; `mus` a
    subset of the setting's μ to run."""
    import jax

    from ...params import RodChannel
    from ...registry import make_perturbation
    from ...scene import Scene

    s = _settings(quick, n)
    mus = s["mus"] if mus is None else mus
    e4_dir = os.path.join(os.path.dirname(os.path.abspath(out)), "e4")
    e4(e4_dir, quick, progress, n, mus)
    e4_done = _e4_points(os.path.join(e4_dir, f"rod3d_n{s['n']}.csv"))
    path = os.path.join(out, f"rod3d_n{s['n']}.csv")
    done = _Points(path, E5_COLUMNS, lambda r: (r["perturbation"], r["mu"], r["realization"], r["n"]))
    for case in ("B", "C"):
        kind, amplitude = E4_CASES[case]
        for mu in mus:
            for real in range(s["realizations"]):
                pt = _found(e4_done, float(s["t1_e4"]), case, float(mu), real, s["n"])
                if pt is None or pt["result"] != "0" or done.find(kind, float(mu), real, s["n"]):
                    continue
                row = dict(perturbation=kind, mu=float(mu), realization=real, n=s["n"], t1=float(pt["t1"]))
                pert = make_perturbation(kind, amplitude, 6, jax.random.fold_in(jax.random.key(0), real))
                # each model on the nodes and the step of its search (whose step is that of the bracket's
                # top): near the boundary a 3D label can turn with a step 2e-4 apart
                rod, f = RodChannel.reference(mu=mu), float(pt["dF_star_field"])
                for model, pre, star, size, top in (
                        ("rod3d", "", float(pt["dF_star"]), s["n"], f * float(pt["width"])),
                        ("field", "field_", f, FIELD_NODES[case], FIELD_TOP[case])):
                    t0 = time.perf_counter()
                    dt = Scene(rod, top, make_perturbation(kind, 1.0, 6), model, size).step()  # as the search's
                    sol = Scene(rod, 1.05 * star, pert, model, size, 6, dt).run(t1=row["t1"], n_save=501)
                    theta = _final_theta(sol)
                    m, share, m2, share2 = _modes(theta, None)
                    row |= {pre + "dF_star": star, pre + "buckled": int(sol.buckled), pre + "t_stop": float(sol.t_stop),
                            pre + "mode": m, pre + "share": share, pre + "second_mode": m2,
                            pre + "second_share": share2, pre + "wall_s": round(time.perf_counter() - t0, 1)}
                done.add(row)
                if progress:
                    print(f"  E5 {kind}, mu = {mu:g}, realization {real}: 3D mode {row['mode']} ({row['share']:.2f}), "
                          f"field mode {row['field_mode']} ({row['field_share']:.2f})", flush=True)
    rows = [r for r in done.rows if int(r["n"]) == s["n"]]
    res = dict(n=s["n"])
    for kind in ("random-velocity", "random-position"):
        for model, pre in (("rod3d", ""), ("field", "field_")):
            ok = [r for r in rows if r["perturbation"] == kind and r[pre + "buckled"] == "1"]
            res[f"{kind} {model}"] = {f"mu={m:g}": [int(r[pre + "mode"]) for r in ok if float(r["mu"]) == m]
                                      for m in s["mus"]}
    _plot_e5(rows, path[:-4] + ".png", s["n"])
    return res


def _plot_e5(rows, path, n):
    fig, axes = subplots(1, 2, figsize=(11, 4.2))
    for ax, kind, paper in zip(axes, ("random-velocity", "random-position"), (32, 21)):
        for pre, label, mark in (("", f"3D rod, {n} segments", "o"), ("field_", "field model", "s")):
            ok = [r for r in rows if r["perturbation"] == kind and r[pre + "buckled"] == "1"]
            ax.plot([float(r["mu"]) for r in ok], [int(r[pre + "mode"]) for r in ok], mark,
                    mfc="none" if pre else None, label=label)
        ax.plot([0.05, 1.0], [6, paper], "k--", lw=0.8, label=f"the paper: 6 → {paper}")
        ax.set_xscale("log")
        ax.set_xlabel("μ")
        ax.set_ylabel("dominant mode at 1.05 ΔF*")
        ax.set_title(f"E5 with the 3D rod: {kind}, each realization", fontsize=8)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
