"""Lock-up (beyond the paper, docs/physics.md §8): F_far,max and the lock-up length of the 3D
rod, read by one definition at a bounded entry force, converged in segments and push speed,
beside every soft-string variant read by the same definition.

The definition (`jaxrod.lockup.staircase`): F_far,max(f_c) is the largest far load the rod
pushes in a steady slide with an entry force of at most f_c F₀, an entry force the rod still
resolves; μL_lock(f_c)/ℓ the μL/ℓ beyond which f_c F₀ pushes nothing to the far end. Each is
bracketed by a staircase of steady injections, one lane per μL/ℓ. The closed forms read by the
same definition are `chain.far_force(f_c F₀)` and `chain.lockup_length(F_in=f_c F₀)`; their
unbounded F_far,max and L_lock are written beside them.

Lanes that share a rod length form one vmapped staircase; a group (one rod length) at one
setting of (segments per buckle wavelength, push speed) is one job, and the jobs run in worker
processes, one per core. Each job writes its own JSON under `jobs/` as it finishes (a second run
skips the jobs whose file is there with the same settings); `curve.csv`, `lockup_length_at_fc.csv`,
`stages.csv`, `profiles.csv` (the last steady stage's wall angle, wall force and axial force
along the rod), `helix_laws.csv` (those profiles against Lubinski, Mitchell and the soft string,
`jaxrod.lockup.laws`), `onsets.csv` (the sinusoidal and helical onsets bracketed by the steady
stages), `curve.json` and `curve.png` are written from them.
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from ..output import write_csv
from .lockup_convergence import FAR, LOCK, converged
from .lockup_path import protocol_rows, single_step_rows

__all__ = ["lockup", "converged", "SETTINGS", "VARIANTS"]

DAMPING, R_OVER_ELL = 20.0, 0.02
VARIANTS = [("chen", "with_weight"), ("chen", "without_weight"), ("wu_juvkam_wold", "with_weight"),
            ("wu_juvkam_wold", "without_weight")]
SETTINGS = {
    # groups: (L/ℓ, far-load lanes' μL/ℓ, the lock-up lane's first μL/ℓ, "auto" or None);
    # runs: (segments per buckle wavelength, push speed [m/s]) — the base, twice the segments, half and a quarter
    # of the speed; every lane runs at the base, the lanes in `converge` (μL/ℓ, or "lock" for the lock-up lane) at all;
    # refine: (L/ℓ, μL/ℓ, (segments per wave, push speed)) lanes that also run at that setting: four times the
    # base's segments (their n against 2n failed), or twice them at half the speed (the segment test where the
    # speed moves the answer)
    False: dict(groups=((2.0, (0.5, 1.0, 1.5, 2.0), None), (4.0, (3.0, 4.0), "auto")), f_c=6.0,
                runs=((16, 10e-3), (32, 10e-3), (16, 5e-3), (16, 2.5e-3)), converge=(0.5, 1.0, 1.5, 2.0, 3.0, "lock"),
                refine=((2.0, 0.5, (64, 10e-3)), (4.0, 3.0, (64, 10e-3)), (4.0, 3.0, (32, 5e-3)),
                        (4.0, 3.0, (32, 2.5e-3))),
                first_push=0.4, stage_push=0.15, max_stages=16, saves_per_stage=41),
    True: dict(groups=((2.0, (0.5, 1.0, 2.0), None),), f_c=6.0, runs=((16, 10e-3),), first_push=0.4,
               stage_push=0.15, max_stages=8, saves_per_stage=41),
    "tiny": dict(groups=((1.0, (0.5,), 0.5),), f_c=6.0, runs=((8, 10e-3),), first_push=0.004, stage_push=0.002,
                 max_stages=2, saves_per_stage=11),
}


def _closed(rod, X, f_c):
    """Per variant: F_far at the entry force f_c and unbounded [F₀], and μL_lock/ℓ at f_c and
    unbounded, on the lane rod at μL/ℓ = X."""
    from ..lockup import chain
    from ..lockup.push import units

    F0, ell = units(rod)
    EI, w, r, L = float(rod.EI), float(rod.rho * rod.g), float(rod.R), float(rod.L)
    mu = X * ell / L
    out = {}
    for onset, law in VARIANTS:
        kw = dict(helical_onset=onset, helical_law=law)
        out[f"{onset}/{law}"] = dict(
            far_at_fc=float(chain.far_force(f_c * F0, L, EI, w, r, mu, **kw)) / F0,
            far_max=float(chain.far_force_max(L, EI, w, r, mu, **kw)) / F0,
            lock_at_fc=float(chain.lockup_length(EI, w, r, mu, F_in=f_c * F0, **kw)) * mu / ell,
            lock=float(chain.lockup_length(EI, w, r, mu, **kw)) * mu / ell)
    return out


def _jobs(S):
    """(group, run) of every staircase of the setting: each group at the base run, its lanes in
    `converge` at the others, and the lanes in `refine` at their own settings."""
    conv = S.get("converge")
    for Lx, Xs, lock in S["groups"]:
        for k, run in enumerate(S["runs"]):
            xs, lk = Xs, lock
            if k > 0 and conv is not None:
                xs, lk = tuple(X for X in Xs if X in conv), (lock if "lock" in conv else None)
                if not xs and lk is None:
                    continue
            yield (Lx, xs, lk), run
    for Lx, X, run in S.get("refine", ()):
        yield (Lx, (X,), None), run


_STAGE_KEYS = ("f_c", "first_push", "stage_push", "saves_per_stage")


def _lane_key(X):
    """A far-load lane's key in the job files: its μL/ℓ, rounded (the lock-up lane's: "lock")."""
    return round(float(X), 9)


def _lane_id(lane):
    return "lock" if lane["vary_mu"] else _lane_key(lane["X"])


def _stored(S, out) -> dict:
    """The lanes already run under `out/jobs/`, by (L/ℓ, segments per wave, speed, lane: μL/ℓ or
    "lock"): (the job's result, the lane), from every job file whose staircase settings are `S`'s
    (`_STAGE_KEYS`) and whose lane either closed or ran at least `S`'s `max_stages`; of two, the
    one with more stages allowed."""
    found = {}
    folder = os.path.join(out, "jobs")
    for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
        with open(os.path.join(folder, name)) as fh:
            res = json.load(fh)
        old = res["settings"]
        if any(old.get(k) != S[k] for k in _STAGE_KEYS):
            continue
        for lane in res["lanes"]:
            if lane["status"] == "open" and old["max_stages"] < S["max_stages"]:
                continue
            key = (res["L_over_ell"], res["per_wave"], res["speed"], _lane_id(lane))
            if key not in found or found[key][0]["settings"]["max_stages"] < old["max_stages"]:
                found[key] = (res, lane)
    return found


def _missing(S, out):
    """The jobs to run: per (group, run), its lanes not yet stored (`_stored`), and the job file's
    path (named by L/ℓ, the lanes, segments per wave and speed)."""
    stored = _stored(S, out)
    for (Lx, Xs, lock), run in _jobs(S):
        xs = tuple(X for X in Xs if (Lx, run[0], run[1], _lane_key(X)) not in stored)
        lk = lock if lock is not None and (Lx, run[0], run[1], "lock") not in stored else None
        if xs or lk is not None:
            lanes = "-".join([f"{x:g}" for x in xs] + (["lock"] if lk is not None else []))
            yield (Lx, xs, lk), run, os.path.join(out, "jobs", f"L{Lx:g}_X{lanes}_w{run[0]}_v{1e3 * run[1]:g}.json")


def _results(S, out) -> list:
    """Every lane of the setting's jobs, as job results holding one lane each (`_stored`)."""
    stored = _stored(S, out)
    results = []
    for (Lx, Xs, lock), run in _jobs(S):
        for lane_key in [_lane_key(X) for X in Xs] + (["lock"] if lock is not None else []):
            hit = stored.get((Lx, run[0], run[1], lane_key))
            if hit is not None:
                results.append(dict(hit[0], lanes=[hit[1]]))
    return results


def _job(args):
    """One staircase: group (L/ℓ, Xs, lock X) at (segments per wave, speed). Runs in a worker."""
    import jax

    jax.config.update("jax_enable_x64", True)
    from ..lockup.push import buckle_wavelength, push_rod
    from ..lockup.staircase import staircase

    (Lx, Xs, X_lock0), (per_wave, speed), S, path, progress = args
    rod = push_rod(Lx, R_OVER_ELL, 1.0)  # μ = 1 gives L = (L/ℓ) ℓ; each lane sets its own μ
    n = max(8, math.ceil(per_wave * float(rod.L) / buckle_wavelength(rod)))
    if X_lock0 == "auto":  # 0.8 × the smallest soft-string μL_lock(f_c)/ℓ
        X_lock0 = 0.8 * min(v["lock_at_fc"] for v in _closed(rod, 1.0, S["f_c"]).values())
    locks = [] if X_lock0 is None else [X_lock0]
    mus = [X / Lx for X in (*Xs, *locks)]
    starts = [max(0.7 * min(v["far_at_fc"] for v in _closed(rod, X, S["f_c"]).values()), 0.1) for X in Xs]
    starts += [0.0] * len(locks)
    vary = [False] * len(Xs) + [True] * len(locks)
    t = time.time()
    res = staircase(rod, mus, starts, speed, f_c=S["f_c"], vary_mu=vary, n=n, first_push=S["first_push"],
                    stage_push=S["stage_push"], max_stages=S["max_stages"], saves_per_stage=S["saves_per_stage"],
                    damping=DAMPING, progress=progress, label=f"{os.path.basename(path)[:-5]}: ")
    lanes = []
    for k, lane in enumerate(res["lanes"]):
        profs = [{key: (np.asarray(a).tolist() if isinstance(a, np.ndarray) else a) for key, a in prof.items()}
                 for prof in lane["profiles"]]
        lanes.append(dict(lane, X=float(mus[k] * Lx), vary_mu=bool(vary[k]), start=float(starts[k]), profiles=profs))
    out = dict(L_over_ell=Lx, per_wave=per_wave, speed=speed, n=int(res["n"]), dt=float(res["dt"]), f_c=S["f_c"],
               F0=res["F0"], ell=res["ell"], l0=res["l0"], r=res["r"], EI=float(rod.EI), w=float(rod.rho * rod.g),
               mu_of_X=1.0 / Lx, wall_s=time.time() - t, lanes=lanes, settings=S)
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1, default=float)
    return path


def lockup(out, quick=False, progress=True, workers: int | None = None) -> dict:
    """Run the setting `quick` (False: μL/ℓ 0.5–4 and the lock-up length, each at the base
    resolution, twice the segments and half the speed; True: μL/ℓ 0.5, 1, 2 at the base;
    "tiny": structure only) and write the files of the module docstring under `out`."""
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing as mp

    import jax

    jax.config.update("jax_enable_x64", True)  # the 3D rod's runs need it, and the closed forms beside them match
    S = SETTINGS[quick]
    os.makedirs(os.path.join(out, "jobs"), exist_ok=True)
    jobs = [(g, run, S, path, progress) for g, run, path in _missing(S, out)]
    jobs.sort(key=lambda j: -(len(j[0][1]) + (j[0][2] is not None)) * j[0][0] * j[1][0] / j[1][1])  # costliest first
    workers = workers or min(len(jobs), os.cpu_count() or 1) or 1
    t = time.time()
    if progress:
        print(f"  lock-up: {len(jobs)} staircase(s) to run on {workers} worker(s), f_c = {S['f_c']:g} F0", flush=True)
    pool = None if len(jobs) <= 1 or workers == 1 else ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"))
    try:
        for path in (pool.map(_job, jobs) if pool else map(_job, jobs)):
            if progress:
                print(f"  {os.path.basename(path)} done after {time.time() - t:.0f} s", flush=True)
    finally:
        if pool:
            pool.shutdown()
    wall = time.time() - t
    if not jobs:  # nothing run: the cost quoted stays that of the last call that ran staircases
        previous = os.path.join(out, "curve.json")
        wall = json.load(open(previous))["wall_s_this_call"] if os.path.exists(previous) else wall
    return _write(out, S, _results(S, out), wall)


def _write(out, S, results, wall):
    from ..lockup.push import push_rod

    from ..lockup.laws import helix_against_laws
    from ..lockup.staircase import crossing

    curve, stages, profiles, laws = [], [], [], []
    for res in results:
        rod = push_rod(res["L_over_ell"], R_OVER_ELL, 1.0)
        for lane in res["lanes"]:
            worst = min([s["segments_per_turn"] for s in lane["stages"] if s["status"] == "sliding"], default=math.inf)
            angle = max([s["helix_angle"] for s in lane["stages"] if s["status"] == "sliding"], default=0.0)
            base = dict(n_segments=res["n"], push_speed=res["speed"], status=lane["status"], entry_force_bound=res["f_c"],
                        segments_per_wave=res["per_wave"],
                        L_over_ell=res["L_over_ell"], stages=len(lane["stages"]), segments_per_turn_sliding=worst,
                        helix_angle_sliding_deg=angle)
            lo = math.nan if lane["lo"] is None else lane["lo"]
            hi = math.nan if lane["hi"] is None else lane["hi"]
            cross, cross_err = crossing(lane["stages"], res["f_c"]) or (math.nan, math.nan)
            closed = _closed(rod, 1.0 if lane["vary_mu"] else lane["X"], res["f_c"])
            at, unbounded = ("lock_at_fc", "lock") if lane["vary_mu"] else ("far_at_fc", "far_max")
            curve.append(dict(quantity=LOCK if lane["vary_mu"] else FAR,
                              muL_over_ell=math.nan if lane["vary_mu"] else lane["X"], n_segments=res["n"],
                              push_speed=res["speed"], protocol="staircase", kind="run", lo=lo, hi=hi,
                              status=lane["status"], crossing=cross, crossing_error=cross_err,
                              **{k: v for k, v in base.items() if k not in ("n_segments", "push_speed", "status")},
                              **{f"soft_{k}_at_fc": v[at] for k, v in closed.items()},
                              **{f"soft_{k}_unbounded": v[unbounded] for k, v in closed.items()}))
            for s in lane["stages"]:
                stages.append(dict(muL_over_ell=lane["X"], varies="mu" if lane["vary_mu"] else "far_load",
                                   n_segments=res["n"], push_speed=res["speed"], **{k: v for k, v in s.items()}))
            wave = 2 * math.pi * math.sqrt(res["ell"] * res["r"])
            for p in lane["profiles"]:
                hx = helix_against_laws(p["theta"], p["wall_force"], p["axial_force"], res["l0"], res["EI"], res["w"],
                                        res["r"], p["mu"], wave)
                laws.append(dict(muL_over_ell=lane["X"], varies="mu" if lane["vary_mu"] else "far_load",
                                 n_segments=res["n"], push_speed=res["speed"], parameter=p["parameter"],
                                 entry_force_over_F0=p["f_in"], helical_compared_over_ell=hx["inner_length"] / res["ell"],
                                 F_lo_over_F0=hx["F_range"][0] / res["F0"], F_hi_over_F0=hx["F_range"][1] / res["F0"],
                                 pitch_over_lubinski=hx["pitch_ratio"], N_over_mitchell=hx["N_ratio"],
                                 N_over_mitchell_plus_w=hx["N_ratio_with_weight"],
                                 dF_ds_over_mu_N=hx["soft_string_ratio"],
                                 whole_rod_dF_over_mu_int_N=hx["soft_string_ratio_whole"],
                                 winding_over_ell=hx["winding_length"] / res["ell"], hand_reversals=hx["reversals"],
                                 winding_int_N_over_int_mitchell=hx["wall_ratio_winding"]))
            p = lane["profiles"][-1] if lane["profiles"] else None
            if p is not None:
                for i, (th, N) in enumerate(zip(p["theta"], p["wall_force"])):
                    F = p["axial_force"][min(i, len(p["axial_force"]) - 1)]
                    profiles.append(dict(muL_over_ell=lane["X"], n_segments=res["n"], push_speed=res["speed"],
                                         parameter=p["parameter"], node=i, s_from_far_end=i * res["l0"], theta=th,
                                         wall_force=N, axial_force=F, mu=p["mu"], EI=res["EI"], w=res["w"], r=res["r"]))
    onsets = _onsets(results)
    job_walls = {(r["L_over_ell"], r["per_wave"], r["speed"], r["wall_s"]): r["wall_s"] for r in results}  # per job
    others = protocol_rows(out, S["f_c"], S["runs"][0][0]) if S.get("converge") else []  # the full setting's points
    curve += converged(curve + others, S) + others
    curve += single_step_rows(out, S["f_c"], stages) if S.get("converge") else []
    cols = list(dict.fromkeys(k for r in curve for k in r))  # the converged rows' columns, empty in the runs'
    curve = [{k: r.get(k, math.nan) for k in cols} for r in curve]
    write_csv(os.path.join(out, "onsets.csv"), onsets)
    write_csv(os.path.join(out, "curve.csv"), curve)
    write_csv(os.path.join(out, "stages.csv"), stages)
    write_csv(os.path.join(out, "profiles.csv"), profiles)
    write_csv(os.path.join(out, "helix_laws.csv"), laws)
    summary = dict(model="rod3d", scheme="implicit", r_over_ell=R_OVER_ELL, damping=DAMPING, f_c=S["f_c"],
                   settings=S, wall_s_this_call=wall, jobs_wall_s=list(job_walls.values()),  # wall: the last call that ran staircases
                   curve=curve, helix_laws=laws, onsets=onsets)
    with open(os.path.join(out, "curve.json"), "w") as fh:
        json.dump(summary, fh, indent=1, default=float)
    _figure(out, S, curve)
    return summary


def _onsets(results):
    """Per setting (segments per wave, speed): the sinusoidal and helical onsets bracketed by the
    steady stages — the largest steady entry force [F₀] without a sinusoid (a helix) at the end
    of the stage and the smallest with one (`push.extents`: a helix shorter than about one buckle
    wavelength is not told from a sinusoid, so the helical bracket is that of a helix at least
    that long)."""
    rows = []
    for per_wave, speed in sorted({(r["per_wave"], r["speed"]) for r in results}, key=lambda k: (k[0], -k[1])):
        pts = [(s["f_in"], s["sinusoidal"] + s["helical"], s["helical"])
               for r in results if (r["per_wave"], r["speed"]) == (per_wave, speed)
               for lane in r["lanes"] for s in lane["stages"] if s["status"] == "sliding"]
        row = dict(segments_per_wave=per_wave, push_speed=speed, steady_stages=len(pts))
        for name, col in (("sinusoidal", 1), ("helical", 2)):
            row[f"{name}_onset_lo"] = max([p[0] for p in pts if p[col] == 0], default=math.nan)
            row[f"{name}_onset_hi"] = min([p[0] for p in pts if p[col] > 0], default=math.nan)
            row[f"{name}_inconsistent"] = sum(1 for p in pts if p[col] == 0 and p[0] > row[f"{name}_onset_hi"])
        rows.append(row)
    return rows


def _figure(out, S, curve):
    import jax.numpy as jnp

    from ..lockup import chain
    from ..lockup.push import push_rod, units
    from ..output import subplots

    rod = push_rod(4.0, R_OVER_ELL, 1.0)
    F0, ell = units(rod)
    EI, w, r, L = float(rod.EI), float(rod.rho * rod.g), float(rod.R), float(rod.L)
    fig, ax = subplots(1, 1, figsize=(7.5, 5))
    X = np.linspace(0.3, 5.0, 300)
    for (onset, law), c in zip(VARIANTS, ("C0", "C1", "C2", "C3")):
        kw = dict(helical_onset=onset, helical_law=law)
        mu = jnp.asarray(X * ell / L)
        at = np.asarray(chain.far_force(S["f_c"] * F0, L, EI, w, r, mu, **kw)) / F0
        lim = np.asarray(chain.far_force_max(L, EI, w, r, mu, **kw)) / F0
        name = f"{onset.replace('_', ' ')}, {law.replace('_', ' ')}"
        ax.plot(X, at, "-", color=c, lw=1.2, label=f"{name}: at f_in = {S['f_c']:g}")
        ax.plot(X, lim, ":", color=c, lw=1, label=f"{name}: f_in → ∞")
    marks, path = {}, [r for r in curve if r["protocol"] != "staircase"]
    for row in curve:
        if row["kind"] != "run" or row["protocol"] != "staircase":
            continue
        key = (row["segments_per_wave"], row["push_speed"])
        style = marks.setdefault(key, ("k", "C4", "C5", "C6", "C7")[len(marks) % 5])
        dx = 0.04 * (list(marks).index(key) - 1)
        lo, hi = row["lo"], row["hi"]
        if row["quantity"] == LOCK:  # the lock-up length: a bracket along μL/ℓ at F_far = 0
            if np.isfinite(lo) and np.isfinite(hi):
                ax.plot([lo, hi], [-0.06 * (1 + list(marks).index(key))] * 2, "-", color=style, lw=3)
            continue
        if np.isfinite(lo) and np.isfinite(hi):
            ax.plot([row["muL_over_ell"] + dx] * 2, [lo, hi], "-", color=style, lw=3)
        elif np.isfinite(lo):
            ax.plot(row["muL_over_ell"] + dx, lo, "^", color=style)
        elif np.isfinite(hi):
            ax.plot(row["muL_over_ell"] + dx, hi, "v", color=style)
    done = [r for r in curve if r["kind"] == "converged"]
    far = [r for r in done if r["quantity"] == FAR]
    if far:
        ax.errorbar([r["muL_over_ell"] + 0.12 for r in far], [r["quasi_static"] for r in far],
                    yerr=[r["error_bar"] for r in far], fmt="o", color="C3", ms=4, capsize=3,
                    label="3D rod, quasi-static (v → 0) ± error bar")
    for r in done:
        if r["quantity"] == LOCK:
            ax.errorbar([r["quasi_static"]], [-0.06 * (len(marks) + 1)], xerr=[r["error_bar"]], fmt="o", color="C3",
                        ms=4, capsize=3)
    for r in path:  # one step from the straight rod to the staircase's lower bound: which side of it
        y = (-0.06 * (len(marks) + 2)) if r["quantity"] == LOCK else r["parameter"]
        x = r["parameter"] if r["quantity"] == LOCK else r["muL_over_ell"] - 0.12
        ax.plot(x, y, "^" if np.isfinite(r["lo"]) else "v", color="C9", ms=6, mfc="none")
    if path:
        ax.plot([], [], "^", color="C9", mfc="none", label="single step from straight: steady ≤ f_c (▲) or not (▼)")
    for key, style in marks.items():
        ax.plot([], [], "-", color=style, lw=4, label=f"3D rod, {key[0]} segments per wave, {1e3 * key[1]:g} mm/s")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set(xlabel="μL/ℓ (bars below 0: the lock-up length μL_lock(f_c)/ℓ)", ylabel="F_far,max / F₀", ylim=(-0.42, 6),
           title=f"largest far load pushed at an entry force ≤ {S['f_c']:g} F₀ (bars: 3D rod's brackets)")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "curve.png"), dpi=130)
