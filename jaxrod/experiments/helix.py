"""Post-buckling of the 3D rod: slow displacement-controlled loading past buckling into a helix
(frictionless), compared with the helical-buckling results of docs/physics.md §6, and a loading–
unloading cycle with friction and its hysteresis. `jaxrod reproduce helix` calls
[`post_buckling`][].

**Helix measures** (per saved state, on the middle half of the rod, s ∈ [L/4, 3L/4], away from
the pinned ends where the rod must leave the wall to reach the bottom):

- θ(s) unwrapped along the rod; `turns` = (θ(3L/4) − θ(L/4))/2π;
- `pitch` = 2π / |β| with β = dθ/ds the least-squares slope of θ(s) [m]; only for a *helix*:
  at least one turn over the middle half and θ(s) linear there (R² > 0.95);
- the axial force F (mean over the middle segments) [N] and the wall force per length [N/m],
  both its mean over the middle and N − w cos θ (the wall force with gravity's normal component
  removed), which for a helix is R F²/(4EI) along the whole turn (Mitchell); for a helix of any
  wavenumber β the small-slope beam equation EI u'''' + F u'' = −N e_r gives
  `N_equilibrium` = R β² (F − EI β²), which equals R F²/(4EI) at Lubinski's β² = F/(2EI);
- a node is *on the far side* when |θ| > π/2 (above the channel's axis height); the rod has
  *gone over the top* when some interior node has |θ| > π.

Theory (docs/physics.md §6): helical buckling starts between 2√2·√(EIw/R) (Chen, Lin & Cheatham)
and 4√2·√(EIw/R) (Mitchell); pitch p = π√(8EI/F) (Lubinski); contact force R F²/(4EI) + w
(Mitchell; + w is its value at the bottom of a turn, where gravity adds fully).
"""

from __future__ import annotations

import math
import os

import jax.numpy as jnp
import numpy as np

from .. import theory
from ..params import RodChannel
from ..integrators.base import save_grid
from ..output import subplots, write_csv
from ..integrators import default_step
from ..rod3d import Rod3D

__all__ = ["load_path", "helix_measures", "helix_theory", "post_buckling", "HELIX_SIZES"]

HELIX_SIZES = {
    # segments, pushing speed [m/s], largest end displacement [m], saves per second of loading
    "tiny": dict(n=12, speed=8e-3, d_max=2.4e-3, sps=50, hold=0.05),
    True: dict(n=30, speed=2e-3, d_max=7e-3, sps=25, hold=0.2),
    False: dict(n=60, speed=1e-3, d_max=7e-3, sps=20, hold=0.5),
}


def helix_theory(rod: RodChannel) -> dict:
    """The §6 numbers for `rod`: the helical onset band [N] and the pitch and contact-force laws."""
    c = math.sqrt(float(rod.EI) * float(rod.w) / float(rod.R))
    return dict(onset_chen=2.0 * math.sqrt(2.0) * c, onset_mitchell=4.0 * math.sqrt(2.0) * c,
                sinusoidal_onset=float(theory.reference_load(rod)))


def load_path(rod: RodChannel, n: int, stages, *, damping: float = 50.0, offset: float = 0.5e-3,
              sps: float = 20.0, progress: bool = True, scheme: str | None = None, dt: float | None = None) -> dict:
    """Run the rod through displacement-controlled `stages`, each `(speed [m/s], duration [s])`
    (speed > 0 pushes, < 0 pulls back, 0 holds), each stage starting from the previous one's
    final state. The rod starts straight on the channel bottom, unloaded, with a mode-6 lateral
    imperfection of `offset` [m] along the wall; mass-proportional viscous `damping` [1/s]
    removes the kinetic energy of snaps so that the path is close to quasi-static. `scheme` and `dt`
    [s]: the integrator (a key of `jaxrod.integrators.SCHEMES`; default the rod's) and its step
    (default the scheme's, `jaxrod.integrators.default_step`, at each stage's start).

    **Returns:** dict of NumPy arrays over all saves: `ts`, `d` (end displacement [m]),
    `reaction` (at the pushed end [N]), `x` (node positions), `normal_force`, `axial_force`,
    `energy` (total mechanical), `dissipated`, `work_in` [J], `stage` (index of each save's stage), and `dt` per stage.
    """
    parts, d0, D0, W0 = [], 0.0, 0.0, 0.0
    model = Rod3D(rod, n, control="displacement", damping=damping)
    s = jnp.arange(n + 1) / n
    from .rod3d import run

    state = model.initial_state(0.0, lateral_offset=offset * jnp.sin(6 * jnp.pi * s))
    dts, t0 = [], 0.0
    for k, (speed, duration) in enumerate(stages):
        model = Rod3D(rod, n, control="displacement", speed=speed, damping=damping)
        n_save = max(2, int(round(duration * sps)) + 1)
        if progress:
            print(f"  stage {k}: speed {speed * 1e3:+g} mm/s for {duration:g} s ({n} segments)", flush=True)
        h = default_step(model, state[0], scheme=scheme) if dt is None else dt
        sol = run(model, *state, duration, n_save, h, stop_on_buckle=False, save_state=True, scheme=scheme)
        if int(sol.result) != 0:
            raise FloatingPointError(f"stage {k} of the load path became non-finite (result {int(sol.result)}).")
        first = 0 if k == 0 else 1
        obs = {k: np.asarray(v) for k, v in sol.observables.items()}
        parts.append(dict(
            ts=np.asarray(sol.ts)[first:] + t0, d=d0 + (obs["end_x"][0] - obs["end_x"])[first:],
            reaction=obs["reaction"][first:, 1], x=np.asarray(sol.q.x)[first:],
            normal_force=obs["normal_force"][first:], axial_force=obs["axial_force"][first:],
            energy=np.asarray(sum(sol.energies.values()))[first:],
            dissipated=D0 + np.asarray(sol.dissipated)[first:], work_in=W0 + np.asarray(sol.work_in)[first:],
            stage=np.full(n_save - first, k),
        ))
        d0, D0, W0 = float(parts[-1]["d"][-1]), float(parts[-1]["dissipated"][-1]), float(parts[-1]["work_in"][-1])
        dts.append(save_grid(duration, n_save, h)[1])
        state, t0 = (sol.q_final, sol.v_final), t0 + duration
    out = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    out["dt"] = np.asarray(dts)
    return out


def helix_measures(rod: RodChannel, x, normal_force, axial_force) -> dict:
    """Helix measures (module docstring) for node positions `x` (..., n+1, 3) [m], wall force per
    length `normal_force` (..., n+1) [N/m] and axial force `axial_force` (..., n) [N]."""
    x = np.asarray(x)
    n = x.shape[-2] - 1
    s = np.linspace(0.0, float(rod.L), n + 1)
    theta = np.unwrap(np.arctan2(x[..., 1], -x[..., 2]), axis=-1)
    mid = (s >= 0.25 * float(rod.L)) & (s <= 0.75 * float(rod.L))
    sm, tm = s[mid], theta[..., mid]
    dev = tm - tm.mean(-1, keepdims=True)
    slope = (dev * (sm - sm.mean())).sum(-1) / ((sm - sm.mean()) ** 2).sum()
    resid = dev - slope[..., None] * (sm - sm.mean())
    r2 = 1.0 - (resid**2).sum(-1) / np.maximum((dev**2).sum(-1), 1e-300)
    turns = (tm[..., -1] - tm[..., 0]) / (2.0 * np.pi)
    helical = (np.abs(turns) >= 1.0) & (r2 > 0.95)
    segs = np.arange(n)
    smid = (segs + 0.5) / n
    F = np.asarray(axial_force)[..., (smid >= 0.25) & (smid <= 0.75)].mean(-1)
    N = np.asarray(normal_force)[..., mid]
    return dict(
        theta=theta, turns=turns, beta=np.abs(slope), linearity=r2, helical=helical,
        pitch=np.where(helical, 2.0 * np.pi / np.maximum(np.abs(slope), 1e-300), np.inf),
        F=F, N_mean=N.mean(-1), N_minus_gravity=(N - float(rod.w) * np.cos(tm)).mean(-1),
        N_equilibrium=float(rod.R) * slope**2 * (F - float(rod.EI) * slope**2),
        N_bottom=np.where(helical, np.max(np.where(np.cos(tm) > 0.9, N, -np.inf), -1), np.nan),
        over_top=np.max(np.abs(theta[..., 1:-1]), -1) > np.pi,
        max_abs_theta=np.max(np.abs(theta[..., 1:-1]), -1),
    )


def _loop_area(d, F):
    """∮ F dd over a closed path [J] (trapezoid rule; positive for a clockwise loop in (d, F))."""
    return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(d)))


def post_buckling(out, quick=False, progress=True) -> dict:
    """The post-buckling experiment: a frictionless rod pushed slowly (displacement control,
    viscous damping 50 1/s) past sinusoidal buckling into a helix, held, then pulled back; and
    the same cycle at μ = 0.3. Writes `helix_post_buckling.png`, `helix_post_buckling.csv`."""
    S = HELIX_SIZES[quick]
    n, v, d_max, hold = S["n"], S["speed"], S["d_max"], S["hold"]
    stages = [(v, d_max / v), (0.0, hold), (-v, d_max / v), (0.0, hold)]
    res = {"model": "rod3d", "n_segments": n, "speed_m_s": v, "d_max_m": d_max, "damping_1_s": 50.0,
           "imperfection": "mode-6 lateral offset 0.5 mm", "hold_s": hold}
    rows, runs = [], {}
    for mu in (0.0, 0.3):
        rod = RodChannel.reference(mu)
        if progress:
            print(f"  post-buckling μ = {mu}: load to {d_max * 1e3:g} mm, hold, unload", flush=True)
        p = load_path(rod, n, stages, sps=S["sps"], progress=progress)
        h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
        runs[mu] = (p, h)
        loading = p["stage"] == 0
        held = np.flatnonzero(p["stage"] == 1)[-1]  # the end of the hold at d_max
        r = {"dt": p["dt"].tolist(),
             "energy_balance_max_J": float(np.max(np.abs(p["energy"] - p["energy"][0] + p["dissipated"] - p["work_in"]))),
             "work_in_J": float(p["work_in"][-1]), "dissipated_J": float(p["dissipated"][-1]),
             "loop_area_J": _loop_area(p["d"], p["reaction"]),
             "peak_reaction_N": float(p["reaction"][loading].max()),
             "turns_at_d_max": float(h["turns"][held]),
             "turns_after_unloading": float(h["turns"][-1]),
             "max_abs_theta_after_unloading": float(h["max_abs_theta"][-1])}
        over = np.flatnonzero(h["over_top"] & loading)
        if over.size:
            i = int(over[0])
            r["over_the_top"] = {"reaction_N": float(p["reaction"][i]), "axial_force_mid_N": float(h["F"][i]),
                                 "reaction_save_before_N": float(p["reaction"][max(i - 1, 0)]),
                                 "d_mm": float(p["d"][i] * 1e3)}
        full = np.flatnonzero((np.abs(h["turns"]) >= 1.0) & loading)
        if full.size:
            i = int(full[0])
            r["first_full_turn_mid"] = {"reaction_N": float(p["reaction"][i]), "axial_force_mid_N": float(h["F"][i]),
                                        "d_mm": float(p["d"][i] * 1e3)}
        F = float(h["F"][held])
        r["state_at_d_max"] = {"axial_force_N": F, "turns_mid": float(h["turns"][held]),
                               "theta_linearity_r2": float(h["linearity"][held]), "helix": bool(h["helical"][held])}
        if h["helical"][held]:
            r["helix_at_d_max"] = {
                "axial_force_N": F, "pitch_m": float(h["pitch"][held]),
                "N_equilibrium_N_m": float(h["N_equilibrium"][held]),
                "pitch_lubinski_m": math.pi * math.sqrt(8.0 * float(rod.EI) / F),
                "N_mean_N_m": float(h["N_mean"][held]), "N_minus_gravity_N_m": float(h["N_minus_gravity"][held]),
                "N_bottom_N_m": float(h["N_bottom"][held]),
                "mitchell_RF2_4EI_N_m": float(rod.R) * F**2 / (4.0 * float(rod.EI)),
                "mitchell_plus_w_N_m": float(rod.R) * F**2 / (4.0 * float(rod.EI)) + float(rod.w)}
        hx = loading & h["helical"]
        if hx.any():
            # over every helical save of the loading: the measured axial force against Lubinski's
            # F = 2 EI β², and the wall force against the helix equilibrium R β² (F − EI β²)
            lub = h["F"][hx] / (2.0 * float(rod.EI) * h["beta"][hx] ** 2)
            eq = h["N_minus_gravity"][hx] / h["N_equilibrium"][hx]
            r["helical_saves_loading"] = {
                "count": int(hx.sum()),
                "F_over_lubinski_median_min_max": [float(np.median(lub)), float(lub.min()), float(lub.max())],
                "N_over_equilibrium_median_min_max": [float(np.median(eq)), float(eq.min()), float(eq.max())]}
        res[f"mu={mu}"] = r
        for i in range(len(p["ts"])):
            rows.append(dict(mu=mu, t=p["ts"][i], stage=int(p["stage"][i]), d=p["d"][i], reaction=p["reaction"][i],
                             axial_force_mid=h["F"][i], turns_mid=h["turns"][i], pitch=h["pitch"][i],
                             N_mean=h["N_mean"][i], N_minus_gravity=h["N_minus_gravity"][i],
                             max_abs_theta=h["max_abs_theta"][i]))
    th = helix_theory(RodChannel.reference(0.0))
    res["theory"] = th
    if out is not None:
        _figure(out, runs, th, n)
        write_csv(os.path.join(out, "helix_post_buckling.csv"), rows)
    return res


def _figure(out, runs, th, n):

    fig, axes = subplots(1, 4, figsize=(21, 4.6))
    for mu, (p, h) in runs.items():
        axes[0].plot(p["d"] * 1e3, p["reaction"], lw=0.9, label=f"μ = {mu}")
        axes[1].plot(p["ts"], h["turns"], lw=0.9, label=f"μ = {mu}")
    for F, name in ((th["onset_chen"], "2√2√(EIw/R) (Chen)"), (th["onset_mitchell"], "4√2√(EIw/R) (Mitchell)"),
                    (th["sinusoidal_onset"], "F⁰₆ (sinusoidal)")):
        axes[0].axhline(F, ls=":", lw=0.8, color="k")
        axes[0].text(0.0, F, " " + name, fontsize=7, va="bottom")
    axes[0].set_xlabel("end displacement [mm]")
    axes[0].set_ylabel("reaction at the pushed end [N]")
    axes[0].set_title(f"loading–unloading cycle ({n} segments, damping 50 1/s)", fontsize=9)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("turns of θ over the middle half")
    axes[1].set_title("helical turns (load, hold, unload, hold)", fontsize=9)
    axes[1].legend(fontsize=7)
    p, h = runs[0.0]
    held = np.flatnonzero(p["stage"] == 1)[-1]
    s = np.linspace(0.0, 3.0, h["theta"].shape[-1])
    axes[2].plot(s, h["theta"][held] / (2 * np.pi), label=f"μ = 0, end of hold, F = {h['F'][held]:.2f} N")
    p3, h3 = runs[0.3]
    held3 = np.flatnonzero(p3["stage"] == 1)[-1]
    axes[2].plot(s, h3["theta"][held3] / (2 * np.pi), label=f"μ = 0.3, end of hold, F = {h3['F'][held3]:.2f} N")
    axes[2].set_xlabel("s [m]")
    axes[2].set_ylabel("θ / 2π (turns)")
    axes[2].set_title("unwrapped angle along the rod at the largest displacement", fontsize=9)
    axes[2].legend(fontsize=7)
    hx = (p["stage"] == 0) & h["helical"]
    rod = RodChannel.reference(0.0)
    b2 = h["beta"][hx] ** 2
    axes[3].plot(b2, h["F"][hx], ".", ms=3, label="axial force F (middle), μ = 0 loading")
    axes[3].plot(b2, 2.0 * float(rod.EI) * b2, "k-", lw=0.8, label="Lubinski: F = 2EIβ² (p = π√(8EI/F))")
    axes[3].plot(b2, h["N_minus_gravity"][hx] * 1.0, ".", ms=3, label="wall force − w cos θ [N/m]")
    axes[3].plot(b2, float(rod.R) * b2 * (h["F"][hx] - float(rod.EI) * b2), "x", ms=3,
                 label="helix equilibrium Rβ²(F − EIβ²) [N/m]")
    axes[3].set_xlabel("β² = (2π/pitch)² [1/m²]")
    axes[3].set_ylabel("[N] or [N/m]")
    axes[3].set_title("helix relations over the frictionless loading", fontsize=9)
    axes[3].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "helix_post_buckling.png"), dpi=130)
