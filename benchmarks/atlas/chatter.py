"""Failure atlas, entry 1 (`chatter`): the explicit sharp sign law (`SymplecticEuler`).

Velocity sign flips per second where the exact solution sticks, and false stable/buckled labels
on a phase-plane grid against the exact solution, growing with the horizon (single mode,
ΔF = 5 N). Use instead: `ProjectedVerlet` (exact proximal stick).

Run by `benchmarks/failure_atlas.py --only chatter`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

from .common import mode_at, scales


def entry_chatter(quick):
    m = mode_at(5.0)
    lam, a, vc = scales(m)
    rows = []
    out = {}
    # (a) chatter where the exact solution sticks
    T = 0.3
    ex = jr.simulate(m, jr.Exact(), 0.0, 0.8 * vc, T, n_save=301)
    t_stick = float(ex.ts[int(np.argmax(np.asarray(ex.stuck)))])
    traces = {}
    for dt in ([1e-4] if quick else [1e-4, 1e-5]):
        n_save = int(round(T / dt)) + 1
        for name, integ in (("SymplecticEuler", jr.SymplecticEuler(dt)), ("ProjectedVerlet", jr.ProjectedVerlet(dt))):
            sol = jr.simulate(m, integ, 0.0, 0.8 * vc, T, n_save=n_save, throw=False,
                              options=jr.RunOptions(stop_when_stuck=False))
            ts, v, A = np.asarray(sol.ts), np.asarray(sol.v), np.asarray(sol.q)
            late = ts > t_stick + 0.01
            flips = np.count_nonzero(np.diff(np.sign(v[late])) != 0)
            rate = flips / (ts[late][-1] - ts[late][0])
            A_ex = float(ex.q[-1])
            rows.append(dict(part="chatter", method=name, dt=dt, lam_dt=lam * dt, t_stick_exact=t_stick,
                             sign_flips_per_s=rate, flips_per_step=rate * dt,
                             max_abs_v_after_stick=float(np.max(np.abs(v[late]))), h_f=dt * float(m.f_d),
                             drift_over_a_at_T=abs(A[-1] - A_ex) / a, stuck_at_T=bool(sol.stuck[-1])))
            traces[(name, dt)] = (ts, v)
            print(f"  chatter {name:16s} dt={dt:.0e}: {rate:9.0f} sign flips/s after the exact stick "
                  f"(t = {t_stick * 1e3:.1f} ms), max|Ȧ| = {np.max(np.abs(v[late])):.3e} rad/s "
                  f"(h·f = {dt * float(m.f_d):.3e}), |A(T) − A_exact|/a = {abs(A[-1] - A_ex) / a:.2e}")
    out["traces"] = traces
    out["t_stick"] = t_stick

    # (b) false classification on a phase-plane grid against the exact solution, vs horizon
    N = 16 if quick else 24
    AA, VV = (x.ravel() for x in jnp.meshgrid(jnp.linspace(-2 * a, 2 * a, N), jnp.linspace(-2 * vc, 2 * vc, N)))
    T_max = 2.0 if quick else 8.0
    n_save = int(T_max / 0.5) + 1  # horizons 0.5, 1, 1.5, ...
    thr = 1.5 * a
    opts = jr.RunOptions(buckle_threshold=thr, save_state=True)

    def labels(integ):
        run = lambda A0, V0: jr.simulate(m, integ, A0, V0, T_max, n_save=n_save, options=opts, throw=False)
        sol = jax.jit(jax.vmap(run))(AA, VV)
        return ~(np.abs(np.asarray(sol.q)) <= thr), np.asarray(sol.ts[0])  # nan/inf count as buckled

    lab_ex, ts = labels(jr.Exact())
    zone = ~np.asarray(jr.theory.in_stable_zone(AA, VV, m.k, m.f_d))
    cls = {}
    for dt in [1e-4]:
        for name, integ in (("SymplecticEuler", jr.SymplecticEuler(dt)), ("ProjectedVerlet", jr.ProjectedVerlet(dt))):
            t0 = time.perf_counter()
            lab, _ = labels(integ)
            wrong = (lab != lab_ex).mean(axis=0)
            cls[name] = wrong
            for i in range(1, len(ts)):
                rows.append(dict(part="classification", method=name, dt=dt, horizon_s=ts[i],
                                 horizon_lam=ts[i] * lam, grid=N * N, wrong_fraction=wrong[i],
                                 false_buckled=int(np.sum(lab[:, i] & ~lab_ex[:, i])),
                                 false_stable=int(np.sum(~lab[:, i] & lab_ex[:, i])),
                                 exact_vs_asymptotic_zone=float(np.mean(lab_ex[:, i] != zone))))
            print(f"  classification {name:16s} dt={dt:.0e}: wrong labels vs exact on {N}×{N} grid at "
                  + ", ".join(f"T={ts[i]:.1f}s: {100 * wrong[i]:.1f}%" for i in range(1, len(ts)))
                  + f"  ({time.perf_counter() - t0:.1f} s)")
    out["cls"] = (ts, cls)
    se_final = cls["SymplecticEuler"][-1]
    last = [r for r in rows if r["part"] == "classification" and r["method"] == "SymplecticEuler"][-1]
    se_fb, se_wrong = last["false_buckled"], last["false_buckled"] + last["false_stable"]
    summary = dict(
        failure="explicit sharp sign (SymplecticEuler): chatter, false classification",
        measurement=(f"single mode ΔF = 5 N, Ȧ₀ = 0.8 Ȧ_cr, dt = 1e-4 s: velocity sign flips per second after "
                     f"the exact stick; {N}×{N} phase-plane grid, labels (|A| > 1.5a) vs the exact solution"),
        number=(f"{rows[0]['sign_flips_per_s']:.0f} flips/s ({rows[0]['flips_per_step']:.2f} per step; "
                f"projected Verlet: {rows[1]['sign_flips_per_s']:.0f}); wrong labels "
                f"{100 * cls['SymplecticEuler'][1]:.1f}% at T = {ts[1]:.1f} s → {100 * se_final:.1f}% at "
                f"T = {ts[-1]:.1f} s, {se_fb} of {se_wrong} false 'buckled' (projected Verlet: "
                f"{100 * cls['ProjectedVerlet'][-1]:.1f}%)"),
        use_instead="ProjectedVerlet (exact proximal stick)",
    )
    return rows, summary, out
