"""Failure atlas: where each tempting way of simulating dry friction goes wrong, measured.

One entry per failure, each with the measurement that shows it and the method to use instead:

1. `chatter`   explicit sharp sign (`SymplecticEuler`): velocity sign flips per second where the
               exact solution sticks, and false stable/buckled labels on a phase-plane grid,
               growing with the horizon.
2. `creep`     tanh law (`DiffraxSmooth`, Kvaerno5): a state on the stick line drifts and runs
               away after a time ∝ 1/ε; the critical velocity v₀* against ε and the horizon.
3. `gradient`  tanh law under explicit fixed steps (`ProjectedVerlet(dt, Tanh(ε))`): dA(T)/dȦ₀
               by `jax.grad` against central finite differences and against the exact
               (sharp-law) derivative, as h·f/ε grows.
4. `split`     `SplitLinearFriction` against `ProjectedVerlet`: a stuck state creeping at high
               load (single mode and field model).
5. `steplimit` steps beyond 2/ω_max: the growth of a raw loop of Verlet steps, and the package
               refusing them (`ValueError`, `RESULTS.step_limit` under vmap).
6. `float32`   float32 against float64: stable/buckled labels on a map-like (ΔF, v₀) batch of the
               field model and v₀* (field and single mode).
7. `broadband` the single-mode model outside its validity: a random lateral velocity field;
               the field model's critical load against the single-mode predictions (P7 for the
               projected mode-6 amplitude, and the minimum of P7 over all modes).

Reference rod, μ = 0.3 throughout; ΔF is measured from F⁰₆ = 1.308 N.

    python benchmarks/failure_atlas.py [--quick] [--only chatter,creep,...]

Writes benchmarks/results/atlas_<entry>.csv, atlas_summary.csv and atlas_panels.png (the
`--quick` run writes `atlas_quick_*` instead).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import jax

if "--_float32" not in sys.argv:  # the float32 child process runs with x64 off
    jax.config.update("jax_enable_x64", True)
import diffrax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
ROD = jr.RodChannel.reference(mu=0.3)
ENTRIES = ("chatter", "creep", "gradient", "split", "steplimit", "float32", "broadband")


def write_csv(path, rows):
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def mode_at(dF, mu=0.3):
    return jr.SingleMode.from_rod(jr.RodChannel.reference(mu=mu), dF=dF)


def scales(m):
    """λ = √|k| [1/s], a = f/|k| [rad], Ȧ_cr = f/λ [rad/s] of a loaded single mode."""
    lam = float(jnp.sqrt(-m.k))
    return lam, float(m.f_d) / lam**2, float(m.f_d) / lam


def field_limit(n, dF=0.0):
    return 2.0 / float(jr.FieldModel.from_rod(ROD, n, dF=dF).max_frequency())


def field_vcrit(n, dF, integ, t1=0.5, n_iter=30, bracket=(1e-4, 0.2)):
    model = jr.FieldModel.from_rod(ROD, n, dF=dF)
    opts = jr.RunOptions(save_state=False)

    def buckles(v0):
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(model)
        return jr.simulate(model, integ, q0, w0, t1, n_save=3, options=opts, throw=False).buckled

    lo, hi = jax.jit(lambda: jr.search.bisect(buckles, *bracket, n_iter))()
    return float(jnp.sqrt(lo * hi))


# ---------------------------------------------------------------------------------------------
# 1. explicit sharp sign: chatter and false classification
# ---------------------------------------------------------------------------------------------

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


# ---------------------------------------------------------------------------------------------
# 2. tanh creep
# ---------------------------------------------------------------------------------------------

def entry_creep(quick):
    m = mode_at(5.0)
    lam, a, vc = scales(m)
    rows, out = [], {}
    epss = [1e-1, 1e-2, 1e-3] if quick else [1e-1, 1e-2, 1e-3, 1e-4]
    A0 = 0.5 * a
    curves = {}
    for eps in epss:
        T = 4.0 / (eps * lam)  # creep time scale 1/(ε'λ)
        integ = jr.DiffraxSmooth(jr.Tanh(eps * vc), diffrax.Kvaerno5(), rtol=1e-8, atol=1e-12, dt0=1e-4,
                                 max_steps=20_000)
        sol = jr.simulate(m, integ, A0, 0.0, T, n_save=401, throw=False)
        ts, A = np.asarray(sol.ts), np.asarray(sol.q)
        drift = np.abs(A - A0) / a
        run = np.flatnonzero(~(np.abs(A) <= 2 * a))
        t_run = ts[run[0]] if run.size else float("nan")
        finite_before = bool(run.size) and bool(np.isfinite(A[run[0] - 1])) and abs(A[run[0] - 1]) < 2 * a
        # a drift measured well before the runaway: at t = 1/(10 ε'λ)
        i10 = int(np.searchsorted(ts, 0.1 / (eps * lam)))
        curves[eps] = (ts, drift)
        rows.append(dict(part="creep", eps_rel=eps, eps=eps * vc, A0_over_a=0.5, horizon_s=T,
                         drift_at_0p1_over_eps_lam=drift[i10], t_runaway_s=t_run,
                         t_runaway_times_eps_lam=t_run * eps * lam, runaway_resolved=finite_before,
                         result=int(sol.result)))
        print(f"  creep ε'={eps:.0e}: |A−A0|/a = {drift[i10]:.2e} at t = 0.1/(ε'λ) = {ts[i10]:.3g} s; runs away "
              f"(|A| > 2a) at t = {t_run:.3g} s, t·ε'λ = {t_run * eps * lam:.2f}")
    out["curves"] = curves
    # exact/projected reference: bit-for-bit still
    pv = jr.simulate(m, jr.ProjectedVerlet(1e-4), A0, 0.0, 10.0, n_save=11)
    still = bool(np.all(np.asarray(pv.q) == A0))

    # v0* against ε and horizon (bisection on the label |A(T)| > a, Kvaerno5)
    horizons = [10.0, 100.0] if quick else [10.0, 30.0, 100.0, 300.0]
    vs = {}
    for H in horizons:
        T = H / lam

        def root(eps, T=T):
            integ = jr.DiffraxSmooth(jr.Tanh(eps * vc), diffrax.Kvaerno5(), rtol=1e-8, atol=1e-12, dt0=1e-4,
                                     max_steps=100_000)

            def buckles(x):
                sol = jr.simulate(m, integ, 0.0, x * vc, T, n_save=2, throw=False)
                return ~(jnp.abs(sol.q_final) <= a)

            lo, hi = jr.search.bisect(buckles, 1e-4, 3.6, 28 if quick else 40)
            return jnp.sqrt(lo * hi)

        t0 = time.perf_counter()
        r = np.asarray(jax.jit(jax.vmap(root))(jnp.asarray(epss)))
        vs[H] = r
        for eps, x in zip(epss, r):
            rows.append(dict(part="boundary", eps_rel=eps, horizon_lam=H, horizon_s=T, v0_crit_over_P6=x,
                             rel_error=abs(x - 1)))
        print(f"  tanh v0*/P6 at λT = {H:5.0f}: " + ", ".join(f"ε'={e:.0e}: {x:.6f}" for e, x in zip(epss, r))
              + f"  ({time.perf_counter() - t0:.1f} s)")
    out["vs"] = (epss, vs)
    e_small = epss[-1]
    summary = dict(
        failure="tanh creep (DiffraxSmooth, any solver)",
        measurement=("single mode ΔF = 5 N, state on the stick line A₀ = a/2 at rest: time until |A| > 2a; "
                     "v₀*/P6 − 1 from the label |A(T)| > a at horizons λT = 10 … 300"),
        number=(f"runs away at t·ε'λ ≈ {np.nanmean([r['t_runaway_times_eps_lam'] for r in rows if r['part'] == 'creep']):.1f} "
                f"(ε' = ε/Ȧ_cr = {epss[0]:g} … {e_small:g}; projected Verlet: bit-for-bit still: {still}); "
                f"v₀* error at ε' = {e_small:g}: {abs(vs[horizons[0]][-1] - 1):.1e} (λT = {horizons[0]:.0f}) → "
                f"{abs(vs[horizons[-1]][-1] - 1):.1e} (λT = {horizons[-1]:.0f}); at ε' = {epss[0]:g}: "
                f"{abs(vs[horizons[0]][0] - 1):.2f} → {abs(vs[horizons[-1]][0] - 1):.2f}"),
        use_instead="ProjectedVerlet with Coulomb (or Exact for one mode)",
    )
    return rows, summary, out


# ---------------------------------------------------------------------------------------------
# 3. gradients of the smoothed law under explicit steps
# ---------------------------------------------------------------------------------------------

def entry_gradient(quick):
    m = mode_at(5.0)
    lam, a, vc = scales(m)
    f = float(m.f_d)
    dt = 1e-4
    T = 5.0 / lam
    # friction acts in two half kicks of h/2: the linearised tanh update 1 − (h/2)f/ε is unstable past h·f/ε = 4
    hfe = [0.1, 1.0, 3.0, 4.5, 10.0, 30.0] if quick else [0.1, 0.3, 1.0, 2.0, 3.0, 3.9, 4.1, 5.0, 10.0, 30.0, 100.0]
    opts = jr.RunOptions(early_exit=False, save_state=False)

    def final(v0, eps):
        sol = jr.simulate(m, jr.ProjectedVerlet(dt, jr.Tanh(eps)), 0.0, v0, T, n_save=2, options=opts, throw=False)
        return sol.q_final

    grad = jax.jit(jax.vmap(jax.grad(final), (0, None)))
    val = jax.jit(jax.vmap(final, (0, None)))
    exact_d = jax.jit(jax.vmap(lambda v0: jax.jvp(lambda x: jr.exact_solution(0.0, x, m.k, m.f_s, m.f_d, T)[0],
                                                  (v0,), (jnp.ones_like(v0),))[1]))
    K = 9 if quick else 21
    v0s = 0.8 * vc * (1 + jnp.linspace(-0.01, 0.01, K))  # a 2 % window
    h = 1e-6 * 0.8 * vc
    d_ex = np.asarray(exact_d(v0s))
    rows, out = [], {}
    for x in hfe:
        eps = dt * f / x
        g = np.asarray(grad(v0s, eps))
        fd = (np.asarray(val(v0s + h, eps)) - np.asarray(val(v0s - h, eps))) / (2 * h)
        fin = np.isfinite(g) & np.isfinite(fd)
        rel_fd = float(np.max(np.abs(g - fd) / np.maximum(np.abs(fd), 1e-300))) if fin.all() else float("inf")
        rel_ex = float(np.max(np.abs(g - d_ex) / np.abs(d_ex))) if fin.all() else float("inf")
        # roughness: largest second difference across the window (the exact derivative is smooth)
        noise = float(np.max(np.abs(np.diff(g, 2))) / np.abs(np.mean(d_ex)))
        rows.append(dict(h_f_over_eps=x, eps=eps, eps_rel=eps / vc, dt=dt, window_points=K,
                         grad_vs_fd_max_rel=rel_fd, grad_vs_exact_max_rel=rel_ex, grad_roughness=noise, exact_roughness=float(np.max(np.abs(np.diff(d_ex, 2))) / np.abs(np.mean(d_ex))),
                         grad_max_abs=float(np.max(np.abs(g))), exact_derivative=float(np.mean(d_ex)),
                         all_finite=bool(fin.all())))
        out[x] = (np.asarray(v0s) / vc, g, fd)
        print(f"  gradient h·f/ε = {x:5.1f} (ε' = {eps / vc:.1e}): max |grad − FD|/|FD| = {rel_fd:9.2e}, "
              f"max |grad − exact|/|exact| = {rel_ex:9.2e}, roughness = {noise:9.2e}")
    out["exact"] = (np.asarray(v0s) / vc, d_ex)
    at1 = [r for r in rows if r["h_f_over_eps"] == 1.0][0]
    lo = [r for r in rows if r["h_f_over_eps"] < 4.0]
    hi = [r for r in rows if r["h_f_over_eps"] > 4.0]
    summary = dict(
        failure="smoothed law under explicit fixed steps: gradients",
        measurement=(f"single mode ΔF = 5 N, explicit Verlet on tanh, dt = {dt:g} s, dA(5/λ)/dȦ₀ by jax.grad vs "
                     f"central finite differences, {K} points in a 2 % window around Ȧ₀ = 0.8 Ȧ_cr"),
        number=(f"h·f/ε < 4: grad = FD to {max(r['grad_vs_fd_max_rel'] for r in lo):.0e} (vs the sharp-law derivative: "
                f"{at1['grad_vs_exact_max_rel']:.0e} at h·f/ε = 1, the ε-bias); h·f/ε > 4: grad vs FD up to "
                f"{max(r['grad_vs_fd_max_rel'] for r in hi):.0e}, vs exact up to "
                f"{max(r['grad_vs_exact_max_rel'] for r in hi):.0e}, roughness up to "
                f"{max(r['grad_roughness'] for r in hi):.0e} of the derivative"),
        use_instead="ProjectedVerlet with Coulomb (exact piecewise gradients), or keep h·f/ε ≲ 1",
    )
    return rows, summary, out


# ---------------------------------------------------------------------------------------------
# 4. creeping splitting
# ---------------------------------------------------------------------------------------------

def entry_split(quick):
    rows, out = [], {}
    dt = 1e-4
    curves = {}
    for dF in ([5.0, 60.0] if quick else [5.0, 20.0, 60.0]):
        m = mode_at(dF)
        lam, a, vc = scales(m)
        A0 = 0.5 * a
        T = 2.0
        opts = jr.RunOptions(buckle_threshold=2 * a, stop_when_stuck=False)
        sp = jr.simulate(m, jr.SplitLinearFriction(dt), A0, 0.0, T, n_save=2001, options=opts, throw=False)
        pv = jr.simulate(m, jr.ProjectedVerlet(dt), A0, 0.0, T, n_save=2001, options=opts, throw=False)
        ts, A = np.asarray(sp.ts), np.asarray(sp.q)
        d1 = abs(float(sp.q[1]) - A0) / a  # after 1 ms = 10 steps
        curves[dF] = (ts, np.abs(A - A0) / a)
        rows.append(dict(part="single mode", dF=dF, dt=dt, lam_dt=lam * dt, A0_over_a=0.5,
                         split_drift_over_a_after_10_steps=d1, predicted_half_h2_a=10 * 0.5 * dt**2 * lam**2 * A0 / a,
                         split_buckled=bool(sp.buckled), split_t_buckle_s=float(sp.t_buckle),
                         verlet_max_drift=float(np.max(np.abs(np.asarray(pv.q) - A0))), verlet_buckled=bool(pv.buckled)))
        print(f"  split ΔF = {dF:4.0f} N (λdt = {lam * dt:.3f}): |A−A0|/a after 10 steps = {d1:.2e} "
              f"(10·½h²|k|A0/a = {10 * 0.5 * dt**2 * lam**2 * A0 / a:.2e}); passes 2a at t = {float(sp.t_buckle):.3g} s; "
              f"projected Verlet drift = {rows[-1]['verlet_max_drift']:.1e}")
    out["curves"] = curves
    # field model: stuck rods at a high load
    n = 63
    dtf = 0.4 * field_limit(n)
    fields = []
    for dF in ([20.0] if quick else [20.0, 40.0]):
        v_star = field_vcrit(n, dF, jr.ProjectedVerlet(dtf), n_iter=24)
        model = jr.FieldModel.from_rod(ROD, n, dF=dF)
        q0, w0 = jr.SineVelocity(0.5 * v_star, 6).initial_state(model)
        opts = jr.RunOptions(stop_when_stuck=False)
        res = {}
        for name, integ in (("ProjectedVerlet", jr.ProjectedVerlet(dtf)), ("SplitLinearFriction", jr.SplitLinearFriction(dtf))):
            sol = jr.simulate(model, integ, q0, w0, 2.0, n_save=201, options=opts, throw=False)
            res[name] = sol
            rows.append(dict(part="field", dF=dF, n=n, dt=dtf, method=name, v0=0.5 * v_star, v0_crit_verlet=v_star,
                             buckled=bool(sol.buckled), t_buckle_s=float(sol.t_buckle),
                             stuck_at_end=bool(sol.stuck[-1]), max_amplitude=float(np.max(np.asarray(sol.amplitude)))))
        fields.append((dF, np.asarray(res["ProjectedVerlet"].ts), np.asarray(res["ProjectedVerlet"].amplitude),
                       np.asarray(res["SplitLinearFriction"].amplitude)))
        print(f"  split field n = {n}, ΔF = {dF:.0f} N, sine v0 = ½v0*(Verlet) = {0.5e3 * v_star:.2f} mm/s: "
              f"Verlet buckled={bool(res['ProjectedVerlet'].buckled)} stuck={bool(res['ProjectedVerlet'].stuck[-1])}; "
              f"split buckled={bool(res['SplitLinearFriction'].buckled)} at t = {float(res['SplitLinearFriction'].t_buckle):.3g} s")
    out["fields"] = fields
    sm = [r for r in rows if r["part"] == "single mode"]
    fl = [r for r in rows if r["part"] == "field" and r["method"] == "SplitLinearFriction"]
    summary = dict(
        failure="creeping splitting (SplitLinearFriction) at high load",
        measurement=("a stuck state A₀ = a/2 (single mode, dt = 1e-4 s), and a field rod (n = 63) given half its "
                     "critical sine velocity; time until it leaves the stick line / buckles"),
        number=("single mode passes 2a at t = " + ", ".join(f"{r['split_t_buckle_s']:.3g} s (ΔF = {r['dF']:.0f} N)" for r in sm)
                + "; field: " + ", ".join(f"buckles at {r['t_buckle_s']:.3g} s (ΔF = {r['dF']:.0f} N)" if r["buckled"]
                                          else f"not buckled in 2 s (ΔF = {r['dF']:.0f} N)" for r in fl)
                + "; projected Verlet: drift 0, never buckles"),
        use_instead="ProjectedVerlet",
    )
    return rows, summary, out


# ---------------------------------------------------------------------------------------------
# 5. steps beyond the stability limit
# ---------------------------------------------------------------------------------------------

def entry_steplimit(quick):
    n = 63
    model = jr.FieldModel.from_rod(ROD, n, dF=5.0)
    limit = 2.0 / float(model.max_frequency())
    om = float(model.max_frequency())
    q0, v0 = jr.RandomVelocity(0.015, jax.random.key(0)).initial_state(model)
    steps = 400 if quick else 1000
    rows, out = [], {}

    def raw(dt, model):  # a raw loop of the package's own step, without the driver's guard
        integ = jr.ProjectedVerlet(dt)

        def body(c, _):
            q, v, a = c
            q, v, a, _ = integ.step(model, q, v, a, 0.0, dt)
            return (q, v, a), jnp.max(jnp.abs(q))

        _, amp = jax.lax.scan(body, (q0, v0, model.acceleration(q0, 0.0)), None, length=steps)
        return np.asarray(amp)

    free = jr.FieldModel.from_rod(ROD.with_friction(0.0), n, dF=5.0)
    for fac, mu in [(0.99, 0.3), (1.01, 0.3), (1.01, 0.0), (1.05, 0.3), (1.2, 0.3), (1.5, 0.3)]:
        dt = fac * limit
        amp = raw(dt, model if mu else free)
        fin = np.isfinite(amp) & (amp > 0)
        # growth per step fitted over the last 40 % of the finite, growing part
        i_end = int(np.argmax(~fin)) if (~fin).any() else len(amp)
        seg = np.arange(int(0.6 * i_end), i_end)
        slope = np.polyfit(seg, np.log(amp[seg]), 1)[0] if len(seg) > 5 else float("nan")
        x = (om * dt) ** 2 / 2 - 1
        r_th = x + math.sqrt(x * x - 1) if x > 1 else 1.0  # |eigenvalue| of frictionless Verlet
        first_nonfinite = int(np.argmax(~np.isfinite(amp))) if (~np.isfinite(amp)).any() else -1
        rows.append(dict(part="raw loop", n=n, mu=mu, dt_over_limit=fac, dt=dt, steps=steps,
                         growth_per_step=float(np.exp(slope)), theory_growth_per_step=r_th,
                         first_nonfinite_step=first_nonfinite, max_theta_at_end=float(amp[-1])))
        out[(fac, mu)] = amp
        print(f"  raw loop μ = {mu}, dt = {fac:.2f}·limit: growth per step {math.exp(slope):.4f} (frictionless theory "
              f"{r_th:.4f}); max|θ| after {steps} steps = {amp[-1]:.3e}; first non-finite step "
              f"{first_nonfinite if first_nonfinite >= 0 else 'none'}")
    # what the package does
    try:
        jr.simulate(model, jr.ProjectedVerlet(1.01 * limit), q0, v0, 0.1)
        msg = "accepted (!)"
    except ValueError as e:
        msg = f"ValueError: {e}"
    print(f"  simulate with dt = 1.01·limit: {msg}")

    def member(dF):
        md = jr.FieldModel.from_rod(ROD, n, dF=dF)
        sol = jr.simulate(md, jr.ProjectedVerlet(1.01 * limit), q0, v0, 0.1, n_save=3, throw=False)
        return sol.result, jnp.isfinite(sol.q_final).all()

    codes, finite = jax.jit(jax.vmap(member))(jnp.array([5.0, 5.0]))
    codes = np.asarray(codes).tolist()
    print(f"  vmapped (traced model) at 1.01·limit: result codes {codes} = "
          f"{jr.RESULTS.describe(codes[0])!r}; state finite: {np.asarray(finite).tolist()}")
    rows.append(dict(part="package", n=n, dt_over_limit=1.01, simulate=msg, vmapped_result_codes=str(codes),
                     vmapped_state_finite=str(np.asarray(finite).tolist())))
    raw_row = lambda fac, mu: [r for r in rows if r["part"] == "raw loop" and r["dt_over_limit"] == fac and r["mu"] == mu][0]
    r101, r101f, r105, r15 = raw_row(1.01, 0.3), raw_row(1.01, 0.0), raw_row(1.05, 0.3), raw_row(1.5, 0.3)
    summary = dict(
        failure="steps beyond the stability limit 2/ω_max",
        measurement=(f"field model n = {n}, ΔF = 5 N, random velocity ±15 mm/s, a raw lax.scan of Verlet steps; "
                     f"then jaxrod.simulate with the same step"),
        number=(f"growth ×{r105['growth_per_step']:.3f}/step at 1.05·limit (frictionless Verlet theory "
                f"×{r105['theory_growth_per_step']:.3f}), ×{r15['growth_per_step']:.2f}/step at 1.5·limit (non-finite "
                f"after {r15['first_nonfinite_step']} steps); at 1.01·limit friction holds it "
                f"(×{r101['growth_per_step']:.3f}/step over {steps} steps; μ = 0: ×{r101f['growth_per_step']:.3f}); "
                f"simulate raises ValueError, vmapped runs return RESULTS.step_limit ({codes[0]})"),
        use_instead="dt < 2/ω_max (the package default: 0.4 of it); the driver refuses larger steps",
    )
    out["limit"] = limit
    return rows, summary, out


# ---------------------------------------------------------------------------------------------
# 6. float32 against float64 (one child process per dtype: x64 is a global switch)
# ---------------------------------------------------------------------------------------------

def float32_child(quick):
    """Runs in the child: the map-like batch and the critical velocities in the current dtype."""
    dtype = str(jnp.result_type(float))
    n = 63
    dt = 0.4 * field_limit(n)  # same static step in both dtypes
    dt = float(np.float32(dt))
    dFs = np.linspace(1.0, 40.0, 6 if quick else 10)
    v0s = np.geomspace(2e-3, 80e-3, 8 if quick else 14)
    DD, VV = (x.ravel() for x in np.meshgrid(dFs, v0s, indexing="ij"))

    def member(dF, v0):
        model = jr.FieldModel.from_rod(ROD, n, dF=dF)
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(model)
        sol = jr.simulate(model, jr.ProjectedVerlet(dt), q0, w0, 0.5, n_save=3,
                          options=jr.RunOptions(save_state=False), throw=False)
        return sol.buckled, sol.t_stop

    t0 = time.perf_counter()
    lab, t_stop = jax.jit(jax.vmap(member))(jnp.asarray(DD), jnp.asarray(VV))
    lab = np.asarray(lab)
    t_map = time.perf_counter() - t0
    v_field = field_vcrit(n, 5.0, jr.ProjectedVerlet(dt), n_iter=30)
    # single mode, projected Verlet λdt = 1e-3, safeguarded Newton on A(T)/a − 1
    m = mode_at(5.0)
    lam, a, vc = scales(m)

    def g(x):
        sol = jr.simulate(m, jr.ProjectedVerlet(1e-3 / lam), 0.0, x * vc, 10.0 / lam, n_save=2, throw=False)
        return sol.q_final / a - 1.0

    r = jax.jit(lambda: jr.boundary.safeguarded_newton(g, 1 / 2.7, 3.6, rtol=1e-10, max_iter=40))()
    return dict(dtype=dtype, n=n, dt=dt, dF=DD.tolist(), v0=VV.tolist(), buckled=lab.tolist(),
                map_seconds=t_map, v0_crit_field=v_field, v0_crit_mode_over_P6=float(r.root),
                mode_root_result=int(r.result))


def entry_float32(quick):
    res = {}
    for dt in ("float64", "float32"):
        cmd = [sys.executable, os.path.abspath(__file__), "--_child"] + (["--_float32"] if dt == "float32" else []) \
            + (["--quick"] if quick else [])
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            raise RuntimeError(p.stderr[-3000:])
        res[dt] = json.loads(p.stdout.split("CHILD ", 1)[1])
    a, b = res["float64"], res["float32"]
    assert b["dtype"] == "float32" and a["dtype"] == "float64", (a["dtype"], b["dtype"])
    l64, l32 = np.array(a["buckled"]), np.array(b["buckled"])
    agree = float(np.mean(l64 == l32))
    dis = np.flatnonzero(l64 != l32)
    rows = []
    for i in range(len(l64)):
        rows.append(dict(part="map", dF=a["dF"][i], v0=a["v0"][i], buckled_float64=bool(l64[i]),
                         buckled_float32=bool(l32[i])))
    vf_err = abs(b["v0_crit_field"] / a["v0_crit_field"] - 1)
    rows.append(dict(part="v0_crit", model="field n=63", float64=a["v0_crit_field"], float32=b["v0_crit_field"],
                     rel_diff=vf_err))
    rows.append(dict(part="v0_crit", model="single mode (PV, λdt=1e-3) / P6", float64=a["v0_crit_mode_over_P6"],
                     float32=b["v0_crit_mode_over_P6"], err64_vs_P6=abs(a["v0_crit_mode_over_P6"] - 1),
                     err32_vs_P6=abs(b["v0_crit_mode_over_P6"] - 1), result32=b["mode_root_result"]))
    print(f"  float32 vs float64: map labels agree on {100 * agree:.1f}% of {len(l64)} members "
          f"({len(dis)} differ: " + ", ".join(f"ΔF={a['dF'][i]:.1f} N v0={1e3 * a['v0'][i]:.2f} mm/s" for i in dis[:5])
          + ")")
    print(f"  field v0*(5 N): float64 {1e3 * a['v0_crit_field']:.5f}, float32 {1e3 * b['v0_crit_field']:.5f} mm/s "
          f"(rel. diff {vf_err:.1e}); single mode v0*/P6 − 1: float64 {a['v0_crit_mode_over_P6'] - 1:.2e}, "
          f"float32 {b['v0_crit_mode_over_P6'] - 1:.2e}")
    summary = dict(
        failure="float32 instead of float64",
        measurement=(f"field model n = 63, {len(l64)}-member (ΔF, v₀) map batch (sine mode 6, 0.5 s): labels; "
                     f"v₀* at ΔF = 5 N (field, bisection) and single mode (projected Verlet λdt = 1e-3) vs P6"),
        number=(f"labels agree on {100 * agree:.1f}% ({len(dis)} of {len(l64)} differ); field v₀* differs by "
                f"{vf_err:.1e}; single-mode v₀* error vs P6: {abs(b['v0_crit_mode_over_P6'] - 1):.1e} (float32) "
                f"vs {abs(a['v0_crit_mode_over_P6'] - 1):.1e} (float64)"),
        use_instead="float64 for boundary values to better than the float32 error shown; float32 labels agreed here",
    )
    out = dict(dF=np.array(a["dF"]), v0=np.array(a["v0"]), l64=l64, l32=l32)
    return rows, summary, out


# ---------------------------------------------------------------------------------------------
# 7. the single-mode model outside its validity: broadband perturbations
# ---------------------------------------------------------------------------------------------

def entry_broadband(quick):
    from jaxrod.boundary import critical_load

    n = 127
    amp = 0.015
    R_ = 2 if quick else 6
    keys = jax.random.split(jax.random.key(11), R_)
    F06 = float(jr.theory.frictionless_load(ROD, 6))
    bracket = (0.05, 40.0)
    dt = jr.scene.Scene(ROD, bracket[1], kind="field", n=n).step()

    def field_dF(key, kind):
        res, _ = critical_load(ROD, amp, model="field", perturbation=kind, n=n, dt=dt, key=key, bracket=bracket,
                               rtol=1e-4, sensitivities=())
        return res.root, res.result

    t0 = time.perf_counter()
    roots, codes = jax.jit(jax.vmap(lambda k: field_dF(k, "random-velocity")))(keys)
    roots, codes = np.asarray(roots), np.asarray(codes)
    sine_root, sine_code = jax.jit(lambda: field_dF(keys[0], "sine"))()
    print(f"  field critical loads computed in {time.perf_counter() - t0:.1f} s")
    model = jr.FieldModel.from_rod(ROD, n, dF=5.0)
    rows = []
    m_all = np.arange(1, n + 1)
    for i, key in enumerate(keys):
        _, v = jr.RandomVelocity(amp, key).initial_state(model)  # rad/s at the nodes
        Am = np.abs(np.asarray(jr.modal.modal_amplitudes(v)))
        F6 = float(jr.theory.critical_load_velocity(ROD, 6, Am[5]))
        Fm = np.asarray(jr.theory.critical_load_velocity(ROD, jnp.asarray(m_all), jnp.asarray(Am)))
        i_min = int(np.nanargmin(Fm))
        rows.append(dict(perturbation="random velocity ±15 mm/s", realization=i, n=n,
                         field_dF_crit=float(roots[i]), field_result=int(codes[i]),
                         mode6_amplitude_mm_s=1e3 * float(ROD.R) * Am[5],
                         single_mode6_dF_crit=F6 - F06, min_over_modes_dF_crit=float(Fm[i_min]) - F06,
                         min_mode=i_min + 1, ratio_mode6_over_field=(F6 - F06) / float(roots[i]),
                         ratio_min_over_field=(float(Fm[i_min]) - F06) / float(roots[i])))
        r = rows[-1]
        print(f"  random velocity #{i}: field ΔF* = {r['field_dF_crit']:.3f} N; single mode 6 (projected "
              f"amplitude {r['mode6_amplitude_mm_s']:.2f} mm/s) predicts {r['single_mode6_dF_crit']:.3f} N "
              f"(×{r['ratio_mode6_over_field']:.1f}); min of P7 over modes {r['min_over_modes_dF_crit']:.3f} N "
              f"(mode {r['min_mode']}, ×{r['ratio_min_over_field']:.2f})")
    F6s = float(jr.theory.critical_load_velocity(ROD, 6, amp / ROD.R)) - F06
    rows.append(dict(perturbation="sine mode 6, 15 mm/s", realization=0, n=n, field_dF_crit=float(sine_root),
                     field_result=int(sine_code), mode6_amplitude_mm_s=15.0, single_mode6_dF_crit=F6s,
                     ratio_mode6_over_field=F6s / float(sine_root)))
    print(f"  sine mode 6 at 15 mm/s (same amplitude, no broadband content): field ΔF* = {float(sine_root):.3f} N, P7 {F6s:.3f} N "
          f"(×{F6s / float(sine_root):.2f})")
    rb = [r for r in rows if r["perturbation"].startswith("random")]
    ratios6 = np.array([r["ratio_mode6_over_field"] for r in rb])
    ratiosm = np.array([r["ratio_min_over_field"] for r in rb])
    summary = dict(
        failure="single-mode model outside its validity (broadband perturbation)",
        measurement=(f"critical load ΔF* for a random lateral velocity ±15 mm/s at every node ({R_} realizations, "
                     f"field n = {n}) against P7 with the field's projected mode-6 amplitude, and the minimum of P7 "
                     f"over all modes"),
        number=(f"mode-6 prediction / field = {ratios6.min():.1f} … {ratios6.max():.1f}; min over modes / field = "
                f"{ratiosm.min():.2f} … {ratiosm.max():.2f} (sine mode 6 at 15 mm/s: {F6s / float(sine_root):.2f})"),
        use_instead="the field model (or Galerkin with enough modes) for broadband perturbations",
    )
    return rows, summary, dict(rows=rows)


# ---------------------------------------------------------------------------------------------
# figure
# ---------------------------------------------------------------------------------------------

def plot(outs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 3, figsize=(16, 18))
    ax = iter(axes.ravel())
    if "chatter" in outs:
        o = outs["chatter"]
        a1 = next(ax)
        for (name, dt), (ts, v) in o["traces"].items():
            if dt == 1e-4:
                a1.plot(1e3 * ts, v, lw=0.6, label=f"{name}, dt = {dt:g} s")
        a1.axvline(1e3 * o["t_stick"], color="k", ls=":", lw=1, label="exact stick")
        a1.set_xlim(1e3 * o["t_stick"] - 5, 1e3 * o["t_stick"] + 15)
        a1.set_ylim(-0.3, 0.3)
        a1.set(xlabel="t [ms]", ylabel="Ȧ [rad/s]", title="1. explicit sgn: chatter after the stick")
        a1.legend(fontsize=7)
        a2 = next(ax)
        ts, cls = o["cls"]
        for name, w in cls.items():
            a2.plot(ts[1:], 100 * w[1:], "o-", label=name)
        a2.set(xlabel="horizon [s]", ylabel="labels ≠ exact [%]", title="1. false classification vs horizon (dt = 1e-4 s)")
        a2.legend(fontsize=7)
    if "creep" in outs:
        o = outs["creep"]
        a3 = next(ax)
        for eps, (ts, d) in o["curves"].items():
            ok = np.isfinite(d) & (d > 0)
            a3.loglog(ts[ok], np.minimum(d[ok], 1e3), label=f"ε' = {eps:g}")
        a3.axhline(1.5, color="k", ls=":", lw=1)
        a3.set(xlabel="t [s]", ylabel="|A − A₀| / a", title="2. tanh creep from the stick line (Kvaerno5)")
        a3.legend(fontsize=7)
        a4 = next(ax)
        epss, vs = o["vs"]
        for H, r in vs.items():
            a4.loglog(epss, np.maximum(np.abs(np.asarray(r) - 1), 1e-12), "o-", label=f"λT = {H:g}")
        a4.set(xlabel="ε' = ε / Ȧ_cr", ylabel="|v₀*/P6 − 1|", title="2. tanh boundary error vs ε and horizon")
        a4.legend(fontsize=7)
    if "gradient" in outs:
        o = outs["gradient"]
        a5 = next(ax)
        x, d_ex = o["exact"]
        for k in [k for k in o if k != "exact"]:
            xx, g, fd = o[k]
            if k in (0.1, 1.0, 3.0, 4.5, 5.0, 10.0, 30.0):
                a5.plot(xx, np.clip(g / d_ex, -4, 6), ".-", lw=0.8, label=f"jax.grad, h·f/ε = {k:g}")
        a5.axhline(1.0, color="k", lw=2, label="exact (sharp law)")
        a5.set_ylim(-4.2, 6.2)
        a5.set(xlabel="Ȧ₀ / Ȧ_cr", ylabel="grad / exact derivative (clipped to [−4, 6])",
               title="3. gradients of explicit tanh steps")
        a5.legend(fontsize=6)
        a6 = next(ax)
        ks = sorted(k for k in o if k != "exact")
        rel = []
        for k in ks:
            xx, g, fd = o[k]
            rel.append(np.max(np.abs(g - fd) / np.maximum(np.abs(fd), 1e-300)))
        a6.loglog(ks, np.maximum(rel, 1e-16), "o-", label="max |grad − FD| / |FD|")
        rel_ex = [np.max(np.abs(o[k][1] - d_ex) / np.abs(d_ex)) for k in ks]
        a6.loglog(ks, np.maximum(rel_ex, 1e-16), "s-", label="max |grad − exact sharp-law derivative| / |exact|")
        a6.axvline(4, color="k", ls=":", lw=1)
        a6.set(xlabel="h·f/ε", ylabel="relative", title="3. gradient error vs h·f/ε")
        a6.legend(fontsize=7)
    if "split" in outs:
        o = outs["split"]
        a7 = next(ax)
        for dF, (ts, d) in o["curves"].items():
            ok = d > 0
            a7.loglog(ts[ok], d[ok], label=f"split, ΔF = {dF:g} N")
        a7.axhline(1.5, color="k", ls=":", lw=1)
        a7.set(xlabel="t [s]", ylabel="|A − A₀| / a", title="4. SplitLinearFriction: stuck state creeps (Verlet: 0)")
        a7.legend(fontsize=7)
        a8 = next(ax)
        for dF, ts, pv, sp in o["fields"]:
            a8.semilogy(ts, pv, "-", label=f"ProjectedVerlet, ΔF = {dF:g} N")
            a8.semilogy(ts, sp, "--", label=f"SplitLinearFriction, ΔF = {dF:g} N")
        a8.set(xlabel="t [s]", ylabel="max|θ| [rad]", title="4. field n = 63, half the critical sine velocity")
        a8.legend(fontsize=7)
    if "steplimit" in outs:
        o = outs["steplimit"]
        a9 = next(ax)
        for key in [k for k in o if k != "limit"]:
            amp = o[key]
            a9.semilogy(np.where(np.isfinite(amp) & (amp < 1e250), amp, np.nan),
                        "--" if key[1] == 0 else "-", label=f"dt = {key[0]:g}·limit, μ = {key[1]:g}")
        a9.set_ylim(1e-4, 1e250)
        a9.set(xlabel="step", ylabel="max|θ| [rad]", title="5. raw Verlet loop past 2/ω_max (field n = 63)")
        a9.legend(fontsize=7)
    if "float32" in outs:
        o = outs["float32"]
        a10 = next(ax)
        same = o["l64"] == o["l32"]
        a10.scatter(o["dF"][same & o["l64"]], 1e3 * o["v0"][same & o["l64"]], c="C3", s=14, label="buckled (both)")
        a10.scatter(o["dF"][same & ~o["l64"]], 1e3 * o["v0"][same & ~o["l64"]], c="C0", s=14, label="straight (both)")
        a10.scatter(o["dF"][~same], 1e3 * o["v0"][~same], c="k", marker="x", s=60, label="float32 ≠ float64")
        a10.set_yscale("log")
        a10.set(xlabel="ΔF [N]", ylabel="v₀ [mm/s]", title="6. float32 vs float64 map labels (field n = 63)")
        a10.legend(fontsize=7)
    if "broadband" in outs:
        rows = outs["broadband"]["rows"]
        a11 = next(ax)
        rb = [r for r in rows if r["perturbation"].startswith("random")]
        i = np.arange(len(rb))
        a11.bar(i - 0.25, [r["field_dF_crit"] for r in rb], 0.25, label="field model ΔF*")
        a11.bar(i, [r["single_mode6_dF_crit"] for r in rb], 0.25, label="single mode 6 (projected)")
        a11.bar(i + 0.25, [r["min_over_modes_dF_crit"] for r in rb], 0.25, label="min of P7 over modes")
        a11.set_yscale("log")
        a11.set(xlabel="realization", ylabel="ΔF* [N]", title="7. random velocity ±15 mm/s, μ = 0.3")
        a11.legend(fontsize=7)
    for a in ax:
        a.axis("off")
    fig.suptitle(f"jaxrod failure atlas — reference rod, μ = 0.3, {jax.devices()[0].platform}, jax {jax.__version__}")
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", default=",".join(ENTRIES))
    ap.add_argument("--_child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--_float32", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._child:
        print("CHILD " + json.dumps(float32_child(args.quick)))
        return
    os.makedirs(OUT, exist_ok=True)
    tag = "atlas_quick_" if args.quick else "atlas_"
    d = jax.devices()[0]
    print(f"device {d.platform} ({os.cpu_count()} CPU cores), jax {jax.__version__}, float64 unless stated")
    summaries, outs = [], {}
    t_all = time.perf_counter()
    for name in args.only.split(","):
        t0 = time.perf_counter()
        print(f"\n[{name}]")
        rows, summary, out = globals()[f"entry_{name}"](args.quick)
        summary["entry"] = name
        summary["seconds"] = round(time.perf_counter() - t0, 1)
        summaries.append(summary)
        outs[name] = out
        write_csv(os.path.join(OUT, f"{tag}{name}.csv"), rows)
        print(f"  -> {summary['number']}  ({summary['seconds']} s)")
    write_csv(os.path.join(OUT, f"{tag}summary.csv"), summaries)
    plot(outs, os.path.join(OUT, f"{tag}panels.png"))
    print("\n| failure | measurement | number | use instead |\n|---|---|---|---|")
    for s in summaries:
        print(f"| {s['failure']} | {s['measurement']} | {s['number']} | {s['use_instead']} |")
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s")


if __name__ == "__main__":
    main()
