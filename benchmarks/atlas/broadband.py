"""Failure atlas, entry 7 (`broadband`): the single-mode model outside its validity.

A random lateral velocity field: the field model's critical load against the single-mode
predictions (P7 for the projected mode-6 amplitude, and the minimum of P7 over all modes). Use
instead: the field model (or Galerkin with enough modes) for broadband perturbations.

Run by `benchmarks/failure_atlas.py --only broadband`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

from .common import ROD


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
