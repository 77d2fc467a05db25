"""Failure atlas, entry 4 (`split`): the creeping splitting at high load.

`SplitLinearFriction` against `ProjectedVerlet`: a stuck state creeping (single mode), and a
field rod (n = 63) given half its critical sine velocity buckling. Use instead:
`ProjectedVerlet`.

Run by `benchmarks/failure_atlas.py --only split`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import numpy as np

import jaxrod as jr

from .common import ROD, field_limit, field_vcrit, mode_at, scales


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
