"""The 3D rod's v₀* against the independent reference at matched resolution (GitHub issue
[verify-honest], item 5: the reference backs the 3D rod's check through the field model).

The 3D rod of s segments has s − 1 interior nodes of spacing L/s; the field model P1 and the
reference (`tests/independent/field_p1.py`: plain NumPy, spectral collocation, Moreau–Jean
trapezoidal steps, no code shared with jaxrod) are run at those s − 1 nodes, at ΔF = 5 N and
20 N, μ = 0.3, sine mode 6, horizon 2 s, buckled when max|θ| > 0.5 rad. The 3D rod's brackets are
read from the committed boundary searches (`results/paper/e3/rod3d_boundary_n{s}.csv`, s = 60 and
120: `jaxrod.experiments.e3.rod3d.boundary_3d`, horizon 0.4 s, 1 % brackets; 240 segments are
left out: the field model's convergence run at 2 × 239 nodes over 2 s takes too long here). The tolerance
of field against reference is the rule of `field_p1.py`: each scheme's first-order Richardson
estimate from n → 2n and dt → dt/2, plus the bisection bracket.

Writes `results/reference/rod3d_matched.csv`, `.json` and `rod3d_matched.md`.
Run: `.venv/bin/python studies/reference/rod3d_matched.py` (a few minutes on 2 cores).
"""

from __future__ import annotations

import csv
import datetime
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from independent.field_p1 import Rod, critical_velocity  # noqa: E402
from field_p1 import DT_REF, MU, RTOL, T1, THRESHOLD, tolerance  # noqa: E402

OUT = os.path.join(ROOT, "results", "reference")
LOADS = (5.0, 20.0)  # ΔF [N] with 3D brackets at all three resolutions
SEGMENTS = (60, 120)


def rod3d_brackets() -> dict:
    """{(ΔF, s): (lo, hi) [m/s]} from the committed 3D boundary searches."""
    out = {}
    for s in SEGMENTS:
        with open(os.path.join(ROOT, "results", "paper", "e3", f"rod3d_boundary_n{s}.csv")) as fh:
            for r in csv.DictReader(fh):
                if float(r["dF"]) in LOADS and float(r["mu"]) == MU:
                    out[(float(r["dF"]), s)] = (1e-3 * float(r["bracket_lo_mm_s"]), 1e-3 * float(r["bracket_hi_mm_s"]))
    return out


def reference_v0(dF: float, n: int, dt: float) -> float:
    return critical_velocity(Rod(mu=MU), dF, n, dt, t1=T1, threshold=THRESHOLD, rtol=RTOL)[0]


def jaxrod_v0(dF: float, n: int, dt_scale: float = 1.0) -> tuple[float, float]:
    """jaxrod's field model at n nodes and dt_scale × its own step: (v₀* [m/s], step [s])."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from jaxrod import RodChannel
    from jaxrod.boundary import critical_velocity as jx_velocity
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    rod = RodChannel.reference(mu=MU)
    F = jnp.asarray(dF, jnp.float64)
    dt = Scene(rod, F, make_perturbation("sine", 1.0), n=n).step() * dt_scale
    r, _ = jx_velocity(rod, F, n=n, dt=dt, rtol=RTOL, sensitivities=())
    return float(r.root), dt


def main():
    os.makedirs(OUT, exist_ok=True)
    brackets = rod3d_brackets()
    rows, table = [], []
    t0 = time.time()
    for dF in LOADS:
        for s in SEGMENTS:
            n = s - 1
            ref = {"n": reference_v0(dF, n, DT_REF), "2n": reference_v0(dF, 2 * n, DT_REF),
                   "dt/2": reference_v0(dF, n, DT_REF / 2)}
            jx = {"n": jaxrod_v0(dF, n), "2n": jaxrod_v0(dF, 2 * n), "dt/2": jaxrod_v0(dF, n, 0.5)}
            e_ref = tolerance(ref["n"], ref["2n"], ref["dt/2"])
            e_jx = tolerance(jx["n"][0], jx["2n"][0], jx["dt/2"][0])
            lo, hi = brackets[(dF, s)]
            v3 = math.sqrt(lo * hi)
            row = dict(dF=dF, segments=s, nodes=n, rod3d=v3, rod3d_lo=lo, rod3d_hi=hi,
                       field=jx["n"][0], field_dt=jx["n"][1], field_2n=jx["2n"][0], field_dt2=jx["dt/2"][0],
                       reference=ref["n"], reference_dt=DT_REF, reference_2n=ref["2n"], reference_dt2=ref["dt/2"],
                       E_field=e_jx, E_reference=e_ref, field_minus_reference=jx["n"][0] - ref["n"],
                       tolerance=e_jx + e_ref, rod3d_minus_reference=v3 - ref["n"])
            rows.append(row)
            print(f"ΔF = {dF:g} N, {s} segments: 3D {1e3 * v3:.3f} mm/s [{1e3 * lo:.3f}, {1e3 * hi:.3f}], "
                  f"field {1e3 * jx['n'][0]:.3f}, reference {1e3 * ref['n']:.3f} mm/s", flush=True)
    wall = time.time() - t0
    with open(os.path.join(OUT, "rod3d_matched.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    rev = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    made = {s: subprocess.run(["git", "-C", ROOT, "log", "-1", "--format=%h %ad", "--date=short", "--",
                               f"results/paper/e3/rod3d_boundary_n{s}.csv"], capture_output=True, text=True).stdout.strip()
            for s in SEGMENTS}
    meta = dict(mu=MU, loads_dF=LOADS, segments=SEGMENTS, t1=T1, threshold=THRESHOLD, rtol=RTOL, mode=6,
                rod3d_source="results/paper/e3/rod3d_boundary_n{s}.csv (horizon 0.4 s, 1 % brackets)",
                rod3d_committed={str(s): c for s, c in made.items()},
                tolerance_rule="E_field + E_reference, E = (|x(n)-x(2n)| + |x(dt)-x(dt/2)|)/(1 - 2**-1) + rtol*x",
                jaxrod_commit=rev, date=datetime.date.today().isoformat(), runtime_s=round(wall, 1), rows=rows)
    with open(os.path.join(OUT, "rod3d_matched.json"), "w") as fh:
        json.dump(meta, fh, indent=1)
    lines = [
        "# The 3D rod against the independent reference at matched resolution",
        "",
        "Written by `studies/reference/rod3d_matched.py` (data: `rod3d_matched.csv`, `rod3d_matched.json`), "
        f"jaxrod at {rev}, {meta['date']}, 2-core CPU. v₀* [mm/s] of the sine mode-6 velocity at F⁰₆ + ΔF, μ = {MU:g}: "
        "the 3D rod of s segments (committed boundary searches, horizon 0.4 s, 1 % bracket; "
        + ", ".join(f"{s} segments committed at {c}" for s, c in made.items()) + "), jaxrod's field model and "
        "the reference (plain NumPy, spectral, Moreau–Jean, horizon 2 s) at the s − 1 interior nodes of the 3D rod. "
        "Tolerance of field against reference: both schemes' first-order Richardson estimates (n → 2n, dt → dt/2) "
        "plus the bisection bracket.",
        "",
        "| ΔF [N] | segments | 3D rod [bracket] | field, s − 1 nodes | reference, s − 1 nodes | field − reference (tolerance) | 3D − reference |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        d, tol, ref = r["field_minus_reference"], r["tolerance"], r["reference"]
        lines.append(f"| {r['dF']:g} | {r['segments']} | {1e3 * r['rod3d']:.2f} [{1e3 * r['rod3d_lo']:.2f}, "
                     f"{1e3 * r['rod3d_hi']:.2f}] | {1e3 * r['field']:.2f} | {1e3 * ref:.2f} | "
                     f"{100 * d / ref:+.2f} % ({100 * tol / ref:.1f} %{'' if abs(d) <= tol else ', **exceeded**'}) | "
                     f"{100 * r['rod3d_minus_reference'] / ref:+.2f} % |")
    with open(os.path.join(OUT, "rod3d_matched.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
