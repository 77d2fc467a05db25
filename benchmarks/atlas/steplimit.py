"""Failure atlas, entry 5 (`steplimit`): steps beyond the stability limit 2/ω_max.

The growth of a raw `lax.scan` of Verlet steps (field model n = 63), and the package refusing
such steps (`ValueError`; `RESULTS.step_limit` under vmap). Use instead: dt < 2/ω_max.

Run by `benchmarks/failure_atlas.py --only steplimit`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

from .common import ROD


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
