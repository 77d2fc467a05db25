"""E1 at μ = 0: the critical force against the pushing speed.

The frictionless rod of E1 reaches a peak force above F⁰₆ that falls with the perturbation v₀
(2.84 → 2.0 N for v₀ = 5 → 30 mm/s at 1 mm/s); the paper reports a frictionless critical force
independent of v₀. The explanation tested here is the **delayed bifurcation of a slowly swept
load**: pushed at speed s the load rises at r = EA·s/L (45 N/s at 1 mm/s for the reference
rod); past F⁰ mode 6 grows at λ(F) with λ² ∝ F − F⁰, so the amplitude needs
∫λ dt = (2/3)(κ²r/ρ)^{1/2} t^{3/2} = Λ = ln(A_buckled/A₀) to become visible, and the load has
overshot F⁰ by

    F_c − F⁰ ∝ (Λ · r)^{2/3} ∝ s^{2/3} · ln(A_buckled/A₀)^{2/3},

which vanishes as s → 0 and falls (logarithmically) as v₀, and with it A₀, grows. Measured
here in two ways: the field model (n nodes) under the same load ramp F(t) = r·t, the critical
force being the load when max|θ| passes `threshold` (cheap: many speeds and amplitudes), and the
3D rod pushed at three speeds (`e1_curves`: the peak reaction, as in E1) for the two smallest
amplitudes: under a slow push the lateral vibration of a larger v₀ modulates the reaction by
about EA(R A ω₆)²/4 with A = v₀/(R ω₆) (≈ 1 N at 30 mm/s, 0.12 N at 10 mm/s), which hides the
breakdown of the linear response.
"""

from __future__ import annotations

import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import theory
from ..integrators import ProjectedVerlet
from ..integrators.base import RunOptions
from ..loads import RampLoad
from ..models import FieldModel
from ..output import subplots, write_csv
from ..params import RodChannel
from ..perturbations import SineVelocity
from ..simulate import simulate
from ..stability_map import fit_power_law
from .rod3d import e1_curves

__all__ = ["field_ramp_force", "e1_speed", "SIZES"]

# field: speeds [m/s] and amplitudes [m/s]; 3D rod: speeds, amplitudes, segments
SIZES = {
    "tiny": dict(field_speeds=(1e-3, 1e-4), v0s=(5e-3, 30e-3), rod_speeds=(), v0s_3d=(), n3d=12),
    True: dict(field_speeds=(3e-3, 1e-3, 3e-4, 1e-4), v0s=(5e-3, 15e-3, 30e-3), rod_speeds=(1e-3, 3e-4),
               v0s_3d=(5e-3, 10e-3), n3d=40),
    False: dict(field_speeds=(3e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4, 5e-5, 3e-5, 1e-5),
                v0s=(5e-3, 10e-3, 15e-3, 20e-3, 25e-3, 30e-3), rod_speeds=(1e-3, 3e-4, 1e-4),
                v0s_3d=(5e-3, 10e-3), n3d=60),
}
FIT_RANGE = (1e-4, 3e-3)  # speeds [m/s] of the exponent fit (below, the phase of the
#                           mode-6 oscillation at the passage through F⁰ scatters the delay)


@eqx.filter_jit
def _ramp_runs(model, v0s, dt, t1, threshold):
    def one(v0):
        q0, v = SineVelocity(v0).initial_state(model)
        opts = RunOptions(buckle_threshold=threshold, stop_when_stuck=False, save_state=False)
        sol = simulate(model, ProjectedVerlet(dt), q0, v, t1, n_save=2, options=opts)
        return sol.t_buckle, sol.buckled

    return jax.vmap(one)(v0s)


def field_ramp_force(rod: RodChannel, speed: float, v0s, n: int = 128, threshold: float = 0.5,
                     F_max: float = 12.0) -> np.ndarray:
    """The load F_c [N] at which the field model (`n` nodes) pushed at `speed` [m/s] — the load
    rising as F = (EA·speed/L)·t from 0 — passes max|θ| = `threshold` [rad] after a sine mode-6
    lateral velocity of each amplitude in `v0s` [m/s] (NaN: not buckled below `F_max`)."""
    rate = float(rod.EA) * speed / float(rod.L)
    t1 = float(F_max / rate)
    model = FieldModel.from_rod(rod, n, F=RampLoad(0.0, F_max, 0.0, t1))
    dt = 0.4 * 2.0 / float(model.max_frequency())  # the highest frequency of the ramp: at its smallest load
    t_b, buckled = _ramp_runs(model, jnp.asarray(v0s, float), dt, t1, threshold)
    return np.where(np.asarray(buckled), rate * np.asarray(t_b), np.nan)


def _exponent(speeds, overshoot):
    speeds, overshoot = np.asarray(speeds), np.asarray(overshoot)
    ok = (speeds >= FIT_RANGE[0]) & (speeds <= FIT_RANGE[1]) & np.isfinite(overshoot) & (overshoot > 0)
    return fit_power_law(speeds[ok], overshoot[ok])[:2] if ok.sum() >= 2 else (float("nan"), float("nan"))


def e1_speed(out, quick=False, progress=True, n_field: int = 128, known=None):
    """E1 at μ = 0 against the pushing speed: field model under the equivalent load ramp (all
    `SIZES` speeds and amplitudes) and the 3D rod (`e1_curves`) at the `SIZES` speeds. Writes
    e1_speed.csv / .png under `out`; returns the numbers and the fitted exponents of F_c − F⁰₆
    against speed (theory of the delayed bifurcation: 2/3). `known`: {(speed, v0): F_c} of 3D
    runs already made with the same settings (E1's own runs at 1 mm/s), not run again."""
    S = SIZES[quick]
    rod = RodChannel.reference(0.0)
    F0 = float(theory.reference_load(rod))
    rows, field = [], {}
    if progress:
        print(f"  E1 μ = 0 against speed: field model, {len(S['field_speeds'])} speeds × "
              f"{len(S['v0s'])} amplitudes, {n_field} nodes", flush=True)
    for sp in S["field_speeds"]:
        fc = field_ramp_force(rod, sp, S["v0s"], n=n_field)
        field[sp] = fc
        rows += [dict(model="field", n=n_field, speed_m_s=sp, v0_m_s=v0, critical_force_N=f, overshoot_N=f - F0)
                 for v0, f in zip(S["v0s"], fc)]
    speeds = np.array(S["field_speeds"])
    fc_field = np.array([field[sp] for sp in S["field_speeds"]])  # (speeds, v0s)
    exps = [_exponent(speeds, fc_field[:, k] - F0) for k in range(len(S["v0s"]))]
    rod3d = {}
    known = known or {}
    for sp in S["rod_speeds"]:
        if all((sp, v0) in known for v0 in S["v0s_3d"]):
            rod3d[sp] = np.array([known[sp, v0] for v0 in S["v0s_3d"]])
        else:
            if progress:
                print(f"  E1 μ = 0 against speed: 3D rod, {S['n3d']} segments, {sp * 1e3:g} mm/s, "
                      f"{len(S['v0s_3d'])} amplitudes", flush=True)
            r = e1_curves(0.0, S["v0s_3d"], n=S["n3d"], speed=sp, t1=0.8, n_save=801)
            rod3d[sp] = np.where(r["peaked"], r["critical_force"], np.nan)
        rows += [dict(model="rod3d", n=S["n3d"], speed_m_s=sp, v0_m_s=v0, critical_force_N=f, overshoot_N=f - F0)
                 for v0, f in zip(S["v0s_3d"], rod3d[sp])]
    exps3d = [_exponent(np.array(S["rod_speeds"]), np.array([rod3d[sp][k] for sp in S["rod_speeds"]]) - F0)
              for k in range(len(S["v0s_3d"]))] if len(S["rod_speeds"]) >= 2 else []
    write_csv(os.path.join(out, "e1_speed.csv"), rows)
    _plot(os.path.join(out, "e1_speed.png"), S, F0, speeds, fc_field, rod3d)
    return {
        "mu": 0.0, "F0_6": F0, "threshold_field_rad": 0.5, "n_field": n_field, "n_segments_3d": S["n3d"],
        "load_rate_N_per_s_at_1mm_s": float(rod.EA) * 1e-3 / float(rod.L),
        "field": {"speeds_m_s": list(S["field_speeds"]), "v0_m_s": list(S["v0s"]),
                  "critical_force_N": fc_field.tolist(),
                  "overshoot_exponent": [e for e, _ in exps], "overshoot_exponent_stderr": [s for _, s in exps],
                  "fit_speeds_m_s": list(FIT_RANGE)},
        "rod3d": {"speeds_m_s": list(S["rod_speeds"]), "v0_m_s": list(S["v0s_3d"]),
                  "critical_force_N": [rod3d[sp].tolist() for sp in S["rod_speeds"]],
                  "overshoot_exponent": [e for e, _ in exps3d]},
        "theory_exponent": 2.0 / 3.0,
    }


def _plot(path, S, F0, speeds, fc_field, rod3d):
    fig, axes = subplots(1, 2, figsize=(11, 4.2))
    for k, v0 in enumerate(S["v0s"]):
        axes[0].loglog(speeds * 1e3, fc_field[:, k] - F0, "o-", ms=3, label=f"field, v₀ = {v0 * 1e3:g} mm/s")
    for k, v0 in enumerate(S["v0s_3d"]):
        sp = np.array(S["rod_speeds"])
        if len(sp):
            axes[0].loglog(sp * 1e3, np.array([rod3d[s][k] for s in S["rod_speeds"]]) - F0, "ks--", mfc="none",
                           label=f"3D rod (peak reaction), v₀ = {v0 * 1e3:g} mm/s" if k == 0 else None)
    ref = speeds[(speeds >= FIT_RANGE[0]) & (speeds <= FIT_RANGE[1])]
    if len(ref):
        y0 = np.nanmedian(fc_field[list(speeds).index(ref[0])] - F0)
        axes[0].loglog(ref * 1e3, y0 * (ref / ref[0]) ** (2 / 3), "k:", label="∝ speed^(2/3) (delayed bifurcation)")
    axes[0].set_xlabel("pushing speed [mm/s]")
    axes[0].set_ylabel("F_c − F⁰₆ [N]")
    axes[0].set_title("E1, μ = 0: overshoot of the critical force past F⁰₆", fontsize=9)
    axes[0].legend(fontsize=6)
    for i, sp in enumerate(speeds):
        axes[1].plot(np.array(S["v0s"]) * 1e3, fc_field[i], "o-", ms=3, label=f"{sp * 1e3:g} mm/s")
    axes[1].axhline(F0, color="k", lw=0.8, ls=":", label="F⁰₆")
    axes[1].set_xlabel("v₀ [mm/s]")
    axes[1].set_ylabel("critical force F_c [N] (field model)")
    axes[1].set_title("the v₀ dependence shrinks with the pushing speed", fontsize=9)
    axes[1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
