"""E4: what releases the friction, in the field model and the 3D rod (issue [paper3d], reason (A)).

At one load below both models' ΔF* (`--fraction` × the field model's ΔF*, so the same load for
both and both stable), one run per model and perturbation — E4 A (sine mode 6, 15 mm/s) and
E4 B (random velocity ±15 mm/s, realization 0 as `resolution.py`) — recorded every 2 ms until
the rod sticks (or `--t1`):

- the slip fraction: nodes on the wall that slide (3D: in contact and not held by the friction
  pass; field: θ̇ ≠ 0 — a stuck node's rate is exactly zero in projected Verlet);
- the kinetic energy by motion: lateral (both models), and for the 3D rod axial ½Σm vₓ²,
  torsional ½ΣJ ω₃² and the rotation of the cross-sections about the other axes (its inertia
  scaled up by `Rod3D.rotary_scale`, so that part is not physical);
- the energy dissipated (friction; for the 3D rod with contact and viscous damping).

Writes `partition_n{n}_mu{mu}.csv` (one row per run: the time to stick, the time integral of
the slip fraction, each kinetic part's largest value and its time integral, the dissipated
energy, the initial kinetic energy, the wall time) and `.png` (slip fraction and the kinetic
parts against time), with commit and date.

    python studies/paper/e4/rod3d/partition.py --n 240 --mu 0.05
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import boundary as bd  # noqa: E402
from jaxrod.output import write_csv  # noqa: E402
from jaxrod.registry import make_perturbation  # noqa: E402
from jaxrod.scene import Scene  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
PERTURBATION = {"A": "sine", "B": "random-velocity"}
FIELD_NODES = 499  # the random field's grid (500 segments) resolved, as the scene's default for random


def _commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    except OSError:
        return ""


def _key():
    return jax.random.fold_in(jax.random.key(0), 0)  # resolution.py's realization 0


def field_star(case, mu):
    rod = jr.RodChannel.reference(mu=mu)
    r, _ = bd.critical_load(rod, 15e-3, model="field", perturbation=PERTURBATION[case], key=_key(), n=FIELD_NODES,
                            bracket=(0.01, 100.0), rtol=1e-4, sensitivities=())
    return float(r.root)


def run(case, mu, dF, model, n, t1, n_save):
    """One run; returns (series dict over the saves up to the stop, summary dict)."""
    rod = jr.RodChannel.reference(mu=mu)
    scene = Scene(rod, dF, make_perturbation(PERTURBATION[case], 15e-3, key=_key()), kind=model,
                  n=n if model == "rod3d" else FIELD_NODES)
    t0 = time.perf_counter()
    sol = jax.block_until_ready(scene.run(t1=t1, n_save=n_save))
    wall = time.perf_counter() - t0
    ts = np.asarray(sol.ts)
    keep = ts <= float(sol.t_stop) + 1e-12
    m = scene.model()
    if model == "rod3d":
        v, w = np.asarray(sol.v.v), np.asarray(sol.v.w)
        mass, J = np.asarray(m.mass), np.asarray(m.inertia)
        parts = dict(lateral=0.5 * np.einsum("n,tn->t", mass, v[..., 1] ** 2 + v[..., 2] ** 2),
                     axial=0.5 * np.einsum("n,tn->t", mass, v[..., 0] ** 2),
                     torsional=0.5 * J[2] * np.sum(w[..., 2] ** 2, axis=-1),
                     rotary=0.5 * np.sum(J[:2] * w[..., :2] ** 2, axis=(-1, -2)))
        on_wall = np.asarray(sol.observables["normal_force"]) > 0
        sliding = on_wall & ~np.asarray(sol.v.stuck)
        slip = sliding.sum(-1) / np.maximum(on_wall.sum(-1), 1)
    else:
        rate = np.asarray(sol.v)
        parts = dict(lateral=np.asarray(sol.energies["kinetic"]))
        slip = np.mean(rate != 0.0, axis=-1)
    series = dict(t=ts[keep], slip=slip[keep], **{k: p[keep] for k, p in parts.items()})
    dt_save = ts[1] - ts[0]
    summary = dict(case=case, mu=mu, dF=dF, model=model, n=n if model == "rod3d" else FIELD_NODES,
                   buckled=int(sol.buckled), t_stop=float(sol.t_stop), slip_integral=float(np.sum(series["slip"]) * dt_save),
                   dissipated=float(np.asarray(sol.dissipated)[keep][-1]), kinetic0=float(sum(p[0] for p in parts.values())),
                   wall_s=round(wall, 1))
    for k in ("lateral", "axial", "torsional", "rotary"):  # the field model has only the lateral part
        summary[f"{k}_max"] = float(np.max(parts[k][keep])) if k in parts else float("nan")
        summary[f"{k}_integral"] = float(np.sum(parts[k][keep]) * dt_save) if k in parts else float("nan")
    return series, summary


def plot(all_series, path, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 6.4), sharex="col")
    for j, case in enumerate(("A", "B")):
        for (c, model), s in all_series.items():
            if c != case:
                continue
            style = "-" if model == "rod3d" else "--"
            axes[0, j].plot(1e3 * s["t"], s["slip"], style, label=f"{model}")
            for k, color in zip(("lateral", "axial", "torsional"), ("C0", "C1", "C2")):
                if k in s:
                    axes[1, j].semilogy(1e3 * s["t"], np.maximum(s[k], 1e-16), style, color=color, label=f"{model}: {k}")
        axes[0, j].set_title(f"E4 {case} ({PERTURBATION[case]})", fontsize=9)
        axes[0, j].set_ylabel("slip fraction of the contacts")
        axes[1, j].set_ylabel("kinetic energy [J]")
        axes[1, j].set_xlabel("t [ms]")
        axes[0, j].legend(fontsize=7)
        axes[1, j].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mu", type=float, default=0.05)
    p.add_argument("--n", type=int, default=240, help="segments of the 3D rod")
    p.add_argument("--fraction", type=float, default=0.9, help="the load as a fraction of the field model's ΔF*")
    p.add_argument("--t1", type=float, default=2.0, help="horizon [s] (the search's)")
    p.add_argument("--n-save", type=int, default=1001)
    a = p.parse_args()
    rows, series = [], {}
    for case in ("A", "B"):
        star = field_star(case, a.mu)
        dF = a.fraction * star
        print(f"E4 {case}, mu = {a.mu:g}: field dF* = {star:.4g} N; runs at {dF:.4g} N", flush=True)
        for model in ("field", "rod3d"):
            s, row = run(case, a.mu, dF, model, a.n, a.t1, a.n_save)
            row.update(field_dF_star=star, commit=_commit(), date=datetime.date.today().isoformat())
            rows.append(row)
            series[(case, model)] = s
            print(f"  {model}: stuck at {1e3 * row['t_stop']:.1f} ms (buckled {row['buckled']}), slip integral "
                  f"{1e3 * row['slip_integral']:.2f} ms, dissipated {row['dissipated']:.3g} J of {row['kinetic0']:.3g} J, "
                  f"{row['wall_s']:.0f} s", flush=True)
    stem = os.path.join(HERE, f"partition_n{a.n}_mu{a.mu:g}")
    write_csv(stem + ".csv", rows)
    plot(series, stem + ".png", f"μ = {a.mu:g}, ΔF = {a.fraction:g} × the field model's ΔF*; field {FIELD_NODES} nodes "
                                f"(dashed), 3D rod {a.n} segments (solid)")


if __name__ == "__main__":
    main()
