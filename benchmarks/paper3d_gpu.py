"""The paper's experiments with the paper's model, prepared for one GPU: the 3D rod at 500 segments
for E3, E4 A/B and E6C (issue [paper3d]), each part written to disk as soon as it finishes.

    python benchmarks/paper3d_gpu.py                 # n = 500, every part (meant for a GPU)
    python benchmarks/paper3d_gpu.py --parts e3      # one part
    python benchmarks/paper3d_gpu.py --smoke         # n = 12, 2 loads / 2 μ / 2 realizations, t1 0.5 s:
                                                     # checks the script on any CPU (the default there)

Parts (the searches are `jaxrod.boundary`'s departure secant with the 3D rod's confirming run,
rtol 1e-2; every point of a part is a lane of one vmapped, jitted search, so a GPU runs them
side by side):

- `e3`: v₀*(ΔF), sine mode 6, μ = 0.3, at 8 loads 0.5–64 N (geometric: the field map's range);
  each lane's bracket is a factor 2 around the field model's v₀* at its load (first run there).
  The exponent of v₀* ∝ ΔF^p by least squares in log–log (`stability_map.fit_power_law`, all 8
  loads, fixed before any run), beside the field model's at the same loads and the paper's −0.77.
- `e4`: ΔF*(μ) for μ ∈ {0.05, 0.1, 0.3, 0.5, 1}, sine mode 6 at 15 mm/s (E4 A) and random velocity
  ±15 mm/s (E4 B, 4 realizations, keys as `critical_load_curve`), bracket 0.05–100 N.
- `e6c`: random position (lateral forces ±2 N/m for 1 ms), μ = 0.9, key 6 (E6's realization):
  ΔF* of that realization, then runs at the paper's ΔF = 40 N and at 1.05 ΔF*, 0.5 s: the
  dominant mode of θ at the last save before the stop and its share of the modal power.

Writes `benchmarks/results/paper3d_gpu[_smoke]/{e3,e4,e6c}.csv` and `summary.json` (commit, date,
device, n, dt, each part's wall time with its compilation). Nothing in jaxrod or its tests
depends on this script. It has been run only with `--smoke` on the project's CPU; its wall time on
a GPU is not known yet. A run that fails (non-finite state) ends its point's search with
result 3 (`ROOT_RESULTS.nonfinite`), never a root: it is not counted as stable. The failure
once met this way at 120 segments, 1 m/s (the float32 friction pass overflowing as a node
lifted off the wall) is fixed: that run now buckles at 2.75 ms, as in float64.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402
from jaxrod.modal import modal_spectrum  # noqa: E402
from jaxrod.output import write_csv  # noqa: E402
from jaxrod.registry import make_perturbation  # noqa: E402
from jaxrod.scene import Scene  # noqa: E402
from jaxrod.stability_map import fit_power_law  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER_E3_EXPONENT = -0.77  # ../shared/PHYSICS.md §5 (results/paper/paper_numbers.json)


def _e3(n, dFs, t1):
    rod = jr.RodChannel.reference(mu=0.3)
    field, _ = bd.boundary_curve(rod, dFs, model="field", rtol=1e-3, sensitivities=())
    vf = np.asarray(field.root)
    dt = Scene(rod, float(dFs.max()), kind="rod3d", n=n).step()

    def one(dF, lo, hi, start):
        return bd.critical_velocity(rod, dF, model="rod3d", n=n, dt=dt, method="departure", bracket=(lo, hi),
                                    start=start, rtol=1e-2, t1=t1, sensitivities=())[0]

    r = jax.block_until_ready(jax.jit(jax.vmap(one))(jnp.asarray(dFs), jnp.asarray(vf / 2), jnp.asarray(2 * vf),
                                                      jnp.asarray(vf)))
    rows = [dict(dF=float(d), v0_star=float(v), lo=float(a), hi=float(b), runs=int(k), result=int(c), v0_field=float(f))
            for d, v, a, b, k, c, f in zip(dFs, r.root, r.lo, r.hi, r.evaluations, r.result, vf)]
    ok = np.asarray(r.result) == 0
    p, se, _ = fit_power_law(dFs[ok], np.asarray(r.root)[ok]) if ok.sum() >= 2 else (np.nan, np.nan, np.nan)
    pf, sef, _ = fit_power_law(dFs, vf)
    return rows, dict(dt=dt, exponent=p, exponent_stderr=se, field_exponent=pf, field_exponent_stderr=sef,
                      paper_exponent=PAPER_E3_EXPONENT, converged=int(ok.sum()))


def _e4(n, mus, realizations, t1):
    rows, summary = [], {}
    for name, pert, reps in (("A", "sine", 1), ("B", "random-velocity", realizations)):
        r, _ = bd.critical_load_curve(mus, 15e-3, perturbation=pert, realizations=reps, model="rod3d", n=n,
                                      method="departure", bracket=(0.05, 100.0), rtol=1e-2, t1=t1, sensitivities=())
        r = jax.block_until_ready(r)
        for i, mu in enumerate(mus):
            for k in range(reps):
                rows.append(dict(case=name, perturbation=pert, mu=float(mu), realization=k,
                                 dF_star=float(r.root[i, k]), runs=int(r.evaluations[i, k]), result=int(r.result[i, k])))
        summary[name] = {f"{mu:g}": float(np.nanmean(np.asarray(r.root[i]))) for i, mu in enumerate(mus)}
    return rows, summary


def _e6c(n, t1):
    rod = jr.RodChannel.reference(mu=0.9)
    key = jax.random.key(6)
    r, _ = bd.critical_load(rod, 2.0, model="rod3d", perturbation="random-position", key=key, n=n,
                            method="departure", bracket=(1e-2, 100.0), rtol=1e-2, t1=t1, sensitivities=())
    dF_star = float(r.root)
    rows = []
    for label, dF in (("paper's load", 40.0), ("1.05 dF*", 1.05 * dF_star)):
        if not np.isfinite(dF):
            continue
        scene = Scene(rod, dF, make_perturbation("random-position", 2.0, 6, key), "rod3d", n)
        sol = scene.run(t1=0.5, n_save=501)
        theta = np.asarray(sol.observables["theta"])
        ts = np.asarray(sol.ts)
        i = min(int(np.searchsorted(ts, float(sol.t_stop))), len(ts) - 1)
        power = np.asarray(modal_spectrum(jnp.asarray(theta[i, 1:-1])))
        m = int(np.argmax(power)) + 1
        rows.append(dict(case=label, dF=dF, buckled=bool(sol.buckled), t_stop=float(sol.t_stop), dominant_mode=m,
                         power_share=float(power[m - 1])))
    return rows, dict(dF_star=dF_star, runs=int(r.evaluations), result=int(r.result))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=500)
    ap.add_argument("--parts", nargs="*", default=["e3", "e4", "e6c"], choices=["e3", "e4", "e6c"])
    ap.add_argument("--smoke", "--quick", action="store_true", help="n = 12, 2 loads, 2 mu, 2 realizations, t1 = 0.5 s")
    ap.add_argument("--on-cpu", action="store_true", help="run the full setting without a GPU (hours on a 2-core CPU)")
    a = ap.parse_args()
    if jax.devices()[0].platform == "cpu" and not (a.smoke or a.on_cpu):
        print("no GPU: running the smoke setting (--smoke); --on-cpu runs the full one here")
        a.smoke = True
    n, t1 = (12, 0.5) if a.smoke else (a.n, 2.0)
    dFs = np.geomspace(2.0, 16.0, 2) if a.smoke else np.geomspace(0.5, 64.0, 8)
    mus = np.array([0.1, 0.5]) if a.smoke else np.array([0.05, 0.1, 0.3, 0.5, 1.0])
    realizations = 2 if a.smoke else 4
    out = os.path.join(HERE, "results", "paper3d_gpu" + ("_smoke" if a.smoke else ""))
    os.makedirs(out, exist_ok=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    summary = dict(commit=commit, date=datetime.date.today().isoformat(), device=str(jax.devices()[0]),
                   platform=jax.devices()[0].platform, n=n, t1=t1, parts={})
    path = os.path.join(out, "summary.json")
    if os.path.exists(path):  # parts run earlier are kept
        summary["parts"] = json.load(open(path)).get("parts", {})
    for part in a.parts:
        t0 = time.perf_counter()
        rows, s = {"e3": lambda: _e3(n, dFs, t1), "e4": lambda: _e4(n, mus, realizations, t1),
                   "e6c": lambda: _e6c(n, t1)}[part]()
        s["wall_s"] = time.perf_counter() - t0
        write_csv(os.path.join(out, f"{part}.csv"), rows)
        summary["parts"][part] = dict(s, commit=commit, n=n)
        with open(path, "w") as fh:
            json.dump(summary, fh, indent=1, default=float)
        print(f"{part}: {s['wall_s']:.0f} s with compilation; " + json.dumps(s, default=float), flush=True)


if __name__ == "__main__":
    main()
