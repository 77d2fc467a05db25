"""Failure atlas, entry 2 (`creep`): the tanh law (`DiffraxSmooth`, Kvaerno5).

A state on the stick line drifts and runs away after a time ∝ 1/ε; the critical velocity v₀*
against ε and the horizon (single mode, ΔF = 5 N). Use instead: `ProjectedVerlet` with Coulomb
(or `Exact` for one mode).

Run by `benchmarks/failure_atlas.py --only creep`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import time

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr
from jaxrod.boundary.roots import bisection

from .common import mode_at, scales


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

            r = bisection(buckles, 1e-4, 3.6, rtol=0.0, max_iter=28 if quick else 40)
            return jnp.sqrt(r.lo * r.hi)

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
