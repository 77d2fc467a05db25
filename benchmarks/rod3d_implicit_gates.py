"""The implicit leapfrog on the 3D rod's other committed answers (issue [implicit3d]'s gates),
each beside the explicit scheme's committed value, with the wall time of both:

- `helix`: the frictionless rod of the post-buckling experiment (60 segments, pushed at 1 mm/s,
  viscous damping 50 1/s, a 0.5 mm mode-6 imperfection) goes over the top of the channel at an
  end load of 2.02–2.04 N with the explicit scheme (the reaction at the save before and at the
  first save with a node over the top, `jaxrod.experiments.helix`; docs/paper.md);
- `e1`: E1's critical force at μ = 0.3 (60 segments, 1 mm/s, three amplitudes), both schemes
  run here side by side;
- `e4`: E4's ΔF* at 500 segments (realization 0 of each perturbation, μ = 0.05, 0.3, 1) at the
  3D scene's default (`--dt 5e-5` only labels the rows) against the explicit scheme's committed
  points. The committed rows (0d1abd4) ran the implicit scheme under every perturbation; they
  showed the random ones off by 2–23 %, so since then a 3D scene runs the implicit scheme only
  under a sine velocity (`jaxrod.scene.scheme_for`), and a rerun checks the A rows only;
  `--e4-gammas 0.02 0` forces the implicit scheme on E4 C at μ = 0.05 at other γ;
- `lockup`: the lock-up scene's injection at μL/ℓ = 1, r/ℓ = 0.02, μ = 0.5, far load 2.5 F₀,
  0.3 m at 5 mm/s, damping 20/s, 37 segments: the entry force over the last fifth of the push,
  4.307–4.352 F₀ with the explicit scheme (results/lockup/muL1_far2.5/lockup.json); with
  `--lockup-n 37 74` also at 74 segments (explicit 4.237–4.282 F₀, muL1_far2.5_n74/lockup.json);

Rows (one per case and step) go to `benchmarks/results/rod3d_implicit_gates.csv` (a rerun
replaces its own rows).

    python benchmarks/rod3d_implicit_gates.py                 # all three (~8 min)
    python benchmarks/rod3d_implicit_gates.py --only helix --dt 5e-5 1e-4
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402

from jaxrod.experiments.helix import helix_measures, load_path  # noqa: E402
from jaxrod.lockup.push import inject, push_rod, units  # noqa: E402
from jaxrod.params import RodChannel  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_implicit_gates.csv")


def helix(dt):
    rod = RodChannel.reference(0.0)
    t0 = time.perf_counter()
    p = load_path(rod, 60, [(1e-3, 7e-3 / 1e-3)], sps=20, progress=False, scheme="implicit", dt=dt)
    sec = time.perf_counter() - t0
    h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
    over = np.flatnonzero(h["over_top"])
    i = int(over[0]) if over.size else None
    value = [float(p["reaction"][i - 1]), float(p["reaction"][i])] if i else [float("nan")] * 2
    return dict(case="helix over the top, mu 0, 60 segments [N]", dt=dt, explicit_lo=2.02, explicit_hi=2.04,
                implicit_lo=round(value[0], 4), implicit_hi=round(value[1], 4), seconds=round(sec, 1))


LOCKUP_EXPLICIT = {37: (4.307, 4.352), 74: (4.237, 4.282)}  # results/lockup/muL1_far2.5{,_n74}/lockup.json


def lockup(dt, n=37):
    rod = push_rod(1.0, 0.02, 0.5)
    F0, _ = units(rod)
    t0 = time.perf_counter()
    r = inject(rod, 2.5 * F0, 0.005, 0.3 / 0.005, n=None if n == 37 else n, n_save=201, damping=20.0,
               scheme="implicit", dt=dt)
    sec = time.perf_counter() - t0
    loading = r["phase"] == 0
    tail = loading & (r["push"] >= 0.8 * float(np.max(r["push"][loading])))
    lo, hi = LOCKUP_EXPLICIT[n]
    return dict(case=f"lock-up entry force, muL/ell 1, far 2.5 F0, {n} segments [F0]", dt=dt, explicit_lo=lo,
                explicit_hi=hi, implicit_lo=round(float(np.min(r["f_in"][tail])), 4),
                implicit_hi=round(float(np.max(r["f_in"][tail])), 4), seconds=round(sec, 1), result=int(r["result"]))


def e1(dt):
    """E1's critical force (the first peak of the pushed end's reaction, `e1_curves`) at μ = 0.3,
    60 segments, 1 mm/s, sine mode-6 amplitudes 5, 15, 30 mm/s: explicit (half its limit) and
    implicit (`dt`) in this process."""
    from jaxrod.experiments.rod3d import e1_curves

    v0s = (5e-3, 15e-3, 30e-3)
    t0 = time.perf_counter()
    ex = e1_curves(0.3, v0s, dt_fraction=0.5, scheme="leapfrog")
    t_ex = time.perf_counter() - t0
    t0 = time.perf_counter()
    im = e1_curves(0.3, v0s, scheme="implicit") if dt is None else _e1_at(v0s, dt)
    t_im = time.perf_counter() - t0
    fe, fi = np.asarray(ex["critical_force"]), np.asarray(im["critical_force"])
    return dict(case="E1 critical force, mu 0.3, 60 segments, v0 5/15/30 mm/s [N]", dt=dt,
                explicit_lo=round(float(fe.min()), 4), explicit_hi=round(float(fe.max()), 4),
                implicit_lo=round(float(fi.min()), 4), implicit_hi=round(float(fi.max()), 4),
                per_amplitude_difference_percent=[round(float(100 * (b / a - 1)), 2) for a, b in zip(fe, fi)],
                seconds=round(t_im, 1), explicit_seconds=round(t_ex, 1))


E4_POINTS = [("A", mu) for mu in (0.05, 0.3, 1.0)]  # realization 0; B and C run the explicit scheme


def e4(dt):
    """E4's ΔF* of the 3D rod at 500 segments (realization 0; sine 15 mm/s, random velocity
    ±15 mm/s, random position ±2 N/m for 1 ms; μ = 0.05, 0.3, 1; horizon 0.5 s, rtol 1e-2, bracket
    ×/÷ 1.5 around the field model's) with the implicit scheme at its default step, one row per
    point, against the explicit scheme's committed row (results/paper/e4/rod3d_n500.csv)."""
    from jaxrod.experiments.e4.rod3d import e4_point

    with open(os.path.join(os.path.dirname(HERE), "results", "paper", "e4", "rod3d_n500.csv"), newline="") as fh:
        ref = {(r["case"], float(r["mu"])): r for r in csv.DictReader(fh)
               if r["realization"] == "0" and r["t1"] == "0.5" and r["width"] == "1.5" and r["result"] == "0"}
    rows = []
    for case, mu in E4_POINTS:
        row = e4_point(case, mu, 0, 500, t1=0.5, width=1.5)
        r = ref.get((case, mu))
        rows.append(dict(case=f"E4 {case}, mu {mu}, realization 0, 500 segments: dF* [N]", dt=dt,
                         explicit_lo=round(float(r["lo"]), 4) if r else "", explicit_hi=round(float(r["hi"]), 4) if r else "",
                         implicit_lo=round(row["lo"], 4), implicit_hi=round(row["hi"], 4), seconds=row["wall_s"],
                         explicit_seconds=float(r["wall_s"]) if r else "", result=row["result"]))
        print(rows[-1], flush=True)
    return rows


def e4_gamma(gammas, case="C", mu=0.05):
    """One E4 point (`case`, `mu`, realization 0, 500 segments) with the implicit scheme forced on
    the 3D scene whatever the perturbation, at each numerical damping γ in `gammas` (the scheme's
    default step): how γ alone moves a random perturbation's ΔF*."""
    import equinox as eqx

    from jaxrod import perturbations
    from jaxrod.experiments.e4.rod3d import e4_point
    from jaxrod.integrators import SCHEMES, ImplicitLeapfrog

    saved = dict(SCHEMES), {c: c.implicit_3d for c in (perturbations.RandomForce, perturbations.RandomVelocity)}
    rows = []
    try:
        for c in saved[1]:
            c.implicit_3d = True
        for g in gammas:
            class Damped(ImplicitLeapfrog):
                gamma: float = eqx.field(static=True, default=g)

            SCHEMES["implicit"] = Damped
            row = e4_point(case, mu, 0, 500, t1=0.5, width=1.5)
            rows.append(dict(case=f"E4 {case}, mu {mu}, realization 0, 500 segments, implicit forced, gamma {g}: dF* [N]",
                             dt=5e-5, implicit_lo=round(row["lo"], 4), implicit_hi=round(row["hi"], 4),
                             seconds=row["wall_s"], result=row["result"]))
            print(rows[-1], flush=True)
    finally:
        SCHEMES.clear()
        SCHEMES.update(saved[0])
        for c, v in saved[1].items():
            c.implicit_3d = v
    return rows


def _e1_at(v0s, dt):
    from jaxrod.experiments.rod3d import e1_curves

    return e1_curves(0.3, v0s, scheme="implicit", dt=dt)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", nargs="*", choices=["helix", "lockup", "e1", "e4"])
    ap.add_argument("--dt", type=float, nargs="+", default=[5e-5])
    ap.add_argument("--lockup-n", type=int, nargs="+", default=[37], choices=sorted(LOCKUP_EXPLICIT),
                    help="the lock-up scene's segment counts (default 37)")
    ap.add_argument("--e4-gammas", type=float, nargs="+", help="only: E4 C at mu 0.05 with the implicit scheme "
                    "forced, at each of these gamma")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rows = []
    if args.e4_gammas:
        rows = [{"commit": commit, **r} for r in e4_gamma(args.e4_gammas)]
    lockups = lambda dt: [lockup(dt, n) for n in args.lockup_n]
    for name, f in (("helix", helix), ("lockup", lockups), ("e1", e1), ("e4", e4)):
        if args.e4_gammas:
            break
        if args.only and name not in args.only:
            continue
        for dt in args.dt:
            out = f(dt)
            for r in out if isinstance(out, list) else [out]:
                rows.append({"commit": commit, **r})
                print(rows[-1], flush=True)
    if os.path.exists(OUT):  # rows of other cases and steps are kept; a rerun replaces its own
        with open(OUT, newline="") as fh:
            done = {(r["case"], float(r["dt"])) for r in rows}
            rows = [r for r in csv.DictReader(fh) if (r["case"], float(r["dt"])) not in done] + rows
    write_csv(OUT, rows)


if __name__ == "__main__":
    main()
