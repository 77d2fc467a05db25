"""The paper's experiments with the paper's model: the 3D rod ([`jaxrod.rod3d`][]) at the paper's
500 segments for E3, E4, E5 and E6C, beside the field model. Each part lives with its experiment
(`jaxrod.experiments.e3.rod3d`, `e4.rod3d`, `e5.rod3d`, `e6.rod3d`; `jaxrod reproduce e3 e4 e5 e6
--model rod3d [--n N]`; docs/paper.md, "The experiments with the 3D rod"); this module holds what
they share: their settings, the CSV of finished points that a rerun skips, the critical-load
search of either model, and reading the mode of θ at a run's stop.

Every search is label bisection of the 3D rod's runs (a run stops at its label: stuck, or past
the buckling threshold) to a relative bracket of 1 %, started from the field model's answer:

- **E3**: v₀*(ΔF) of the sine mode 6, μ = 0.3, a bracket ±4 % around the field model's v₀*,
  widened until two runs hold it (`e3.rod3d.boundary_3d`); the exponent of v₀* ∝ ΔF^p by least
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
import os
import subprocess
import time

import numpy as np

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


def _critical_load(rod, amplitude, perturbation, key, model, n, t1, bracket, rtol, method=None):
    import jax

    from ..boundary import critical_load

    t0 = time.perf_counter()
    r, _ = critical_load(rod, amplitude, model=model, perturbation=perturbation, key=key, t1=t1, bracket=bracket,
                         rtol=rtol, n=n, method=method, sensitivities=())
    r = jax.block_until_ready(r)
    return r, time.perf_counter() - t0


def _best(rows):
    """Of the rows of one E4 point: a converged one before one that failed, then the longest
    horizon, then the widest bracket (None for none)."""
    return max(rows, key=lambda r: (r["result"] == "0", float(r["t1"]), float(r["width"] or 0))) if rows else None


def _modes(theta, n_modes=40):
    """The two strongest sine modes of `theta` (interior nodes) and their power shares, among the
    first `n_modes` (at most one per interior node: more would alias)."""
    import jax.numpy as jnp

    from ..modal import modal_spectrum

    theta = np.asarray(theta)
    n_modes = None if n_modes is None else min(n_modes, theta.shape[-1])
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
