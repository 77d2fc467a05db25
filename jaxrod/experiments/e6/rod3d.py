"""E6C with the full model: the random position at μ = 0.9 with the 3D rod: ΔF*, then runs at 1.05 ΔF* and at the paper's 40 N (`jaxrod reproduce e6 --model rod3d`). docs/paper.md, "The experiments with the 3D rod", gives the method and the results."""

from __future__ import annotations

import math
import os
import time

import numpy as np

from ...output import subplots, write_csv
from ..paper3d import (WIDTH, E4_CASES, FIELD_TOP, FIELD_NODES, E4_COLUMNS, E5_COLUMNS, E6_COLUMNS, _settings, _Points, _critical_load, _best, _modes, _theta_3d, _final_theta, _found, _e4_points)

def e6c(out, quick=False, progress=True, n=None) -> dict:
    """E6C with the 3D rod at `n` segments: `rod3d_random_position_n{n}.csv` under `out`."""
    import jax

    from ...params import RodChannel
    from ...registry import make_perturbation
    from ...scene import Scene

    s = _settings(quick, n)
    rod = RodChannel.reference(mu=0.9)
    key = jax.random.key(6)
    t1 = s["t1_e6"]
    path = os.path.join(out, f"rod3d_random_position_n{s['n']}.csv")
    done = _Points(path, E6_COLUMNS, lambda r: (r["n"], r["case"]))
    if len(done.find(s["n"], "1.05 dF*")) == 0 or len(done.find(s["n"], "paper's 40 N")) == 0:
        f, _ = _critical_load(rod, 2.0, "random-position", key, "field", None, t1, (1e-3, 300.0), 1e-4)
        f = float(f.root)
        r, sec = _critical_load(rod, 2.0, "random-position", key, "rod3d", s["n"], t1, (f / 4, 4 * f), s["rtol"],
                                "bisection")
        star = float(r.root)
        pert = make_perturbation("random-position", 2.0, 6, key)
        for case, dF in (("1.05 dF*", 1.05 * star), ("paper's 40 N", 40.0)):
            if done.find(s["n"], case):
                continue
            if not math.isfinite(dF):  # the search failed: recorded, so that it is not run again
                done.add(dict(n=s["n"], case=case, dF=dF, dF_star_field=f, dF_star=star, dF_star_lo=float(r.lo),
                              dF_star_hi=float(r.hi), search_runs=int(r.evaluations), search_result=int(r.result),
                              wall_s=round(sec, 1)))
                sec = 0.0
                continue
            t0 = time.perf_counter()
            sol = Scene(rod, dF, pert, "rod3d", s["n"]).run(t1=t1, n_save=501)
            theta, i = _theta_3d(sol)
            m, share, m2, share2 = _modes(theta[i])
            done.add(dict(n=s["n"], case=case, dF=dF, dF_star_field=f, dF_star=star, dF_star_lo=float(r.lo),
                          dF_star_hi=float(r.hi), search_runs=int(r.evaluations), search_result=int(r.result),
                          buckled=int(sol.buckled), t_stop=float(sol.t_stop), mode_before=_modes(theta[0])[0],
                          mode_at_buckling=m, power_share=share, second_mode=m2, second_share=share2,
                          wall_s=round(sec + time.perf_counter() - t0, 1)))
            sec = 0.0  # the search's time is counted once, on the first row
            if progress:
                print(f"  E6C {case} = {dF:.4g} N: mode {m} ({share:.2f}; next {m2}: {share2:.2f})", flush=True)
    rows = {r["case"]: r for r in done.rows if int(r["n"]) == s["n"] and r["buckled"] != ""}
    return {case: dict(dF=float(r["dF"]), dF_star=float(r["dF_star"]), dF_star_field=float(r["dF_star_field"]),
                       mode=int(r["mode_at_buckling"]), share=float(r["power_share"]), next_mode=int(r["second_mode"]),
                       next_share=float(r["second_share"])) for case, r in rows.items()} | dict(n=s["n"])
