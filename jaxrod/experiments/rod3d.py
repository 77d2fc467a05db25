"""The reference paper's full-model experiments with the 3D rod: E1's runs under displacement
control (`e1_curves`; the experiment is `experiments.e1`), the assumption checks of E6, and the
cross-check of the critical sine velocity against the field model. Each returns a dict of
numbers and writes PNG + CSV; `jaxrod reproduce e1|e6` calls them."""

from __future__ import annotations

import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import theory
from .._results import RESULTS
from ..params import RodChannel
from ..integrators import default_for, default_step
from ..integrators.base import RunOptions
from ..output import subplots, write_csv
from ..simulate import simulate
from ..rod3d import Rod3D, sine_velocity, step_limit

__all__ = ["run", "e1_curves", "e6_full", "crosscheck_critical_velocity", "rolling_check", "SIZES"]

SIZES = {
    "tiny": dict(n=12, v0s=(10e-3, 30e-3), conv=(12,), t1=0.4, n_save=201, dFs=(), n_cross=12),
    True: dict(n=40, v0s=(5e-3, 15e-3, 30e-3), conv=(20, 40, 60), t1=0.6, n_save=601, dFs=(1.0, 5.0, 20.0), n_cross=40),
    False: dict(n=60, v0s=(5e-3, 10e-3, 15e-3, 20e-3, 25e-3, 30e-3), conv=(30, 60, 120), t1=0.8,
                n_save=801, dFs=(1.0, 5.0, 20.0, 60.0), n_cross=60),
}


def run(model, q0, v0, t1, n_save, dt, *, threshold=0.5, stop_on_buckle=True, stop_when_stuck=True,
        save_state=False, progress=False, scheme=None):
    """One [`jaxrod.simulate`][] run of the 3D rod with its default scheme (the implicit leapfrog,
    `jaxrod.integrators.default_for`) or `scheme` (a key of `jaxrod.integrators.SCHEMES`) and the
    options of [`jaxrod.RunOptions`][] (same names and defaults; vmap it for a batch, without
    `progress`)."""
    opts = RunOptions(buckle_threshold=threshold, stop_on_buckle=stop_on_buckle,
                      stop_when_stuck=stop_when_stuck, save_state=save_state, progress=progress)
    return simulate(model, default_for(model, float(dt), scheme), q0, v0, t1, n_save=n_save, options=opts, throw=False)


def _batched(model, states, t1, n_save, dt, threshold, stop_on_buckle=True, stop_when_stuck=True, scheme=None):
    """A vmapped batch of runs from the batched initial states `(q0s, v0s)`."""
    return jax.vmap(lambda q, v: run(model, q, v, t1, n_save, dt, threshold=threshold, stop_on_buckle=stop_on_buckle,
                                     stop_when_stuck=stop_when_stuck, scheme=scheme))(*states)


def _first(states):
    return jax.tree_util.tree_map(lambda a: a[0], states[0])


def e1_curves(mu, v0s, n=60, speed=1e-3, t1=0.8, n_save=801, rod=None, dt_fraction=None, scheme=None, dt=None):
    """Reaction force against end displacement for a rod pushed at `speed` [m/s] from rest with
    a sine mode-6 lateral velocity of each amplitude in `v0s` [m/s] (one vmapped batch). The
    run of a member stops once it has clearly buckled (max θ > 1 rad, past the force peak).
    The scheme is the rod's default or `scheme` (a key of `jaxrod.integrators.SCHEMES`), the step
    `dt` [s], or the scheme's default (`jaxrod.integrators.default_step`), or `dt_fraction` × the explicit limit 2/ω_max at the
    initial state.

    **Returns:** dict with `displacement` (n_save,) [m], `reaction` (B, n_save) at the pushed
    end [N], `critical_force` (B,) the first peak, where the linear response breaks down [N],
    `d_critical` [m], `buckled`, `peaked` (the reaction fell 10 % below its running maximum:
    the peak is a peak, not the end of the run; a slow push can peak without reaching 1 rad),
    `steps` (steps each member took: runs stop once buckled), `dt`.
    """
    rod = RodChannel.reference(mu) if rod is None else rod
    model = Rod3D(rod, n, control="displacement", speed=speed)
    states = jax.vmap(lambda v0: model.initial_state(0.0, lateral_velocity=sine_velocity(model, v0)))(jnp.asarray(v0s))
    if dt is None:
        dt = (default_step(model, _first(states), scheme) if dt_fraction is None
              else dt_fraction * step_limit(model, _first(states)))
    sol = _batched(model, states, t1, n_save, dt, 1.0, scheme=scheme)
    ts = np.linspace(0.0, t1, n_save)
    R = np.asarray(sol.observables["reaction"][..., 1])
    end_x = np.asarray(sol.observables["end_x"])
    D = end_x[:, :1] - end_x
    buckled = np.asarray(sol.buckled)
    # the critical force: the peak where the linear response first breaks down, i.e. the
    # running maximum at the first save where the reaction has fallen 10 % below it (later
    # peaks of a frictionless rod slapping in the channel are post-buckling dynamics), once the
    # maximum has passed the frictionless load F⁰₆ (no mode loses its stiffness below it: under
    # a slow push the lateral vibration of a large v₀ modulates the early reaction by about
    # EA(R A ω₆)²/4, ≈ 1 N at 30 mm/s, which is not buckling)
    run_max = np.maximum.accumulate(R, axis=1)
    broke = (R < 0.9 * run_max) & (run_max > float(theory.reference_load(rod)))
    first = np.where(broke.any(1), np.argmax(broke, axis=1), R.shape[1] - 1)
    i = np.array([int(np.argmax(R[k, : first[k] + 1])) for k in range(len(v0s))])
    return dict(ts=ts, displacement=D, reaction=R, critical_force=R[np.arange(len(v0s)), i],
                d_critical=D[np.arange(len(v0s)), i], buckled=buckled, peaked=broke.any(1), n=n, dt=_used_step(t1, n_save, dt),
                steps=np.asarray(sol.n_steps), balance=np.asarray(jnp.max(jnp.abs(sol.energy_balance), axis=1)))


def _used_step(t1, n_save, dt) -> float:
    from ..integrators.base import save_grid

    return save_grid(t1, n_save, dt)[1]


def e6_full(out, quick=False, progress=True):
    """E6 in the full model: μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s, ends held after pre-compression
    (as the paper). Torsional and shear energy over the total; normal-force uniformity and
    axial-force variation before buckling; lift-off; modal spectra before and after."""
    from ..modal import modal_spectrum

    S = SIZES[quick]
    n = S["n"]
    rod = RodChannel.reference(0.3)
    F0 = float(theory.reference_load(rod))
    F0cr = float(theory.critical_load_continuous(rod))
    model = Rod3D(rod, n)
    q0, v0 = model.initial_state(F0 + 5.0, lateral_velocity=sine_velocity(model, 35e-3))
    if progress:
        print(f"  E6 (full model): {n} segments, 0.1 s", flush=True)
    sol = run(model, q0, v0, 0.1, 201, default_step(model, q0), stop_on_buckle=False, stop_when_stuck=False)
    ts = np.asarray(sol.ts)
    E = {k: np.asarray(v) for k, v in sol.energies.items()}
    total = sum(E.values())
    # "before buckling": until the amplitude passes 0.1 rad (2.4 × the stick-line amplitude A_cr)
    amp = np.asarray(sol.amplitude)
    i_b = int(np.argmax(amp > 0.1)) if np.any(amp > 0.1) else len(ts)
    pre = slice(1, max(i_b, 2))
    Nn = np.asarray(sol.observables["normal_force"])[:, 1:-1] / float(rod.w)
    Fx = np.asarray(sol.observables["axial_force"])
    theta = np.asarray(sol.observables["theta"])[:, 1:-1]
    nm = min(40, n - 1)
    p_before = np.asarray(modal_spectrum(theta[1], nm))
    i_after = min(i_b + 10, len(ts) - 1)  # 10 saves past 0.1 rad
    p_after = np.asarray(modal_spectrum(theta[i_after], nm))
    res = {
        "model": "rod3d", "n_segments": n, "case": "μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s, ends held",
        "t_amplitude_0.1rad": float(ts[i_b]) if i_b < len(ts) else None,
        "twist_over_total_max": float(np.max(E["twist"] / total)),
        "shear_over_total_max": float(np.max(E["shear"] / total)),
        "normal_force_over_w_before": [float(Nn[pre].min()), float(Nn[pre].max())],
        "axial_force_variation_before_over_F0cr": float(np.max(Fx[pre].max(1) - Fx[pre].min(1)) / F0cr),
        "axial_force_mean_before": float(Fx[pre].mean()),
        "max_lift_off_gap_over_R": float(np.max(np.asarray(sol.observables["gap"])) / float(rod.R)),
        "max_theta": float(np.max(amp)),
        "dominant_mode_before": int(np.argmax(p_before)) + 1,
        "dominant_mode_after": int(np.argmax(p_after)) + 1,
        "dominant_power_after": float(np.max(p_after)),
        "energy_balance_max_J": float(np.max(np.abs(np.asarray(sol.energy_balance)))),
        "dissipated_J": float(sol.dissipated[-1]),
    }
    _figure(os.path.join(out, "e6_full_model.png"), ts, E, pre, Nn, Fx / F0cr, (p_before, p_after, ts[1], ts[i_after]))
    gap = np.asarray(sol.observables["gap"])
    rows = [dict(t=t, **{k: E[k][i] for k in E}, gap=float(gap[i]), amplitude=amp[i]) for i, t in enumerate(ts)]
    write_csv(os.path.join(out, "e6_full_model.csv"), rows)
    return res


def crosscheck_critical_velocity(dFs, n=60, mu=0.3, t1=0.4, grid=9, rounds=2, progress=True, friction_at="surface",
                                 ends="pinned"):
    """The critical sine mode-6 velocity v₀* [m/s] at each ΔF from the 3D rod under a dead load
    F = F⁰₆ + ΔF (as the field model) and from the field model (boundary search). The 3D value
    is bracketed by `rounds` vmapped grids of `grid` amplitudes, each zooming into the
    bracket of the previous (buckled: θ > 0.5 rad within `t1`; runs stop when stuck). The
    bracket is [largest stable, next amplitude] (every tested amplitude above it buckled);
    outcomes that are not monotonic in v₀ (a buckled amplitude below a stable one) are
    reported, with the smallest buckled amplitude. `friction_at` and `ends` are passed to
    [`Rod3D`][].

    **Returns:** list of dicts with `dF`, `field`, `rod3d`, `rod3d_bracket`, `monotonic`,
    `smallest_buckled`, `smallest_tested`, `every_tested_amplitude_buckled`.
    """
    from ..boundary import critical_velocity

    rod = RodChannel.reference(mu)
    F0 = float(theory.reference_load(rod))
    out = []
    for dF in dFs:
        t0 = time.perf_counter()
        r, _ = critical_velocity(rod, dF, model="field", rtol=1e-4, sensitivities=())
        t_field = time.perf_counter() - t0
        v_field = float(r.root)
        model = Rod3D(rod, n, control="load", end_load=F0 + dF, friction_at=friction_at, ends=ends)
        lo, hi = 0.4 * v_field, 2.5 * v_field
        bracketed, tested = False, {}
        for k in range(rounds):
            v0s = np.geomspace(lo, hi, grid)
            states = jax.vmap(lambda v0: model.initial_state(F0 + dF, lateral_velocity=sine_velocity(model, v0)))(jnp.asarray(v0s))
            dt = default_step(model, _first(states))
            sol = _batched(model, states, t1, 11, dt, 0.5, True, True)
            failed = np.asarray(sol.result) != 0
            if failed.any():  # a failed run is not a label: stop rather than count it as stable
                raise RuntimeError(f"cross-check ΔF = {dF} N: the 3D runs at v0 = {v0s[failed].tolist()} m/s failed "
                                   f"({RESULTS.describe(np.asarray(sol.result)[failed][0])}).")
            b = np.asarray(sol.buckled)
            tested.update(zip(v0s.tolist(), b.tolist()))
            if progress:
                print(f"  cross-check ΔF = {dF} N ({friction_at}), round {k}: buckled {b.astype(int).tolist()}", flush=True)
            if not b.any():
                lo, hi = (hi, hi * 3) if not bracketed else (lo, hi)
                continue
            stable = np.flatnonzero(~b)
            if stable.size == 0:  # every amplitude buckled
                if not bracketed:
                    lo, hi = lo / 3, lo
                continue
            j = int(stable[-1])
            if j == grid - 1:
                continue  # a stable member at the top: the bracket lies above (non-monotonic grid)
            lo, hi = v0s[j], v0s[j + 1]
            bracketed = True
        vs = np.array(sorted(tested))
        bs = np.array([tested[v] for v in vs])
        out.append(dict(dF=dF, field=v_field, rod3d=float(np.sqrt(lo * hi)) if bracketed else None,
                        rod3d_bracket=[float(lo), float(hi)] if bracketed else None,
                        monotonic=bool(np.all(np.diff(bs.astype(int)) >= 0)),
                        smallest_buckled=float(vs[bs][0]) if bs.any() else None,
                        every_tested_amplitude_buckled=bool(bs.all()),
                        smallest_tested=float(vs[0]), n_segments=n, friction_at=friction_at, ends=ends,
                        seconds_field=round(t_field, 2), seconds_rod3d=round(time.perf_counter() - t0 - t_field, 1),
                        rod3d_runs=len(tested)))
    return out


def rolling_check(dF=20.0, n=60, mu=0.3, mode=12, amplitude=1e-3, t1=0.1, sweeps=(1, 64)):
    """Does a rod that the reduced models call stuck stay put in the 3D model? The rod is
    pre-compressed to the dead load F⁰₆ + `dF` and given a lateral offset R·A·sin(mπs/L)
    (A = `amplitude` rad, m = `mode`) at rest; its net elastic + gravity restoring force per
    length, |EI k⁴ − F k² + w/R|·A·R, is a fraction `margin` < 1 of μ·w (the field model's
    stick condition, P1), so in the field model it does not move. Run for `t1` [s] with friction
    at the contact point (`friction_at="surface"`: the rod can roll) and at the centre line
    (`"axis"`: sliding only), each with every largest number of projected Gauss–Seidel
    friction sweeps in `sweeps` (each pass warm-started; 64: converged to `friction_tol`).

    **Returns:** dict with `margin` and, per case, `max_dtheta` (largest |θ(t1) − θ(0)| [rad]),
    `mean_dtheta` (mean of θ(t1) − θ(0) over the interior: a rigid roll around the channel shows
    as mean ≈ max), `all_stuck` (every interior node held by static friction at t1) and
    `friction_residual` (of the last pass); and `elastic_roll`, the largest |Δθ| of the roll that
    the holding friction sets up when the ends spin freely, r² f̂ L/(2 GJ k R) (f̂ the held
    force per length, r the rod's radius, k = mπ/L).
    """
    rod = RodChannel.reference(mu)
    F = float(theory.reference_load(rod)) + dF
    k = mode * np.pi / float(rod.L)
    EI, w, R = float(rod.EI), float(rod.w), float(rod.R)
    margin = abs(EI * k**4 - F * k**2 + w / R) * amplitude / (mu * w / R)
    s = jnp.linspace(0.0, 1.0, n + 1)
    r = 0.5 * float(rod.d)
    res = {"dF": dF, "n_segments": n, "mu": mu, "mode": mode, "amplitude_rad": amplitude, "t1": t1,
           "margin_net_force_over_mu_N": margin,
           "elastic_roll": r**2 * margin * mu * w * float(rod.L) / (2 * float(rod.GJ) * k * R)}
    for where in ("surface", "axis"):
        for sw in sweeps:
            model = Rod3D(rod, n, control="load", end_load=F, friction_at=where, friction_sweeps=sw)
            q0, v0 = model.initial_state(F, lateral_offset=R * amplitude * jnp.sin(mode * jnp.pi * s))
            # not stopped when stuck: the question is whether a held rod creeps
            sol = run(model, q0, v0, t1, 3, default_step(model, q0), stop_on_buckle=False, stop_when_stuck=False)
            d = np.asarray(sol.observables["theta"][-1] - sol.observables["theta"][0])[1:-1]
            res[f"{where}, {sw} sweeps"] = {"max_dtheta": float(np.max(np.abs(d))), "mean_dtheta": float(np.mean(d)),
                                            "all_stuck": bool(jnp.all(sol.v_final.stuck[1:-1])),
                                            "friction_residual": float(np.max(sol.observables["friction_residual"]))}
    return res


def _figure(path, ts, E, pre, Nn, Fx_over_F0cr, spectra):
    """E6 in the full model: energy fractions, the normal and axial force before buckling (saves
    `pre`), and the modal power of θ before and after buckling (`spectra`: the two spectra and
    their times [s])."""
    total = sum(E.values())
    p_before, p_after, t_before, t_after = spectra
    fig, axes = subplots(1, 3, figsize=(15, 4.2))
    for k in ("twist", "shear", "bend"):
        axes[0].semilogy(ts * 1e3, E[k] / total, label=f"{k} / total")
    axes[0].set_xlabel("t [ms]")
    axes[0].legend(fontsize=7)
    axes[0].set_title("energy fractions (μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s)", fontsize=9)
    axes[1].plot(ts[pre] * 1e3, Nn[pre].min(1), label="min N/w (interior)")
    axes[1].plot(ts[pre] * 1e3, Nn[pre].max(1), label="max N/w")
    axes[1].plot(ts[pre] * 1e3, Fx_over_F0cr[pre].max(1) - Fx_over_F0cr[pre].min(1), label="axial force range / F⁰cr")
    axes[1].set_xlabel("t [ms] (before buckling)")
    axes[1].legend(fontsize=7)
    axes[1].set_title("normal and axial force before buckling", fontsize=9)
    m = np.arange(1, len(p_before) + 1)
    axes[2].bar(m - 0.2, p_before, width=0.4, label=f"t = {t_before * 1e3:.1f} ms")
    axes[2].bar(m + 0.2, p_after, width=0.4, label=f"t = {t_after * 1e3:.1f} ms")
    axes[2].set_yscale("log")
    axes[2].set_ylim(1e-6, 1.5)
    axes[2].set_xlabel("mode m")
    axes[2].legend(fontsize=7)
    axes[2].set_title("modal power of θ, before and after buckling", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
