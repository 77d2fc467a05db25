"""Which model for which scene: the cheapest model whose answer is within 2 % of the converged
field model's.

Scenes (reference rod; every search uses the horizon T = 0.5 s of `jaxrod boundary` and
`jaxrod critical-load`, runs stop when the rod sticks or passes max|θ| = 0.5 rad):

- `sine dF=1/5/20`: sine mode-6 lateral velocity at mu = 0.3; the answer is the critical
  speed v0* [m/s] (label bisection, bracket [1e-4, 1] m/s).
- `map`: the E3 classification, mu = 0.3, sine mode 6, a log grid of dF in [0.5, 64] N x v0 in
  [1, 200] mm/s; the answer is the buckled/straight label of every point (agreement >= 98 %).
- `random velocity mu=0.05 / 1`: a lateral velocity uniform in ±15 mm/s, drawn independently
  on the reference paper's 500 segments, `realizations` draws; the answers are the mean
  critical load dF* [N] (label bisection on log dF, bracket [0.05, 200] N) and the median
  dominant mode of the rod buckled at 1.05 dF*.
- `random position mu=0.05 / 1`: lateral forces uniform in ±2 N/m on the 500 segments for 1 ms,
  then released from rest (the paper's position perturbation); same answers.

The random fields are defined once, on 500 segments, as sine series (modes 1-499), and every
model sees the part of the same field that it resolves: a field model with n nodes the modes
m <= n, a Galerkin model its own modes, the single-mode model mode 6. (Drawing independently
at each model's own points, as `jaxrod.RandomVelocity` does, would change the perturbation's
modal content with n and leave nothing to converge to.)

Models: the single-mode oscillator (mode 6), Galerkin with 8-64 modes, the field model at
32-768 nodes (1536 for the random scenes); the reference is the finest field model (for the
sine scenes converged at 768 nodes: see `field_convergence.py`). "Default" marks the resolution `jaxrod` picks by itself
(`jaxrod.scene.default_nodes`: 128 nodes up to 32 unstable modes, 384 beyond; 32 Galerkin
modes). Times: compilation and one run of the whole computation (bisection included),
measured separately; the cheapest model is the one with the shortest run (see `cost`).

    python benchmarks/model_choice.py [--quick]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.scene import Scene, default_nodes  # noqa: E402
from jaxrod.search import bisect  # noqa: E402

T1 = 0.5  # s, the horizon of every run
TOL = 0.02  # "within 2 %"
SEGMENTS = 500  # the reference paper's discrete rod
DF_BRACKET = (0.05, 200.0)  # N
V_BRACKET = (1e-4, 1.0)  # m/s
MAP_DF = (0.5, 64.0)
MAP_V0 = (1e-3, 0.2)


# -- the perturbations, defined once on 500 segments ---------------------------------------------

def segment_modes(key, amplitude: float) -> np.ndarray:
    """Sine-series coefficients (modes 1..499) of a field drawn uniformly in ±`amplitude` on the
    500 segments (midpoint rule: exact for modes below 500)."""
    vals = np.asarray(jax.random.uniform(key, (SEGMENTS,), jnp.float64, -1.0, 1.0)) * amplitude
    s = (np.arange(SEGMENTS) + 0.5) / SEGMENTS
    m = np.arange(1, SEGMENTS)
    return (2.0 / SEGMENTS) * np.sin(np.pi * s[:, None] * m[None, :]).T @ vals


def _resolved(model, b):
    """The sine series `b` at the model's sample points, cut to the modes the model resolves."""
    s = model.sample_points()
    keep = model.n_nodes if isinstance(model, jr.FieldModel) else model.n_modes
    m = jnp.arange(1, min(keep, b.shape[-1]) + 1, dtype=s.dtype)
    return jnp.sin(jnp.pi * s[:, None] * m[None, :] / model.rod.L) @ b[: len(m)]


class SeriesVelocity(jr.perturbations.AbstractPerturbation):
    """A lateral velocity given as a sine series `b` [m/s] (modes 1..len(b)), rod straight."""

    b: jax.Array

    def fields(self, model):
        v = _resolved(model, self.b)
        return jnp.zeros_like(v), v


class SeriesForce(jr.RandomForce):
    """`jaxrod.RandomForce` (forces for `duration`, then released from rest) with the force per
    length given as a sine series `b` [N/m] instead of drawn at the model's points."""

    b: jax.Array = None

    def fields(self, model):
        f = _resolved(model, self.b)
        return f, jnp.zeros_like(f)


def perturbation(kind: str, b):
    if kind == "random velocity":
        return SeriesVelocity(b)
    return SeriesForce(0.0, jax.random.key(0), 1e-3, b)


# -- candidates and their static resolution ------------------------------------------------------

def candidates(quick: bool, random: bool):
    """The models tried, cheapest class first; the last one is the reference. Random scenes add
    1536 nodes: their perturbation reaches mode 499, which 768 nodes resolve only coarsely."""
    if quick:
        return [("mode", None), ("galerkin", 8), ("galerkin", 32), ("field", 32), ("field", 64), ("field", 128)]
    return [("mode", None), ("galerkin", 8), ("galerkin", 16), ("galerkin", 32), ("galerkin", 64),
            ("field", 32), ("field", 64), ("field", 128), ("field", 384), ("field", 768)] + (
                [("field", 1536)] if random else [])


def label(kind, n):
    return "single mode (m = 6)" if kind == "mode" else f"{kind}, n = {n}"


def resolution(rod, dF_max, kind, n):
    """(n, dt, grid_dt): static settings from the scene's largest load."""
    probe = Scene(rod, float(dF_max), kind=kind, n=n)
    grid_dt = Scene(rod, float(dF_max), kind="field", n=128).step()
    return n, probe.step(), grid_dt


def is_default(rod, dF_max, kind, n):
    if kind == "field":
        return n == default_nodes(rod, float(Scene(rod, float(dF_max)).F))
    return kind == "galerkin" and n == jr.scene.DEFAULT_MODES


def run_scene(rod, dF, pert, kind, n, dt, grid_dt):
    sc = Scene(rod, dF, pert, kind, n, 6, dt, grid_dt=grid_dt)
    sol = sc.run(t1=T1, n_save=101, save_state=False)
    return sol, sc


def dominant(sc, q):
    if sc.kind == "field":
        return jr.modal.dominant_mode(q)
    if sc.kind == "galerkin":
        return jnp.argmax(jnp.abs(q)) + 1
    return jnp.asarray(sc.mode)


def cost(row):
    """Ranking key: the run time (compilation excluded: it is paid once per resolution), with
    runs under 50 ms counted as equally cheap (timer noise on a shared CPU); then fewer
    degrees of freedom; then the shorter wall time (compilation included)."""
    return (max(row["run_s"], 0.05), 1 if row["model"] == "mode" else row["n"], row["wall_s"])


def timed(fn, *args):
    """Compile (lower + compile) and one run of `jax.jit(fn)`, timed separately."""
    t0 = time.perf_counter()
    compiled = jax.jit(fn).lower(*args).compile()
    t1 = time.perf_counter()
    out = jax.block_until_ready(compiled(*args))
    return out, t1 - t0, time.perf_counter() - t1


# -- the computations --------------------------------------------------------------------------

def critical_speed(rod, dF, kind, n, iters):
    n, dt, gdt = resolution(rod, dF, kind, n)

    def fn():
        buckles = lambda v0: run_scene(rod, dF, jr.SineVelocity(v0, 6.0), kind, n, dt, gdt)[0].buckled
        lo, hi = bisect(buckles, *V_BRACKET, iters)
        ok = ~buckles(jnp.asarray(V_BRACKET[0])) & buckles(jnp.asarray(V_BRACKET[1]))
        return jnp.where(ok, jnp.sqrt(lo * hi), jnp.nan)

    v, c, r = timed(fn)
    return {"value": float(v)}, c, r


def map_labels(rod, dFs, v0s, kind, n):
    n, dt, gdt = resolution(rod, dFs.max(), kind, n)
    grid_dF, grid_v = (jnp.asarray(a.ravel()) for a in np.meshgrid(dFs, v0s, indexing="ij"))

    def fn(dF, v0):
        sol, _ = run_scene(rod, dF, jr.SineVelocity(v0, 6.0), kind, n, dt, gdt)
        return sol.buckled

    b, c, r = timed(jax.vmap(fn), grid_dF, grid_v)
    return {"labels": np.asarray(b)}, c, r


def critical_load(mu, kind_p, B, kind, n, iters):
    rod = jr.RodChannel.reference(mu=mu)
    n, dt, gdt = resolution(rod, DF_BRACKET[1], kind, n)
    lo0, hi0 = (jnp.asarray(x) for x in DF_BRACKET)

    def one(b):
        pert = perturbation(kind_p, b)
        buckles = lambda dF: run_scene(rod, dF, pert, kind, n, dt, gdt)[0].buckled
        lo, hi = bisect(buckles, lo0, hi0, iters)
        top = buckles(hi0)
        # no buckling below the bracket top: +inf (the model sees too little of the perturbation)
        dF = jnp.where(top, jnp.where(buckles(lo0), lo0, jnp.sqrt(lo * hi)), jnp.inf)
        sol, sc = run_scene(rod, jnp.where(top, 1.05 * dF, hi0), pert, kind, n, dt, gdt)
        return dF, jnp.where(sol.buckled, dominant(sc, sol.q_final), 0)

    (dF, modes), c, r = timed(jax.vmap(one), jnp.asarray(B))
    dF, modes = np.asarray(dF), np.asarray(modes)
    mean = float(np.mean(dF)) if np.all(np.isfinite(dF)) else math.inf
    buckled = modes[modes > 0]
    return {"value": mean, "per_realization": dF.tolist(), "modes": modes.tolist(),
            "mode": float(np.median(buckled)) if buckled.size else math.nan}, c, r


# -- the benchmark ---------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer models, realizations and iterations")
    ap.add_argument("--out", default=None,
                    help="CSV path (default benchmarks/results/model_choice.csv, model_choice_quick.csv with --quick)")
    args = ap.parse_args()
    args.out = args.out or f"benchmarks/results/model_choice{'_quick' if args.quick else ''}.csv"
    quick = args.quick
    iters = 10 if quick else 14  # bisection halvings: relative bracket 6e-4 (v0*), 6e-4 (dF*) when full
    R = 2 if quick else 8
    n_map = 4 if quick else 8
    t_start = time.perf_counter()
    print(f"jax {jax.__version__}, {jax.devices()[0].platform}, float64; reference: the finest field model; "
          f"{R} realizations; horizon {T1} s")

    rod = jr.RodChannel.reference(mu=0.3)
    scenes = []  # (scene name, answer kind, dF_max for the default, compute(kind, n) -> (answer, c, r))
    for dF in (1.0, 5.0, 20.0):
        scenes.append((f"sine mode 6, dF = {dF:g} N, mu = 0.3", "v0* [mm/s]", dF, "sine", 0.3,
                       lambda k, n, dF=dF: critical_speed(rod, dF, k, n, iters)))
    dFs = np.geomspace(*MAP_DF, n_map)
    v0s = np.geomspace(*MAP_V0, n_map)
    scenes.append((f"E3 map, mu = 0.3, {n_map}x{n_map} grid", "labels", MAP_DF[1], "sine", 0.3,
                   lambda k, n: map_labels(rod, dFs, v0s, k, n)))
    keys = jax.random.split(jax.random.key(7), R)
    for kind_p, amp in (("random velocity", 15e-3), ("random position", 2.0)):
        B = np.stack([segment_modes(k, amp) for k in keys])
        for mu in (0.05, 1.0):
            scenes.append((f"{kind_p} ±{amp * 1e3 if kind_p == 'random velocity' else amp:g} "
                           f"{'mm/s' if kind_p == 'random velocity' else 'N/m'}, mu = {mu:g}",
                           "dF* [N]", DF_BRACKET[1], kind_p.replace(" ", "-"), mu,
                           lambda k, n, mu=mu, kp=kind_p, B=B: critical_load(mu, kp, B, k, n, iters)))

    rows, choices = [], []
    for name, what, dF_max, pert_kind, mu, compute in scenes:
        print(f"\n{name}")
        results = {}
        cands = candidates(quick, pert_kind != "sine")
        ref = cands[-1]
        for kind, n in cands:
            ans, c, r = compute(kind, n)
            results[(kind, n)] = (ans, c, r)
            shown = (f"{int(ans['labels'].sum())} of {ans['labels'].size} buckled" if "labels" in ans
                     else f"{ans['value'] * (1e3 if what.startswith('v0') else 1):.5g}"
                     + (f", mode {ans['mode']:g}" if "mode" in ans else ""))
            print(f"  {label(kind, n):22s} {shown:32s} compile {c:6.2f} s  run {r:8.2f} s")
        ref_ans = results[ref][0]
        best = None
        for kind, n in cands:
            ans, c, r = results[(kind, n)]
            mode_ok = None
            if "labels" in ans:
                err = 1.0 - float(np.mean(ans["labels"] == ref_ans["labels"]))
                val = f"{int(ans['labels'].sum())}/{ans['labels'].size} buckled"
            else:
                err = abs(ans["value"] / ref_ans["value"] - 1) if math.isfinite(ans["value"]) else math.inf
                val = ans["value"] * (1e3 if what.startswith("v0") else 1)
            ok = err <= TOL
            if "mode" in ans:  # random scenes: the critical load and the buckling mode must both hold
                mode_ok = ans["mode"] == ref_ans["mode"]
                ok = ok and mode_ok
            row = dict(scene=name, answer=what, perturbation=pert_kind, mu=mu, model=kind, n=n,
                       default=is_default(rod, dF_max, kind, n), value=val, error=err,
                       dominant_mode=ans.get("mode"), mode_equal=mode_ok, within=ok,
                       compile_s=round(c, 3), run_s=round(r, 3), wall_s=round(c + r, 3),
                       per_realization=json.dumps([round(x, 4) for x in ans["per_realization"]])
                       if "per_realization" in ans else None)
            rows.append(row)
            if ok and (best is None or cost(row) < cost(best)):
                best = row
        refrow = next(r for r in rows if r["scene"] == name and (r["model"], r["n"]) == ref)
        dflt = next((r for r in rows if r["scene"] == name and r["default"] and r["model"] == "field"), None)
        choices.append(dict(scene=name, answer=what, perturbation=pert_kind, mu=mu,
                            reference_model=label(*ref), reference=refrow["value"], reference_mode=refrow["dominant_mode"],
                            chosen_model=best["model"], chosen_n=best["n"], chosen=label(best["model"], best["n"]),
                            chosen_value=best["value"], chosen_mode=best["dominant_mode"], error=best["error"],
                            run_s=best["run_s"], wall_s=best["wall_s"], reference_run_s=refrow["run_s"],
                            reference_wall_s=refrow["wall_s"],
                            default_field=label("field", dflt["n"]) if dflt else None,
                            default_field_error=dflt["error"] if dflt else None,
                            default_field_within=dflt["within"] if dflt else None))
        print(f"  -> {choices[-1]['chosen']} (error {best['error']:.3g}, run {best['run_s']:.2f} s, "
              f"wall {best['wall_s']:.2f} s; reference run {refrow['run_s']:.2f} s)")

    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    fields = sorted({k for r in rows for k in r}, key=lambda k: list(rows[0]).index(k) if k in rows[0] else 99)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    summary = {"realizations": R, "horizon_s": T1, "tolerance": TOL,
               "choices": choices, "seconds": round(time.perf_counter() - t_start, 1)}
    with open(os.path.splitext(args.out)[0] + "_summary.json", "w") as fh:
        json.dump(summary, fh, indent=1, default=float)
    print("\n| scene | answer | reference (finest field) | cheapest within 2 % | its answer | run (wall) | "
          "reference run (wall) |")
    print("|---|---|---:|---|---:|---:|---:|")
    fmt = lambda x, m=None: (x if isinstance(x, str) else f"{x:.4g}") + (f", mode {m:g}" if m is not None else "")
    for ch in choices:
        print(f"| {ch['scene']} | {ch['answer']} | {fmt(ch['reference'], ch['reference_mode'])} "
              f"(n = {ch['reference_model'].split('= ')[-1]}) | {ch['chosen']} | "
              f"{fmt(ch['chosen_value'], ch['chosen_mode'])} | {ch['run_s']:.2f} s ({ch['wall_s']:.1f} s) | "
              f"{ch['reference_run_s']:.2f} s ({ch['reference_wall_s']:.1f} s) |")
    print(f"total {summary['seconds']} s")


if __name__ == "__main__":
    main()
