"""E5: the dominant buckling mode against μ for random perturbations."""

from __future__ import annotations

import math
import os

import numpy as np

from ... import theory
from ...output import subplots, write_csv
from ...params import RodChannel
from .._settings import _settings
from .._stats import finite_mean_std
from ..convergence import convergence, dominant_modes_at

__all__ = ['e5']


def e5(out, quick, progress):
    from ...boundary import critical_load_curve
    from ...registry import make_perturbation
    from ...scene import Scene, default_nodes

    s = _settings(quick)
    mus = s["mus"]
    R = s["realizations"]
    rod0 = RodChannel.reference()
    n = s["n"] or default_nodes(rod0, float(theory.reference_load(rod0)) + s["max_dF"])  # of the load F, not ΔF
    res = {"model": "field", "n": n}  # the sine default; each perturbation records its own n
    rows = []
    for kind, amp in (("random-velocity", 15e-3), ("random-position", 2.0)):
        # the scene's default n for the perturbation (499 for a random velocity: every mode of
        # the 500-segment noise grid resolved), rtol 1e-4 (the dominant mode is read at 1.05 ΔF*)
        n = s["n"] or Scene(rod0, s["max_dF"], make_perturbation(kind, amp), "field").size()
        rr, _ = critical_load_curve(mus, amp, perturbation=kind, realizations=R, seed=5, n=n, t1=s["t1"],
                                    bracket=(1e-3, s["max_dF"]), rtol=1e-4)
        dFs = np.asarray(rr.root) * 1.05  # just past the boundary
        ok = np.asarray(rr.result) == 0
        modes, buckled = dominant_modes_at(kind, amp, mus, dFs, n, R, seed=5)
        modes = np.where(ok & np.asarray(buckled), np.asarray(modes), np.nan).astype(float)
        mean, std = finite_mean_std(modes, ddof=0)
        res[kind] = {"n": n, "amplitude": amp, "mu": mus.tolist(), "dominant_mode_mean": mean.tolist(),
                     "dominant_mode_std": std.tolist(), "dominant_mode_min": float(np.nanmin(modes)),
                     "dF_evaluated": finite_mean_std(np.where(ok, dFs, np.nan))[0].tolist()}
        for i, m in enumerate(mus):
            rows.append(dict(perturbation=kind, mu=m, mode_mean=mean[i], mode_std=std[i]))
    # theory: the mode whose zone is crossed first for an equal modal velocity amplitude
    n_modes = n
    a_modal = 15e-3 * math.sqrt(2.0 / (3 * (n + 1))) / float(rod0.R)  # RMS modal amplitude of U(-a, a) per node
    m_theory = [int(theory.min_critical_load(rod0.with_friction(m), n_modes, a_modal)[1]) for m in mus]
    res["theory_first_mode_equal_modal_velocity"] = {"mu": mus.tolist(), "mode": m_theory,
                                                     "modal_velocity_rad_s": a_modal}
    _figure(os.path.join(out, "e5_modes.png"), res, rod0)
    write_csv(os.path.join(out, "e5_modes.csv"), rows)
    res["convergence"] = convergence(out, quick, progress)  # of ΔF* and of the mode in n, at two μ
    return res


def _figure(path, res, rod):
    """Left: the dominant mode against μ per perturbation (mean ± std over the realizations) and
    P7's first zone crossed; right: P6's velocity intercepts of modes 2–10 against the load."""
    fig, axes = subplots(1, 2, figsize=(12, 4.8))
    for kind in ("random-velocity", "random-position"):
        r = res[kind]
        axes[0].errorbar(r["mu"], r["dominant_mode_mean"], yerr=r["dominant_mode_std"], fmt="o-", capsize=3,
                         label=f"{kind} (field, ΔF = 1.05 ΔF*)")
    th = res["theory_first_mode_equal_modal_velocity"]
    axes[0].plot(th["mu"], th["mode"], "k--", label="P7: first zone crossed, equal modal Ȧ₀")
    axes[0].axhline(6, color="gray", lw=0.8)
    axes[0].set_xscale("log")
    axes[0].set_xlabel("μ")
    axes[0].set_ylabel("dominant buckling mode")
    axes[0].set_title("E5: buckling mode against friction", fontsize=10)
    axes[0].legend(fontsize=7)
    F = np.linspace(1.0, 20.0, 300)
    f = float(theory.friction_amplitude(rod))
    for m in (2, 4, 6, 8, 10):
        k = np.asarray(theory.stiffness(rod, m, F))
        v = np.where(k < 0, f / np.sqrt(np.abs(k)), np.nan)
        axes[1].plot(F, float(rod.R) * 1e3 * v, label=f"mode {m} (F⁰ = {float(theory.frictionless_load(rod, m)):.2f} N)")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("F [N]")
    axes[1].set_ylabel("R·Ȧ_m,cr [mm/s] (P6, μ = 0.3)")
    axes[1].set_title("velocity intercepts of modes 2–10", fontsize=10)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
