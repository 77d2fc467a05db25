"""Reproduce the reference paper's experiments: E2–E5 with the reduced models, E1 and the
full-model part of E6 with the 3D rod ([`jaxrod.rod3d`][]), and the post-buckling experiment
(`helix`: the frictionless helix against docs/physics.md §6, a loading–unloading cycle with friction).

`jaxrod reproduce {e1,e2,e3,e4,e5,e6,helix,all} [--out DIR] [--quick]` writes, per experiment, PNG
figures laid out like a paper's panels and CSV data under `DIR/eN/`, and merges every fitted
number into `DIR/results.json` (with the settings that made it). Critical values come from the
boundary search ([`jaxrod.boundary`][]), not from grids; E3 is a map by definition.
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from . import theory
from .output import subplots, write_csv
from .params import RodChannel

__all__ = ["reproduce", "EXPERIMENTS"]

EXPERIMENTS = ("e1", "e2", "e3", "e4", "e5", "e6", "helix")


def _settings(quick) -> dict:
    if quick == "tiny":  # for the test suite: structure, not accuracy
        return dict(n=24, mus=np.array([0.1, 0.4, 1.0]), realizations=2, map_dF=(0.5, 64.0, 4),
                    map_v0=(1e-3, 0.2, 5), t1=0.3, max_dF=300.0)
    if quick:
        return dict(n=48, mus=np.geomspace(0.05, 1.0, 4), realizations=3, map_dF=(0.5, 64.0, 8),
                    map_v0=(1e-3, 0.2, 10), t1=0.3, max_dF=300.0)
    return dict(n=None, mus=np.geomspace(0.05, 1.0, 8), realizations=8, map_dF=(0.5, 64.0, 20),
                map_v0=(1e-3, 0.2, 24), t1=0.5, max_dF=300.0)


# -- E1 (3D rod) ---------------------------------------------------------------------------------

def e1(out, quick, progress):
    from .experiments.rod3d import e1 as run_e1

    return run_e1(out, quick, progress)


# -- E2 -----------------------------------------------------------------------------------------

def e2(out, quick, progress):
    from .figures import phase_portraits

    agreement = phase_portraits(out, n_grid=8 if quick == "tiny" else 12 if quick else 24)
    return {"grid_agreement_simulated_vs_analytic": agreement}


# -- E3 -----------------------------------------------------------------------------------------

def e3(out, quick, progress):
    from .stability_map import stability_map

    s = _settings(quick)
    lo, hi, n = s["map_dF"]
    vlo, vhi, vn = s["map_v0"]
    summ = stability_map((0.3, 0.0), np.geomspace(lo, hi, n), np.geomspace(vlo, vhi, vn), "field",
                         s["n"], 6, out, progress=progress, t1=2.0)
    fric, free = summ["maps"]["0.3"], summ["maps"]["0"]
    return {
        "model": "field", "n": summ["n"], "dt": summ["dt"],
        "boundary_exponent": fric["exponent"], "boundary_exponent_stderr": fric["exponent_stderr"],
        "boundary_exponent_theory": -0.5,
        "largest_stable_dF_over_F0cr": fric["largest_stable_dF_over_F0cr"],
        "frictionless_buckles_for_every_dF_gt_0": free["buckles_for_every_dF_gt_0"],
        "frictionless_stable_points": free["stable"],
    }


# -- E4 -----------------------------------------------------------------------------------------

def _fit(x, y):
    from .stability_map import fit_power_law

    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(y) & (y > 0)
    if ok.sum() < 2:
        return math.nan, math.nan, math.nan
    return fit_power_law(x[ok], y[ok])


def _frictionless_dF(s, amplitude, perturbation):
    """ΔF* at μ = 0 by a linear-space search (the boundary is at ΔF = 0 up to the horizon)."""
    import jax
    import jax.numpy as jnp

    from .boundary import rod_indicator, safeguarded_newton
    from .scene import Scene, make_perturbation

    rod = RodChannel.reference(mu=0.0)
    n = s["n"] or 128
    probe = Scene(rod, 1.0, kind="field", n=n)
    dt = probe.step()
    pert = make_perturbation(perturbation, amplitude, 6, jax.random.key(0))
    g = lambda dF: rod_indicator(Scene(rod, dF, pert, "field", n, 6, dt), s["t1"])
    r = jax.jit(lambda: safeguarded_newton(g, jnp.asarray(-0.5), jnp.asarray(2.0), 1e-6, 60, geometric=False))()
    return float(r.root), int(r.result)


def e4(out, quick, progress):
    from .boundary import critical_load_curve
    from .scene import default_nodes

    s = _settings(quick)
    mus = s["mus"]
    R = s["realizations"]
    rod = RodChannel.reference()
    F0 = float(theory.reference_load(rod))
    F0cr = float(theory.critical_load_continuous(rod))
    cases = [
        ("sine 7.5 mm/s", "sine", 7.5e-3, 1, 2.0),
        ("sine 15 mm/s", "sine", 15e-3, 1, 2.0),
        ("random velocity ±15 mm/s", "random-velocity", 15e-3, R, None),
        ("random position (forces ±2 N/m for 1 ms)", "random-position", 2.0, R, 1.0),
    ]
    n_used = s["n"] or default_nodes(rod, float(theory.reference_load(rod)) + s["max_dF"])
    rows, res = [], {"model": "field", "n": n_used, "mu": mus.tolist(),
                     "dF_measured_from": f"F0_6 = {F0:.4f} N (F0cr continuous = {F0cr:.4f} N)"}
    fig, ax = subplots(figsize=(7, 5))
    for label, kind, amp, reals, theory_exp in cases:
        t0 = time.perf_counter()
        rr, _ = critical_load_curve(mus, amp, perturbation=kind, realizations=reals, seed=4, n=s["n"],
                                    t1=s["t1"], bracket=(1e-3, s["max_dF"]))
        F = np.where(np.asarray(rr.result) == 0, np.asarray(rr.root), np.nan)
        mean = np.nanmean(F, axis=1)
        std = np.nanstd(F, axis=1, ddof=1) if reals > 1 else np.zeros_like(mean)
        p, se, c = _fit(mus, mean)
        free, free_code = _frictionless_dF(s, amp, kind)
        entry = {"dF_star": mean.tolist(), "dF_star_std": std.tolist(), "exponent": p, "exponent_stderr": se,
                 "exponent_theory": theory_exp, "realizations": reals, "amplitude": amp,
                 "frictionless_dF_star": free, "frictionless_result": free_code,
                 "evaluations_total": int(np.asarray(rr.evaluations).sum()),
                 "seconds": round(time.perf_counter() - t0, 1)}
        if kind == "sine":
            p7 = np.array([float(theory.critical_load_velocity(rod.with_friction(m), 6, amp / rod.R)) - F0 for m in mus])
            entry["single_mode_P7"] = p7.tolist()
            entry["field_over_P7"] = (mean / p7).tolist()
            ax.plot(mus, p7, ":", color="gray")
        res[label] = entry
        ax.errorbar(mus, mean, yerr=std if reals > 1 else None, fmt="o-", capsize=3,
                    label=f"{label}: δF ∝ μ^{p:.2f}±{se:.2f}")
        for i, m in enumerate(mus):
            rows.append(dict(case=label, mu=m, dF_star_mean=mean[i], dF_star_std=std[i], realizations=reals))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("μ")
    ax.set_ylabel("δF = F_cr − F⁰₆ [N]")
    ax.set_title("E4: critical load against friction (field model; dotted: single-mode P7)", fontsize=10)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "e4_critical_load.png"), dpi=130)
    write_csv(os.path.join(out, "e4_critical_load.csv"), rows)
    return res


# -- E5 -----------------------------------------------------------------------------------------

def e5(out, quick, progress):
    import jax
    import jax.numpy as jnp

    from .boundary import critical_load_curve
    from .scene import Scene, default_nodes, make_perturbation

    s = _settings(quick)
    mus = s["mus"]
    R = s["realizations"]
    rod0 = RodChannel.reference()
    n = s["n"] or default_nodes(rod0, s["max_dF"])
    fig, axes = subplots(1, 2, figsize=(12, 4.8))
    res = {"model": "field", "n": n}
    rows = []
    for kind, amp in (("random-velocity", 15e-3), ("random-position", 2.0)):
        rr, _ = critical_load_curve(mus, amp, perturbation=kind, realizations=R, seed=5, n=n, t1=s["t1"],
                                    bracket=(1e-3, s["max_dF"]))
        dFs = np.asarray(rr.root) * 1.05  # just past the boundary
        ok = np.asarray(rr.result) == 0
        probe = Scene(rod0, float(np.nanmax(dFs)), kind="field", n=n)
        dt = probe.step()
        root_key = jax.random.key(5)

        def mode_at(mu, dF, i, r):
            rod = RodChannel.reference(mu=mu)
            key = jax.random.fold_in(root_key, i * R + r)
            sc = Scene(rod, dF, make_perturbation(kind, amp, 6, key), "field", n, 6, dt)
            sol = sc.run(t1=2.0, n_save=201, save_state=False)
            from .modal import dominant_mode

            return dominant_mode(sol.q_final), sol.buckled

        run = jax.jit(jax.vmap(jax.vmap(mode_at, (None, 0, None, 0)), (0, 0, 0, None)))
        modes, buckled = run(jnp.asarray(mus), jnp.asarray(dFs), jnp.arange(len(mus)), jnp.arange(R))
        modes = np.where(ok & np.asarray(buckled), np.asarray(modes), np.nan).astype(float)
        mean, std = np.nanmean(modes, axis=1), np.nanstd(modes, axis=1)
        res[kind] = {"amplitude": amp, "mu": mus.tolist(), "dominant_mode_mean": mean.tolist(),
                     "dominant_mode_std": std.tolist(), "dominant_mode_min": float(np.nanmin(modes)),
                     "dF_evaluated": np.nanmean(np.where(ok, dFs, np.nan), axis=1).tolist()}
        axes[0].errorbar(mus, mean, yerr=std, fmt="o-", capsize=3, label=f"{kind} (field, ΔF = 1.05 ΔF*)")
        for i, m in enumerate(mus):
            rows.append(dict(perturbation=kind, mu=m, mode_mean=mean[i], mode_std=std[i]))
    # theory: the mode whose zone is crossed first for an equal modal velocity amplitude
    n_modes = n
    a_modal = 15e-3 * math.sqrt(2.0 / (3 * (n + 1))) / float(rod0.R)  # RMS modal amplitude of U(-a, a) per node
    m_theory = [int(theory.min_critical_load(rod0.with_friction(m), n_modes, a_modal)[1]) for m in mus]
    res["theory_first_mode_equal_modal_velocity"] = {"mu": mus.tolist(), "mode": m_theory,
                                                     "modal_velocity_rad_s": a_modal}
    axes[0].plot(mus, m_theory, "k--", label="P7: first zone crossed, equal modal Ȧ₀")
    axes[0].axhline(6, color="gray", lw=0.8)
    axes[0].set_xscale("log")
    axes[0].set_xlabel("μ")
    axes[0].set_ylabel("dominant buckling mode")
    axes[0].set_title("E5: buckling mode against friction", fontsize=10)
    axes[0].legend(fontsize=7)
    # P6 intercepts against load for modes 2..10
    F = np.linspace(1.0, 20.0, 300)
    rod = rod0
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
    fig.savefig(os.path.join(out, "e5_modes.png"), dpi=130)
    write_csv(os.path.join(out, "e5_modes.csv"), rows)
    return res


# -- E6 (reduced models) ------------------------------------------------------------------------

def e6(out, quick, progress):
    import jax

    from .modal import modal_spectrum
    from .scene import Scene, make_perturbation

    s = _settings(quick)
    n = s["n"] or 128
    fig, axes = subplots(1, 2, figsize=(12, 4.5))
    res = {"model": "field", "n": n}
    cases = [
        ("sine mode 6, μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s", 0.3, 5.0, make_perturbation("sine", 35e-3, 6)),
        ("random position, μ = 0.9, ΔF = 40 N", 0.9, 40.0,
         make_perturbation("random-position", 2.0, 6, jax.random.key(6))),
    ]
    rows = []
    for ax, (label, mu, dF, pert) in zip(axes, cases):
        sc = Scene(RodChannel.reference(mu=mu), dF, pert, "field", n)
        sol = sc.run(t1=0.5, n_save=501)
        q = np.asarray(sol.q)
        ts = np.asarray(sol.ts)
        i_after = int(np.searchsorted(ts, float(sol.t_stop))) if bool(sol.buckled) else len(ts) - 1
        i_after = min(i_after, len(ts) - 1)
        nonzero = [i for i in range(len(ts)) if np.any(q[i] != 0)]
        i_before = nonzero[0] if nonzero else 0
        m = np.arange(1, min(n, 40) + 1)
        p_before = np.asarray(modal_spectrum(q[i_before], len(m)))
        p_after = np.asarray(modal_spectrum(q[i_after], len(m)))
        ax.bar(m - 0.2, p_before, width=0.4, label=f"before (t = {ts[i_before] * 1e3:.1f} ms)")
        ax.bar(m + 0.2, p_after, width=0.4, label=f"{'at buckling' if bool(sol.buckled) else 'end'} "
                                                  f"(t = {ts[i_after] * 1e3:.1f} ms)")
        ax.set_yscale("log")
        ax.set_ylim(1e-6, 1.5)
        ax.set_xlabel("mode m")
        ax.set_ylabel("normalised modal power")
        ax.set_title(label, fontsize=9)
        ax.legend(fontsize=7)
        res[label] = {"buckled": bool(sol.buckled), "t_buckle": float(sol.t_buckle),
                      "dominant_mode_before": int(np.argmax(p_before)) + 1,
                      "dominant_mode_after": int(np.argmax(p_after)) + 1,
                      "dominant_power_after": float(np.max(p_after)),
                      "energy_balance_error": float(sol.energy_balance_error())}
        for mm, a, b in zip(m, p_before, p_after):
            rows.append(dict(case=label, mode=int(mm), power_before=a, power_after=b))
    from .experiments.rod3d import SIZES, crosscheck_critical_velocity, e6_full, rolling_check

    res["full_model"] = e6_full(out, quick, progress)
    S = SIZES[quick]
    # friction at the contact point (the model) and at the centre line (sliding only, no
    # rolling: the reduced models' assumption), to separate rolling from everything else
    res["crosscheck_critical_velocity"] = crosscheck_critical_velocity(
        S["dFs"], n=S["n_cross"], progress=progress)
    res["crosscheck_critical_velocity_axis_friction"] = crosscheck_critical_velocity(
        S["dFs"], n=S["n_cross"], progress=progress, friction_at="axis")
    if S["dFs"]:
        if progress:
            print("  rolling check: a rod the field model calls stuck, friction at the surface and the axis", flush=True)
        res["rolling_check"] = rolling_check(max(S["dFs"]), n=S["n_cross"])
    fig.suptitle("E6 (reduced model): modal power before and after buckling", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "e6_spectra.png"), dpi=130)
    write_csv(os.path.join(out, "e6_spectra.csv"), rows)
    return res


# -- post-buckling (3D rod): helix, loading–unloading hysteresis --------------------------------

def helix(out, quick, progress):
    from .experiments.helix import post_buckling

    return post_buckling(out, quick, progress)


def reproduce(which, out: str = "results/paper", quick=False, progress: bool = True) -> dict:
    """Run the experiments in `which` (names from `EXPERIMENTS`, or `"all"`), write figures, CSV
    and `results.json` under `out`; returns the dict written. `quick`: `False` (the full run),
    `True` (coarser, fewer realizations: minutes) or `"tiny"` (the test suite's structure check)."""
    import jax

    names = EXPERIMENTS if which in ("all", ["all"], ("all",)) else tuple(which)
    bad = [w for w in names if w not in EXPERIMENTS]
    if bad:
        raise ValueError(f"unknown experiment(s) {bad}: expected {EXPERIMENTS} or 'all'.")
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "results.json")
    results = {}
    fns = {"e1": e1, "e2": e2, "e3": e3, "e4": e4, "e5": e5, "e6": e6, "helix": helix}
    for name in names:
        sub = os.path.join(out, name)
        os.makedirs(sub, exist_ok=True)
        t0 = time.perf_counter()
        if progress:
            print(f"[{name}] running ({'quick' if quick else 'full'}) ...", flush=True)
        r = fns[name](sub, quick, progress)
        r["seconds"] = round(time.perf_counter() - t0, 1)
        r["quick"] = quick
        r["jax"] = jax.__version__
        r["devices"] = jax.local_device_count()
        results[name] = r
        # merge into what is on disk now (another run may have written other experiments since)
        on_disk = json.load(open(path)) if os.path.exists(path) else {}
        on_disk[name] = r
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w") as fh:
            json.dump(on_disk, fh, indent=1, default=_json_default)
        os.replace(tmp, path)
        results = on_disk
        if progress:
            print(f"[{name}] done in {r['seconds']} s", flush=True)
    return results


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)
