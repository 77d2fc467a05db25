"""The paper's experiments with the paper's model: the 3D rod ([`jaxrod.rod3d`][]) at the paper's
500 segments for E3, E4, E5 and E6C, beside the field model (`jaxrod reproduce e3 e4 e5 e6
--model rod3d [--n N]`; docs/paper.md, "The experiments with the 3D rod").

Every search is label bisection of the 3D rod's runs (a run stops at its label: stuck, or past
the buckling threshold) to a relative bracket of 1 %, started from the field model's answer:

- **E3**: v₀*(ΔF) of the sine mode 6, μ = 0.3, a bracket ±4 % around the field model's v₀*,
  widened until two runs hold it (`e3_rod3d.boundary_3d`); the exponent of v₀* ∝ ΔF^p by least
  squares in log–log over all the loads, fixed before any run, beside the paper's −0.77.
- **E4**: ΔF*(μ) of the sine 15 mm/s (A), of random velocities ±15 mm/s (B) and of random
  positions (C: forces ±2 N/m for 1 ms; realization r: key `fold_in(key(0), r)`), in a bracket
  a factor `WIDTH` either side of the field model's ΔF* for the same perturbation (for B on 499
  nodes, the random grid resolved), squared while the bracket holds no boundary, up to
  `WIDTH`⁴; horizon 0.5 s. The 3D rod never sticks (it rocks on the wall, rolling without
  slip), so a stable run lasts the whole horizon: the field model's 2 s costs four times the
  runs and gave the same bracket as 0.5 s where both were run (docs/rod3d.md gives the brackets
  and the cost).
- **E5**: on E4's points of B and C, one run of each model at 1.05 times its own ΔF*, with the
  step of its search (near the boundary a 3D label can turn with a step 2·10⁻⁴ apart), and the
  dominant mode of θ at the stop with its share of the power (a few seconds a run at 500
  segments: the runs stop at buckling).
- **E6C**: the random position (forces ±2 N/m for 1 ms, key 6 as `jaxrod reproduce e6`) at
  μ = 0.9: ΔF* (horizon 0.5 s, bracket a factor 4), then runs at 1.05 ΔF* and at the paper's
  40 N, and the largest modes of θ at the stop with their shares of the power of 40 modes.

A sweep never loses finished work: E3 appends every run to `e3/rod3d_runs.csv` and replays it,
E4, E5 and E6C append every finished point to their CSV (with wall time, commit and date) and
skip the points already there when the command runs again.
"""

from __future__ import annotations

import csv
import datetime
import math
import os
import subprocess
import time

import numpy as np

from ..output import subplots, write_csv

__all__ = ["e3", "e4", "e4_point", "e5", "e6c", "write_boundary", "SIZES", "WIDTH", "PAPER_E3_EXPONENT"]

WIDTH = 1.5
E4_CASES = {"A": ("sine", 15e-3), "B": ("random-velocity", 15e-3), "C": ("random-position", 2.0)}
FIELD_TOP = {"A": 100.0, "B": 100.0, "C": 300.0}  # the top of the field model's search bracket [N]
# the field model's nodes (None: the scene's default): every mode of the random velocity's 500-segment grid
FIELD_NODES = {"A": None, "B": 499, "C": None}
PAPER_E3_EXPONENT = -0.77  # ../shared/PHYSICS.md §5 (results/paper/paper_numbers.json)
SIZES = {
    False: dict(n=500, loads=(0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0, 60.0), mus=(0.05, 0.1, 0.3, 0.5, 1.0),
                realizations=4, t1_e3=0.4, t1_e4=0.5, t1_e6=0.5, rtol=1e-2),
    True: dict(n=60, loads=(1.0, 5.0, 20.0, 60.0), mus=(0.05, 0.3), realizations=1, t1_e3=0.4, t1_e4=0.5,
               t1_e6=0.5, rtol=1e-2),
    "tiny": dict(n=8, loads=(5.0, 20.0), mus=(0.3,), realizations=1, t1_e3=0.05, t1_e4=0.05, t1_e6=0.05, rtol=0.1),
}
E4_COLUMNS = ["case", "mu", "realization", "n", "t1", "width", "dF_star_field", "dF_star", "lo", "hi", "runs",
              "result", "wall_s", "commit", "date"]
E5_COLUMNS = ["perturbation", "mu", "realization", "n", "t1"] + [p + c for p in ("", "field_") for c in (
    "dF_star", "buckled", "t_stop", "mode", "share", "second_mode", "second_share", "wall_s")] + ["commit", "date"]
E6_COLUMNS = ["n", "case", "dF", "dF_star_field", "dF_star", "dF_star_lo", "dF_star_hi", "search_runs",
              "search_result", "buckled", "t_stop", "mode_before", "mode_at_buckling", "power_share", "second_mode",
              "second_share", "wall_s", "commit", "date"]


def _commit() -> str:
    try:
        here = os.path.dirname(os.path.abspath(__file__))
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=here).stdout.strip()
    except OSError:
        return ""


def _settings(quick, n):
    s = dict(SIZES[quick])
    if n is not None:
        s["n"] = int(n)
    return s


class _Points:
    """The finished points of a part, read from its CSV, and the writer that appends new ones."""

    def __init__(self, path, columns, key):
        self.path, self.columns, self.key = path, columns, key
        self.rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []

    def find(self, *k):
        return [r for r in self.rows if self.key(r) == tuple(str(x) for x in k)]

    def add(self, row):
        row = {**row, "commit": _commit(), "date": datetime.date.today().isoformat()}
        new = not os.path.exists(self.path)
        with open(self.path, "a", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=self.columns)
            if new:
                w.writeheader()
            w.writerow({c: row.get(c, "") for c in self.columns})
        self.rows.append({c: str(row.get(c, "")) for c in self.columns})


def write_boundary(res: dict, stem: str) -> None:
    """`e3_rod3d.boundary_3d`'s result as `stem.json` (all of it), `stem.csv` (one row per load,
    plain numbers) and `stem.png`."""
    import json

    from .e3_rod3d import plot_boundary_3d

    with open(stem + ".json", "w") as fh:
        json.dump(res, fh, indent=1)
    write_csv(stem + ".csv", [dict(dF=p["dF"], n_segments=res["n_segments"], mu=res["mu"], t1=res["t1"], dt=res["dt"],
                                   field_mm_s=1e3 * p["field"], rod3d_mm_s=1e3 * p["rod3d"],
                                   bracket_lo_mm_s=1e3 * p["bracket"][0] if p["bracket"] else math.nan,
                                   bracket_hi_mm_s=1e3 * p["bracket"][1] if p["bracket"] else math.nan,
                                   difference_percent=100 * (p["rod3d"] / p["field"] - 1), runs=p["runs"])
                              for p in res["points"]])
    plot_boundary_3d(res, stem + ".png")


def e3(out, quick=False, progress=True, n=None) -> dict:
    """E3's boundary of the 3D rod at `n` segments (default: the setting's): writes
    `rod3d_boundary_n{n}_{scheme}.{json,csv,png}` (the 3D rod's default scheme: `implicit`) and
    the runs file under `out`."""
    from .e3_rod3d import boundary_3d

    s = _settings(quick, n)
    res = boundary_3d(s["loads"], n=s["n"], rtol=s["rtol"], t1=s["t1_e3"],
                      runs_csv=os.path.join(out, "rod3d_runs.csv"), progress=progress)
    write_boundary(res, os.path.join(out, f"rod3d_boundary_n{s['n']}_{res['scheme']}"))
    return dict(n=s["n"], loads=list(s["loads"]), exponent_rod3d=res["exponent_rod3d"],
                exponent_rod3d_stderr=res["exponent_rod3d_stderr"], exponent_field=res["exponent_field"],
                exponent_field_stderr=res["exponent_field_stderr"], exponent_paper=PAPER_E3_EXPONENT,
                runs=[p["runs"] for p in res["points"]], converged=sum(p["bracket"] is not None for p in res["points"]))


def _critical_load(rod, amplitude, perturbation, key, model, n, t1, bracket, rtol, method=None):
    import jax

    from ..boundary import critical_load

    t0 = time.perf_counter()
    r, _ = critical_load(rod, amplitude, model=model, perturbation=perturbation, key=key, t1=t1, bracket=bracket,
                         rtol=rtol, n=n, method=method, sensitivities=())
    r = jax.block_until_ready(r)
    return r, time.perf_counter() - t0


def e4_point(case, mu, realization, n, t1=0.5, width=WIDTH, rtol=1e-2) -> dict:
    """One E4 point: ΔF* [N] of the field model (to 1e-4) and of the 3D rod of `n` segments (label
    bisection to `rtol`, bracket a factor `width` either side of the field model's), for the sine
    15 mm/s (`case` "A"), the random velocity ±15 mm/s ("B") or the random position (forces
    ±2 N/m for 1 ms, "C") of `realization`; a row of `E4_COLUMNS` without commit and date."""
    import jax

    from ..params import RodChannel

    rod = RodChannel.reference(mu=mu)
    kind, amplitude = E4_CASES[case]
    key = jax.random.fold_in(jax.random.key(0), realization)
    f, sec_f = _critical_load(rod, amplitude, kind, key, "field", FIELD_NODES[case], t1, (0.01, FIELD_TOP[case]), 1e-4)
    f = float(f.root)
    r, sec = _critical_load(rod, amplitude, kind, key, "rod3d", n, t1, (f / width, f * width), rtol, "bisection")
    return dict(case=case, mu=float(mu), realization=realization, n=n, t1=float(t1), width=width, dF_star_field=f,
                dF_star=float(r.root), lo=float(r.lo), hi=float(r.hi), runs=int(r.evaluations), result=int(r.result),
                wall_s=round(sec + sec_f, 1))


def _best(rows):
    """Of the rows of one E4 point: a converged one before one that failed, then the longest
    horizon, then the widest bracket (None for none)."""
    return max(rows, key=lambda r: (r["result"] == "0", float(r["t1"]), float(r["width"] or 0))) if rows else None


def e4(out, quick=False, progress=True, n=None, mus=None) -> dict:
    """E4 A, B and C with the 3D rod at `n` segments: `rod3d_n{n}.csv` (one row per point) and
    `.png` (ΔF* against μ, both models) under `out`; `mus` a subset of the setting's μ to run.

    A point found in the CSV on the setting's horizon or a longer one is not run again (a run
    stable for the longer horizon is stable for the shorter; each point is reported on the
    longest horizon it has). A point whose 3D search found both ends of its bracket on one side
    (`invalid_bracket`) is run again with the bracket's width squared, up to `WIDTH`⁴."""
    from ..boundary.roots import ROOT_RESULTS

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


def _modes(theta, n_modes=40):
    import jax.numpy as jnp

    from ..modal import modal_spectrum

    p = np.asarray(modal_spectrum(jnp.asarray(theta), n_modes))
    order = np.argsort(p)[::-1]
    return int(order[0]) + 1, float(p[order[0]]), int(order[1]) + 1, float(p[order[1]])


def _theta_3d(sol):
    """The 3D rod's lateral angle θ at its interior nodes over the saved times, and the index of
    the save at its stop."""
    theta = np.asarray(sol.observables["theta"])[:, 1:-1]
    return theta, min(int(np.searchsorted(np.asarray(sol.ts), float(sol.t_stop))), len(theta) - 1)


def _final_theta(sol):
    """θ at the interior nodes where the run stopped: the 3D rod's recorded angle (its observable
    `theta`), or a field model's final state."""
    if "theta" in (sol.observables or {}):
        theta, i = _theta_3d(sol)
        return theta[i]
    return np.asarray(sol.q_final)


def _found(points, t1, *key):
    """The row of E4 point `key` (case, μ, realization, n) on a horizon ≥ `t1`, by `_best`."""
    return _best([r for r in points.find(*key) if float(r["t1"]) >= t1])


def _e4_points(path):
    return _Points(path, E4_COLUMNS, lambda r: (r["case"], r["mu"], r["realization"], r["n"]))


def e5(out, quick=False, progress=True, n=None, mus=None) -> dict:
    """E5 with the 3D rod at `n` segments, on E4's points (run first where missing, under
    `out`/../e4): for each random perturbation (E4's B and C), μ and realization, one run of each
    model at 1.05 times its own ΔF*, on the point's horizon, and the dominant mode of θ at the stop
    with its share of the power of every mode; `rod3d_n{n}.csv` and `.png` under `out`; `mus` a
    subset of the setting's μ to run."""
    import jax

    from ..params import RodChannel
    from ..scene import Scene, make_perturbation

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


def e6c(out, quick=False, progress=True, n=None) -> dict:
    """E6C with the 3D rod at `n` segments: `rod3d_random_position_n{n}.csv` under `out`."""
    import jax

    from ..params import RodChannel
    from ..scene import Scene, make_perturbation

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
