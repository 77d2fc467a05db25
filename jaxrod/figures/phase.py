"""E2: phase portraits of the single-mode oscillator for the six cases of docs/physics.md §4."""

from __future__ import annotations

import csv
import os

import jax
import jax.numpy as jnp
import numpy as np

from .. import theory
from ..integrators import Exact, ProjectedVerlet
from ..models import SingleMode
from ..output import subplots
from ..simulate import simulate

__all__ = ["phase_portraits", "classify_grid"]

CASES = [  # (row, col, k, f, title)
    (0, 0, 1.0, 0.0, "f = 0, k > 0: centre"),
    (0, 1, 0.0, 0.0, "f = 0, k = 0: drift"),
    (0, 2, -1.0, 0.0, "f = 0, k < 0: saddle"),
    (1, 0, 1.0, 1.0, "f > 0, k > 0: ends on the stick line"),
    (1, 1, 0.0, 1.0, "f > 0, k = 0: every state stops"),
    (1, 2, -1.0, 1.0, "f > 0, k < 0: finite stable zone"),
]


def classify_grid(k, f, A, Adot, t1=600.0, dt=1e-2, bound=50.0):
    """Classify initial states by a vmapped projected-Verlet run: stable if the state stays
    finite with |A| ≤ `bound` up to `t1` (units of the normalised oscillator).

    **Returns:** boolean array of the broadcast shape of `A`, `Adot`.
    """
    model = SingleMode(k, f, f)

    def one(a, v):
        sol = simulate(model, ProjectedVerlet(dt), a, v, t1, n_save=61, throw=False)
        return jnp.all(jnp.isfinite(sol.q)) & jnp.all(jnp.abs(sol.q) <= bound)

    A, Adot = jnp.broadcast_arrays(jnp.asarray(A, float), jnp.asarray(Adot, float))
    return np.asarray(jax.jit(jax.vmap(one))(A.ravel(), Adot.ravel())).reshape(A.shape)


def _trajectories(k, f, starts, t1=12.0, n=600):
    model = SingleMode(k, f, f)
    a, v = (jnp.asarray(x, float) for x in zip(*starts))
    run = jax.vmap(lambda a, v: simulate(model, Exact(), a, v, t1, n_save=n, throw=False))
    sol = run(a, v)
    return list(zip(np.asarray(sol.q), np.asarray(sol.v)))


def phase_portraits(out_dir: str, n_grid: int = 24, extent: float = 4.0) -> dict:
    """Write `phase.png` (2×3 panels: f = 0 or > 0 by k > 0, = 0, < 0) and `phase.csv`.

    Axes are normalised: |k| = 1 s⁻², f = 1 rad/s² where non-zero, so the stick line is
    |A| ≤ 1 and, for k < 0, the velocity intercept is Ȧ_cr = 1. Each panel shows exact
    trajectories, the analytic stable zone (shaded), the stick line, and the classification
    of an `n_grid`² grid of initial states by a vmapped projected-Verlet simulation (dots:
    stable; crosses: unstable).

    **Returns:** a dict with, per case, the fraction of grid points where the simulated and
    analytic classifications agree.
    """
    from matplotlib.patches import Polygon

    os.makedirs(out_dir, exist_ok=True)
    g = np.linspace(-extent, extent, n_grid)
    AA, VV = np.meshgrid(g, g)
    fig, axes = subplots(2, 3, figsize=(13, 8.2), sharex=True, sharey=True)
    starts = [(a, v) for a in (-3.0, -1.5, 0.0, 1.5, 3.0) for v in (-2.5, -1.0, 1.0, 2.5)]
    starts += [(2.0, 0.0), (-0.5, 0.0), (0.0, 0.5), (0.0, 0.99), (0.0, 1.01)]
    agreement = {}
    rows = []
    for r, c, k, f, title in CASES:
        ax = axes[r, c]
        sim = classify_grid(k, f, AA, VV)
        if f > 0 or k > 0:
            zone = np.asarray(theory.in_stable_zone(AA, VV, k, f))
        else:  # frictionless k <= 0: bounded only at rest (k = 0) or at the origin (k < 0)
            zone = (VV == 0) & ((AA == 0) | (k == 0))
        agreement[title] = float(np.mean(sim == zone))
        for a, v, s_, z_ in zip(AA.ravel(), VV.ravel(), sim.ravel(), zone.ravel()):
            rows.append((k, f, a, v, int(s_), int(z_)))
        # analytic zone
        if k < 0 and f > 0:
            A_b, V_b = (np.asarray(x) for x in theory.stable_zone_boundary(k, f, n=300, extent=20))
            ax.add_patch(Polygon(np.c_[A_b, V_b], closed=True, color="tab:green", alpha=0.25, lw=0))
        elif f > 0 or k > 0:
            ax.axhspan(-extent * 1.1, extent * 1.1, color="tab:green", alpha=0.12, lw=0)
        # stick line
        if f > 0:
            half = extent * 1.1 if k == 0 else f / abs(k)
            ax.plot([-half, half], [0, 0], color="k", lw=4, solid_capstyle="butt", zorder=4)
        elif k == 0:
            ax.axhline(0.0, color="k", lw=2, zorder=4)
        else:
            ax.plot([0], [0], "ko", ms=5, zorder=4)
        for A, V in _trajectories(k, f, starts):
            ax.plot(A, V, color="tab:blue", lw=0.7, alpha=0.8)
        ax.scatter(AA[sim], VV[sim], s=6, c="tab:green", marker="o", lw=0, zorder=5)
        ax.scatter(AA[~sim], VV[~sim], s=9, c="tab:red", marker="x", lw=0.6, zorder=5)
        if k < 0:
            lam = np.sqrt(-k)
            xs = np.linspace(-extent, extent, 2)
            ax.plot(xs, lam * (f / -k - xs), "--", color="gray", lw=0.8)
            ax.plot(xs, -lam * (f / -k + xs), "--", color="gray", lw=0.8)
        ax.set_xlim(-extent, extent)
        ax.set_ylim(-extent, extent)
        ax.set_title(f"{title}\nsim/theory agree on {100 * agreement[title]:.1f}% of grid", fontsize=9)
        if r == 1:
            ax.set_xlabel("A [rad] (units of f/|k|)")
        if c == 0:
            ax.set_ylabel("dA/dt [rad/s]")
    fig.suptitle(
        "Single-mode oscillator  A'' + kA + f sgn(A') = 0: exact trajectories (blue), analytic "
        "stable zone (green), stick line (black),\nvmapped projected-Verlet classification "
        "(dots stable, crosses unstable)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "phase.png"), dpi=130)
    with open(os.path.join(out_dir, "phase.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["k", "f", "A0", "Adot0", "stable_simulated", "stable_theory"])
        w.writerows(rows)
    return agreement
