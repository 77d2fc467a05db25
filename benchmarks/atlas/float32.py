"""Failure atlas, entry 6 (`float32`): float32 against float64.

Stable/buckled labels on a map-like (ΔF, v₀) batch of the field model (n = 63), and v₀* of the
field model and of the single mode. x64 is a global switch, so each dtype runs in a child
process, `failure_atlas.py --_child [--_float32] [--quick]`, which calls `float32_child`.

Run by `benchmarks/failure_atlas.py --only float32`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

from .common import ROD, field_limit, field_vcrit, mode_at, scales

# the child process runs the driver (benchmarks/failure_atlas.py), which sets the dtype first
DRIVER = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "failure_atlas.py")


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
        cmd = [sys.executable, DRIVER, "--_child"] + (["--_float32"] if dt == "float32" else []) \
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
