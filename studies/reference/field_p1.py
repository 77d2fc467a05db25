"""The field model P1 against an independent reference (GitHub issue [verify-honest], item 5).

Computes, with the reference of `tests/independent/field_p1.py` (plain NumPy: spectral
collocation in space, Moreau–Jean trapezoidal steps with an exact per-step friction problem) and
with jaxrod's field model (finite differences, projected Verlet), the same quantities:

1. v₀* [m/s] of the sine mode-6 velocity perturbation at ΔF = 2 N and 5 N, μ = 0.3;
2. ΔF* [N] of the random position perturbation (forces ±2 N/m on the 500-segment noise grid,
   key 0, for 1 ms, then released from rest), μ = 0.3;
3. one column of the stability map (`jaxrod.stability_map`, μ = 0.3 grid): the labels at
   ΔF = dF_grid[7] = 4.82 N over its 16 v₀, and the searched boundary v₀* at that load for
   μ = 0.1, 0.3, 0.6,

each at n = 64 nodes and, for the measured convergence of both schemes, at 2n = 128 nodes and
at half the step. The tolerance of each comparison is E_jaxrod + E_reference, with
E = 2(|x(n) − x(2n)| + |x(dt) − x(dt/2)|) + the final bisection bracket: the Richardson
estimate of the error of x(n, dt), (x(n) − x(2n))/(1 − 2^−p), for first-order convergence
p = 1, the order both schemes have at friction events (a higher order would give a smaller E). Writes `results/reference/field_p1.csv`,
`field_p1.json` and `agreement.md`. Run: `.venv/bin/python studies/reference/field_p1.py`
(about 2 min on 2 cores; `--export-draws` rewrites the random draws file from jaxrod).
"""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests"))
from independent.field_p1 import (Rod, FieldP1, critical_load_random_force,  # noqa: E402
                                  critical_velocity, sine_velocity)

OUT = os.path.join(ROOT, "results", "reference")
DRAWS = os.path.join(ROOT, "tests", "independent", "random_force_key0.txt")

MU = 0.3
LOADS = (2.0, 5.0)  # ΔF [N] of item 1
AMPLITUDE, DURATION = 2.0, 1e-3  # random position: N/m, s (E4 C of jaxrod.experiments.e4)
MAP_DF = float(np.geomspace(0.5, 64.0, 16)[7])  # jaxrod.stability_map's default grid
MAP_V0 = np.geomspace(1e-3, 0.2, 16)
MAP_DF_MAX = 64.0  # the map's largest load sets its step
COLUMN_MUS = (0.1, 0.3, 0.6)
N, N2 = 64, 128  # nodes; forcing of the random position kept on N sine modes at 2N
DT_REF = 1e-4  # s, the reference's step (its convergence: DT_REF/2)
RTOL = 1e-4  # relative bracket of every bisection
T1, THRESHOLD = 2.0, 0.5  # s, rad: jaxrod's horizon and buckling threshold


def export_draws():
    """Write jaxrod's random draws r_j (key 0, grid 500, uniform in [−1, 1]) as plain numbers."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    r = np.asarray(jax.random.uniform(jax.random.key(0), (499,), jnp.float64, -1.0, 1.0))
    rev = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout
    header = ("r_j, j = 1..499: jax.random.uniform(jax.random.key(0), (499,), float64, -1, 1), the draws of\n"
              "jaxrod.perturbations.scene_noise_modes (grid 500) for key 0, the default key of\n"
              f"jaxrod.boundary.critical_load; exported once by studies/reference/field_p1.py (jaxrod {rev.strip()})")
    np.savetxt(DRAWS, r, fmt="%.17g", header=header)


def load_draws() -> np.ndarray:
    return np.loadtxt(DRAWS)


# -- the reference ------------------------------------------------------------------------------

def reference_values(n: int, dt: float, forcing_modes: int = N) -> dict:
    """Every quantity of the module by the reference at `n` nodes, step `dt` [s]."""
    draws = load_draws()
    out = {}
    for dF in LOADS:
        out[f"v0_star_dF{dF:g}_mu{MU:g}"] = critical_velocity(Rod(mu=MU), dF, n, dt, t1=T1, threshold=THRESHOLD,
                                                             rtol=RTOL)[0]
    out[f"dF_star_random_position_mu{MU:g}"] = critical_load_random_force(
        Rod(mu=MU), draws, AMPLITUDE, n, dt, modes=forcing_modes, duration=DURATION, t1=T1, threshold=THRESHOLD,
        rtol=RTOL)[0]
    for mu in COLUMN_MUS:
        out[f"v0_star_dF{MAP_DF:.4g}_mu{mu:g}"] = critical_velocity(Rod(mu=mu), MAP_DF, n, dt, t1=T1,
                                                                   threshold=THRESHOLD, rtol=RTOL)[0]
    model = FieldP1(Rod(mu=MU), Rod(mu=MU).F0(6) + MAP_DF, n, dt)
    out[f"map_column_dF{MAP_DF:.4g}_mu{MU:g}"] = "".join(
        str(int(model.run(*sine_velocity(model, v), T1, THRESHOLD).buckled)) for v in MAP_V0)
    return out


# -- jaxrod -------------------------------------------------------------------------------------

def jaxrod_values(n: int, dt_scale: float = 1.0, forcing_modes: int = N) -> tuple[dict, dict]:
    """The same quantities by jaxrod's field model at `n` nodes and `dt_scale` × its own step.
    **Returns:** (values, steps [s] used)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from jaxrod import RodChannel
    from jaxrod.boundary import critical_load, critical_velocity as jx_velocity
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    f = lambda x: jnp.asarray(x, jnp.float64)
    out, steps = {}, {}
    rod = RodChannel.reference(mu=MU)
    for dF in LOADS:
        dt = Scene(rod, f(dF), make_perturbation("sine", 1.0), n=n).step() * dt_scale
        r, _ = jx_velocity(rod, f(dF), n=n, dt=dt, rtol=RTOL, sensitivities=())
        out[f"v0_star_dF{dF:g}_mu{MU:g}"], steps[f"v0_star_dF{dF:g}_mu{MU:g}"] = float(r.root), dt
    key = f"dF_star_random_position_mu{MU:g}"
    dt = Scene(rod, f(100.0), make_perturbation("random-position", 1.0), n=n).step() * dt_scale
    if forcing_modes >= n:  # jaxrod's own perturbation: its forcing resolves n modes
        r, _ = critical_load(rod, f(AMPLITUDE), perturbation="random-position", n=n, dt=dt, rtol=RTOL,
                             sensitivities=())
        out[key] = float(r.root)
    else:
        out[key] = _jaxrod_random_force_on_modes(rod, n, dt, forcing_modes)
    steps[key] = dt
    map_dt = Scene(RodChannel.reference(mu=max(COLUMN_MUS)), f(MAP_DF_MAX), n=n).step() * dt_scale
    for mu in COLUMN_MUS:
        r, _ = jx_velocity(RodChannel.reference(mu=mu), f(MAP_DF), n=n, dt=map_dt, rtol=RTOL, sensitivities=())
        out[f"v0_star_dF{MAP_DF:.4g}_mu{mu:g}"] = float(r.root)
        steps[f"v0_star_dF{MAP_DF:.4g}_mu{mu:g}"] = map_dt
    out[f"map_column_dF{MAP_DF:.4g}_mu{MU:g}"] = jaxrod_map_column(n, map_dt)
    steps[f"map_column_dF{MAP_DF:.4g}_mu{MU:g}"] = map_dt
    return out, steps


def jaxrod_map_column(n: int, dt: float) -> str:
    """jaxrod's labels (1 buckled) at ΔF = MAP_DF over MAP_V0 at n nodes, step dt: each member
    of the map is a scene run to t1 (a sweep member takes exactly its single run's steps)."""
    import jax.numpy as jnp

    from jaxrod import RodChannel
    from jaxrod.boundary import crossing_state
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    rod = RodChannel.reference(mu=MU)
    lab = lambda v: float(crossing_state(Scene(rod, jnp.asarray(MAP_DF, jnp.float64),
                                               make_perturbation("sine", jnp.asarray(v, jnp.float64)),
                                               n=n, dt=dt), T1)[1])
    return "".join(str(int(lab(v))) for v in MAP_V0)


def _jaxrod_random_force_on_modes(rod, n: int, dt: float, modes: int) -> float:
    """jaxrod's ΔF* of the random position with its forcing kept on `modes` sine modes at n > modes
    nodes (the same physical perturbation at 2n), by bisection of jaxrod's run label."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from jaxrod.boundary import crossing_state
    from jaxrod.perturbations import AbstractPerturbation, RandomForce, scene_noise
    from jaxrod.scene import Scene
    from independent.field_p1 import bisect

    class ForceOnModes(AbstractPerturbation):
        amplitude: jax.Array
        key: jax.Array
        duration: jax.Array
        modes: int = eqx.field(static=True)
        grid: int = eqx.field(static=True, default=500)

        def fields(self, model):
            s = model.sample_points()
            return scene_noise(self.key, self.amplitude, s, model.rod.L, self.grid, modes=self.modes), jnp.zeros_like(s)

        def initial_state(self, model, integrator=None):
            return RandomForce.initial_state(self, model, integrator)

    pert = ForceOnModes(jnp.asarray(AMPLITUDE, jnp.float64), jax.random.key(0), jnp.asarray(DURATION, jnp.float64),
                        modes)
    label = eqx.filter_jit(lambda dF: crossing_state(Scene(rod, dF, pert, "field", n, 6, dt), T1)[1])
    lo, hi, _ = bisect(lambda dF: bool(label(jnp.asarray(dF, jnp.float64)) > 0), 0.05, 100.0, RTOL)
    return math.sqrt(lo * hi)


# -- comparison ---------------------------------------------------------------------------------

ORDER = 1  # convergence order assumed in the Richardson error estimate (both schemes' order at events)


def tolerance(base, n2, half, rtol=RTOL) -> float:
    """E = (|x(n) − x(2n)| + |x(dt) − x(dt/2)|)/(1 − 2^−ORDER) plus the final bisection bracket."""
    return (abs(base - n2) + abs(base - half)) / (1 - 2.0**-ORDER) + rtol * abs(base)


def main():
    if "--export-draws" in sys.argv or not os.path.exists(DRAWS):
        export_draws()
    os.makedirs(OUT, exist_ok=True)
    t0 = time.time()
    ref = {"n": reference_values(N, DT_REF), "2n": reference_values(N2, DT_REF), "dt/2": reference_values(N, DT_REF / 2)}
    t_ref = time.time() - t0
    jx, jx_dt = {}, {}
    for name, (n, sc) in {"n": (N, 1.0), "2n": (N2, 1.0), "dt/2": (N, 0.5)}.items():
        jx[name], jx_dt[name] = jaxrod_values(n, sc)
    t_jx = time.time() - t0 - t_ref
    rows, table, summary = [], [], {}
    for q in ref["n"]:
        for scheme, vals, dts in (("reference", ref, {k: DT_REF * (0.5 if k == "dt/2" else 1.0) for k in ref}),
                                  ("jaxrod", jx, {k: jx_dt[k][q] for k in jx})):
            for res, v in vals.items():
                rows.append(dict(quantity=q, scheme=scheme, resolution=res, n=N2 if res == "2n" else N,
                                 dt=dts[res], value=v[q]))
        if q.startswith("map_column"):
            summary[q] = {"reference": ref["n"][q], "jaxrod": jx["n"][q], "v0": MAP_V0.tolist(),
                          "reference_2n": ref["2n"][q], "reference_dt/2": ref["dt/2"][q],
                          "jaxrod_2n": jx["2n"][q], "jaxrod_dt/2": jx["dt/2"][q]}
            mism = [float(v) for v, a, b in zip(MAP_V0, ref["n"][q], jx["n"][q]) if a != b]
            table.append((q, jx["n"][q], ref["n"][q], f"{len(mism)} labels differ" + (f" (v₀ = {mism})" if mism else ""),
                          "exact, except v₀ within the tolerance of v₀*(μ = 0.3) of this load",
                          "labels of the map's 16 v₀ (1 = buckled)"))
            continue
        e_ref = tolerance(ref["n"][q], ref["2n"][q], ref["dt/2"][q])
        e_jx = tolerance(jx["n"][q], jx["2n"][q], jx["dt/2"][q])
        tol = e_ref + e_jx
        d = jx["n"][q] - ref["n"][q]
        summary[q] = {"reference": ref["n"][q], "jaxrod": jx["n"][q], "difference": d, "tolerance": tol,
                      "agree": abs(d) <= tol, "E_reference": e_ref, "E_jaxrod": e_jx,
                      "reference_2n": ref["2n"][q], "reference_dt/2": ref["dt/2"][q],
                      "jaxrod_2n": jx["2n"][q], "jaxrod_dt/2": jx["dt/2"][q]}
        src = (f"jaxrod |n−2n| {abs(jx['n'][q] - jx['2n'][q]):.3g}, |dt−dt/2| {abs(jx['n'][q] - jx['dt/2'][q]):.3g}; "
               f"reference |n−2n| {abs(ref['n'][q] - ref['2n'][q]):.3g}, |dt−dt/2| {abs(ref['n'][q] - ref['dt/2'][q]):.3g}; "
               f"E = (Σ|Δ|)/(1 − 2^−{ORDER}) + {RTOL:g}·x per scheme")
        table.append((q, f"{jx['n'][q]:.6g}", f"{ref['n'][q]:.6g}", f"{d:+.3g} ({100 * d / ref['n'][q]:+.2f} %)",
                      f"{tol:.3g}" + ("" if abs(d) <= tol else " — **exceeded**"), src))
    with open(os.path.join(OUT, "field_p1.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    params = {
        "rod": {"L": 3.0, "d": 1.5e-3, "E": 77e9, "rho_v": 6450.0, "R": 5.125e-3, "g": 9.81, "mu_s = mu_d": "the mu of each quantity"},
        "F0_6": Rod().F0(6), "mu": MU, "loads_dF": LOADS, "random_position": {"amplitude_N_per_m": AMPLITUDE,
        "duration_s": DURATION, "key": 0, "grid": 500, "forcing_modes": N, "draws": os.path.relpath(DRAWS, ROOT)},
        "map_column": {"dF": MAP_DF, "v0": MAP_V0.tolist(), "mus": COLUMN_MUS, "dt_from_load": MAP_DF_MAX},
        "n": N, "n2": N2, "reference_dt": DT_REF, "jaxrod_dt": jx_dt, "rtol": RTOL, "t1": T1, "threshold": THRESHOLD,
        "tolerance_rule": "E_jaxrod + E_reference, E = (|x(n)-x(2n)| + |x(dt)-x(dt/2)|)/(1 - 2**-order) + rtol*x",
        "order": ORDER,
        "runtime_s": {"reference": round(t_ref, 1), "jaxrod": round(t_jx, 1)}, "quantities": summary,
    }
    with open(os.path.join(OUT, "field_p1.json"), "w") as fh:
        json.dump(params, fh, indent=1, default=float)
    write_agreement(table)
    print(json.dumps(summary, indent=1, default=float))


def write_agreement(table):
    lines = [
        "# Field model P1: jaxrod against an independent reference",
        "",
        "Written by `studies/reference/field_p1.py` (data: `field_p1.csv`, `field_p1.json`). jaxrod: "
        "finite differences (D₂²) and projected Verlet at its own step; reference "
        "(`tests/independent/field_p1.py`): spectral collocation (exact ω_m) and Moreau–Jean trapezoidal "
        f"steps of {DT_REF:g} s with the friction problem solved exactly each step. Both at n = {N} nodes; "
        f"μ_s = μ_d; horizon {T1:g} s; buckled when max|θ| > {THRESHOLD:g} rad; ΔF above F⁰₆ = 1.308 N. "
        f"Random position: ±{AMPLITUDE:g} N/m on the 500-segment grid (key 0), {DURATION * 1e3:g} ms, "
        f"forcing on {N} sine modes at both n and 2n. Map column: ΔF = {MAP_DF:.4g} N (the 8th load of "
        "`stability_map`'s grid), v₀ = geomspace(1e-3, 0.2, 16) m/s, step of the map's largest load (64 N).",
        "",
        "| quantity | jaxrod | reference | difference | tolerance | where the tolerance comes from |",
        "|---|---|---|---|---|---|",
    ]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in table]
    lines += ["", "Units: v₀* in m/s, ΔF* in N. Tolerance = E_jaxrod + E_reference, each E the Richardson estimate "
              "of that scheme's error at (n, dt) for first-order convergence, (|x(n) − x(2n)| + |x(dt) − x(dt/2)|)/(1 − 2⁻¹), "
              "plus its bisection bracket; all numbers, and the 2n and dt/2 values, in `field_p1.json`."]
    with open(os.path.join(OUT, "agreement.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
