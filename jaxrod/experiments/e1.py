"""E1: the rod pushed at 1 mm/s (displacement control) in the 3D model, μ = 0 and 0.3, the
critical force (first peak of the reaction) against the perturbation v₀, its convergence in the
segment count, and, at μ = 0, against the pushing speed (`e1_speed`)."""

from __future__ import annotations

import os

import numpy as np

from .. import theory
from ..output import subplots, write_csv
from ..params import RodChannel
from .e1_speed import SIZES as SPEED_SIZES, e1_speed
from .rod3d import SIZES, e1_curves

__all__ = ["e1"]


def e1(out, quick=False, progress=True):
    """E1: displacement control at 1 mm/s, μ = 0 and 0.3, v₀ over `SIZES`; the critical force
    against v₀; its convergence in the segment count at μ = 0.3, v₀ = 15 mm/s."""
    S = SIZES[quick]
    res = {"model": "rod3d", "n_segments": S["n"], "speed_m_s": 1e-3, "v0_m_s": list(S["v0s"])}
    rows, curves = [], {}
    F0 = float(theory.frictionless_load(RodChannel.reference(0.0), 6))
    for mu in (0.0, 0.3):
        if progress:
            print(f"  E1 μ = {mu}: {len(S['v0s'])} rods, {S['n']} segments", flush=True)
        r = e1_curves(mu, S["v0s"], n=S["n"], t1=S["t1"], n_save=S["n_save"])
        curves[mu] = r
        for k, v0 in enumerate(S["v0s"]):
            for d, f in zip(r["displacement"][k][::5], r["reaction"][k][::5]):
                rows.append(dict(mu=mu, v0=v0, displacement=d, reaction=f))
        res[f"mu={mu}"] = {"critical_force": r["critical_force"].tolist(),
                           "d_critical_mm": (r["d_critical"] * 1e3).tolist(),
                           "buckled": r["buckled"].tolist(), "peaked": r["peaked"].tolist(),
                           "energy_balance_max_J": r["balance"].tolist(),
                           "dt": r["dt"]}
    res["F0_6_theory"] = F0
    # convergence in n at μ = 0.3, v₀ = 15 mm/s
    conv = []
    for n in S["conv"]:
        if progress:
            print(f"  E1 convergence: {n} segments", flush=True)
        r = e1_curves(0.3, (15e-3,), n=n, t1=S["t1"], n_save=S["n_save"])
        conv.append(float(r["critical_force"][0]))
    res["convergence"] = {"mu": 0.3, "v0": 15e-3, "n_segments": list(S["conv"]), "critical_force": conv}
    # μ = 0 against the pushing speed (is the v₀ dependence a delayed bifurcation?), reusing
    # the runs at 1 mm/s made above when the segment counts agree
    known = {}
    if SPEED_SIZES[quick]["n3d"] == S["n"]:
        known = {(1e-3, v0): f for v0, f, b in zip(S["v0s"], res["mu=0.0"]["critical_force"], res["mu=0.0"]["peaked"]) if b}
    res["speed"] = e1_speed(out, quick, progress, known=known)
    _figure(os.path.join(out, "e1_force_displacement.png"), S, curves, F0)
    write_csv(os.path.join(out, "e1_force_displacement.csv"), rows)
    return res


def _figure(path, S, curves, F0):
    """Reaction against end displacement at μ = 0 and 0.3 (one line per v₀), and the critical
    force against v₀."""
    fig, axes = subplots(1, 3, figsize=(15, 4.5))
    for (mu, r), ax in zip(curves.items(), axes[:2]):
        for k, v0 in enumerate(S["v0s"]):
            ax.plot(r["displacement"][k] * 1e3, r["reaction"][k], label=f"v₀ = {v0 * 1e3:g} mm/s")
        ax.axhline(F0, color="k", lw=0.8, ls=":", label="F⁰₆ (frictionless theory)")
        ax.set_xlabel("end displacement [mm]")
        ax.set_ylabel("reaction at the pushed end [N]")
        ax.set_title(f"E1: μ = {mu}, {S['n']} segments, pushed at 1 mm/s", fontsize=9)
        ax.legend(fontsize=7)
        axes[2].plot(np.asarray(S["v0s"]) * 1e3, r["critical_force"], "o-", label=f"μ = {mu}")
    axes[2].set_xlabel("v₀ [mm/s]")
    axes[2].set_ylabel("critical force [N]")
    axes[2].axhline(F0, color="k", lw=0.8, ls=":")
    axes[2].set_title("critical force (peak reaction) against v₀", fontsize=9)
    axes[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
