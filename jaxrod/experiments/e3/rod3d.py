"""E3 with the full model: the stable-zone boundary v₀*(ΔF) of the 3D rod and its exponent.

The field model's map (`experiments.e3`) fits v₀ ∝ ΔF^p to a grid of 20 × 24 runs. The 3D rod
costs orders of magnitude more per run (benchmarks/README.md), so its boundary is found point by point: at each load, label
bisection in v₀ on the common engine's scene ([`jaxrod.scene.Scene`][] `kind="rod3d"`: dead
load F⁰₆ + ΔF, friction at the contact point, sine mode-6 lateral velocity, buckled when
max|θ| passes 0.5 rad, a run stops when it buckles or sticks; the same run built directly so
that friction can be placed at the centre line too), one compiled run reused by every load and
amplitude. The first bracket is ±`width` around the field model's v₀* at that load —
only a starting guess: every bracket is checked by two 3D runs and widened until it holds the
boundary. Each load's search depends on nothing but its load, so loads can be split between
processes that share the runs file.

Every run is appended to a CSV as it finishes (`runs.csv`): a search that is stopped and
restarted replays its finished runs from that file and loses nothing.
"""

from __future__ import annotations

import csv
import math
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from ... import theory
from ...params import RodChannel
from ...perturbations import SineVelocity
from ...scene import Scene
from ...output import write_csv
from ...stability_map import fit_power_law
from ..paper3d import PAPER_E3_EXPONENT, _settings

__all__ = ["boundary_3d", "label_3d", "plot_boundary_3d", "RUN_COLUMNS", "e3", "write_boundary"]

DT_RTOL = 1e-3
RUN_COLUMNS = ["dF", "n_segments", "mu", "friction_at", "ends", "sink", "t1", "dt", "scheme", "v0", "buckled", "seconds"]
SINK = 1e-3  # the 3D rod's default contact: it sinks 1e-3·R into the wall under its weight


def label_3d(rod, n, dt, t1, friction_at="surface", ends="pinned", sink=SINK, scheme="implicit"):
    """The jitted label (ΔF [N], v₀ [m/s]) → 1.0 buckled, 0.0 not, NaN for a failed run
    ([`jaxrod.boundary.run_label`][]) of the 3D rod of `n` segments under the
    dead load F⁰₆ + ΔF with a sine mode-6 lateral velocity v₀: the run of
    [`jaxrod.boundary.crossing_state`][] (stops when it buckles or sticks, at most `t1` [s],
    step `dt` [s]) — with the defaults the same run as the scene `Scene(kind="rod3d")`, with
    `friction_at` and `ends` passed to [`jaxrod.rod3d.Rod3D`][], the wall's Hertz constant set so
    that the rod sinks `sink`·R into it under its weight (`Rod3D`'s default: 1e-3), `scheme`
    `"implicit"` ([`jaxrod.ImplicitLeapfrog`][], the 3D rod's default), `"leapfrog"`
    ([`jaxrod.ProjectedLeapfrog`][]) or `"verlet"` ([`jaxrod.ProjectedVerlet`][])."""
    from ...boundary import run_label
    from ...integrators import SCHEMES
    from ...integrators.base import RunOptions
    from ...rod3d import Rod3D
    from ...simulate import simulate

    if scheme not in SCHEMES:
        raise ValueError(f"scheme = {scheme!r} is invalid: expected one of {tuple(SCHEMES)}.")
    integrator = SCHEMES[scheme](dt)

    @jax.jit
    def buckled(dF, v0):
        model = Rod3D(rod, n, control="load", end_load=theory.reference_load(rod) + dF, friction_at=friction_at,
                      ends=ends, contact_stiffness=rod.w / (sink * rod.R) ** 1.5)
        q0, v0 = SineVelocity(v0).initial_state(model, integrator)
        opts = RunOptions(buckle_threshold=0.5, save_state=False)  # the dead load's threshold
        return run_label(simulate(model, integrator, q0, v0, t1, n_save=201, options=opts, throw=False))

    return buckled


def _runs_of(path, n, mu, t1, dt, friction_at, ends, sink, scheme):
    """Finished runs {(ΔF, v₀): buckled} of the same settings from the CSV at `path` (a step
    within `DT_RTOL` of `dt` counts as the same: a call takes the smallest step of its loads,
    and the step limit moves by ~1e-5 relative between loads; a row without a scheme was run
    with projected Verlet, the only scheme before `scheme` was recorded)."""
    done = {}
    if path and os.path.exists(path):
        with open(path) as fh:
            for r in csv.DictReader(fh):
                same = (int(r["n_segments"]) == n and math.isclose(float(r["mu"]), mu)
                        and r["friction_at"] == friction_at and r["ends"] == ends
                        and math.isclose(float(r["sink"]), sink)
                        and math.isclose(float(r["t1"]), t1) and math.isclose(float(r["dt"]), dt, rel_tol=DT_RTOL)
                        and (r.get("scheme") or "verlet") == scheme)
                if same and r["buckled"] != "":  # a failed run (no label) is run again
                    done[(float(r["dF"]), float(r["v0"]))] = r["buckled"] == "1"
    return done


def _append(path, row):
    if not path:
        return
    new = not os.path.exists(path)
    if not new:  # a file of older columns (no scheme: projected Verlet) gets today's, once
        with open(path, newline="") as fh:
            old = list(csv.DictReader(fh))
            header = list(old[0].keys()) if old else RUN_COLUMNS
        if header != RUN_COLUMNS:
            with open(path, "w", newline="") as fh:
                w = csv.DictWriter(fh, RUN_COLUMNS)
                w.writeheader()
                w.writerows({**{"scheme": "verlet"}, **{k: v for k, v in r.items() if v is not None}} for r in old)
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "a", newline="") as fh:
        w = csv.DictWriter(fh, RUN_COLUMNS)
        if new:
            w.writeheader()
        w.writerow(row)


def _bisect(label, guess, width, rtol, max_runs):
    """The boundary of a label monotone in v₀ (False below, True above; None for a failed run,
    which ends the search) from a first bracket
    guess·(1 ∓ width): widened geometrically (×(1 + 2·width) per try, doubling) until its ends
    differ, then bisected geometrically until hi/lo − 1 ≤ `rtol`.

    **Returns:** `(lo, hi)` (largest stable, smallest buckled amplitude tested) or `None` when
    `max_runs` labels did not bracket it, every amplitude down to guess·1e-6 buckled (up to
    guess·1e6 held), or a run failed."""
    lo, hi = guess * (1 - width), guess * (1 + width)
    b_lo, b_hi = label(lo), label(hi)
    runs, step = 2, 1 + 2 * width
    floor, ceiling = guess * 1e-6, guess * 1e6  # the doubling step would otherwise reach 0 or ∞
    while b_lo == b_hi or b_lo is None or b_hi is None:
        if b_lo is None or b_hi is None:
            return None
        if runs >= max_runs or (b_lo and lo <= floor) or (not b_hi and hi >= ceiling):
            return None
        if b_lo:  # both buckled: the boundary lies below
            hi, lo = lo, max(lo / step, floor)
            b_lo = label(lo)
        else:
            lo, hi = hi, min(hi * step, ceiling)
            b_hi = label(hi)
        runs += 1
        step *= step
    while hi / lo - 1 > rtol and runs < max_runs:
        mid = math.sqrt(lo * hi)
        b = label(mid)
        if b is None:
            return None
        if b:
            hi = mid
        else:
            lo = mid
        runs += 1
    return lo, hi


def boundary_3d(dFs, *, n=120, mu=0.3, t1=0.4, rtol=0.01, width=0.04, max_runs=16, runs_csv=None,
                friction_at="surface", ends="pinned", sink=SINK, scheme="implicit", dt=None, progress=True):
    """v₀*(ΔF) [m/s] of the 3D rod of `n` segments at each load `dFs` [N] above F⁰₆ (label
    bisection to `rtol` relative bracket width), next to the field model's converged boundary
    search, and the power laws v₀* ∝ ΔF^p fitted to each.

    **Arguments:** `t1` the horizon [s] (a run that neither sticks nor buckles by then is
    stable), `width` the half-width of the first bracket (relative), `max_runs` per load,
    `runs_csv` the file every finished run is appended to and replayed from, `friction_at` and
    `ends` passed to [`jaxrod.rod3d.Rod3D`][], `sink` the wall's compliance, `scheme` the
    integrator (see `label_3d`) and `dt` its step [s] (default: the scheme's,
    `jaxrod.integrators.default_step`: `jaxrod.rod3d.IMPLICIT_DT` for the implicit leapfrog, half
    the explicit limit for the explicit ones).

    **Returns:** dict with `points` (per load: `dF`, `field`, `rod3d`, `bracket`, `runs`,
    `seconds`), `exponent_rod3d` ± `exponent_rod3d_stderr`, `exponent_field` ± its stderr (the
    same loads), `exponent_theory` (−0.5) and the settings.
    """
    from ...boundary import critical_velocity

    rod = RodChannel.reference(mu)
    dFs = np.sort(np.asarray(dFs, float))
    # one step for every load (the step limit barely moves with the load): one compiled run
    if dt is None:
        from ...integrators import default_step

        dt = min(default_step(Scene(rod, float(dF), SineVelocity(1e-3), kind="rod3d", n=n).model(), scheme=scheme)
                 for dF in dFs)

    buckled = label_3d(rod, n, dt, t1, friction_at, ends, sink, scheme)
    done = _runs_of(runs_csv, n, mu, t1, dt, friction_at, ends, sink, scheme)
    points = []
    for dF in dFs:
        t0 = time.perf_counter()
        r, _ = critical_velocity(rod, dF, model="field", rtol=1e-4, sensitivities=())
        v_field = float(r.root)
        count = [0, 0.0]

        def label(v0, dF=float(dF)):
            key = (dF, float(v0))
            if key not in done:
                t = time.perf_counter()
                b = float(buckled(jnp.asarray(dF), jnp.asarray(v0)))
                done[key] = None if math.isnan(b) else bool(b)
                sec = time.perf_counter() - t
                count[1] += sec
                _append(runs_csv, dict(dF=dF, n_segments=n, mu=mu, friction_at=friction_at, ends=ends, sink=sink, t1=t1,
                                       dt=dt, scheme=scheme, v0=float(v0),
                                       buckled="" if done[key] is None else int(done[key]), seconds=round(sec, 2)))
                if progress:
                    verdict = "failed" if done[key] is None else "buckled" if done[key] else "stable"
                    print(f"  ΔF = {dF:g} N, v0 = {1e3 * v0:.3f} mm/s: {verdict}"
                          f" ({sec:.0f} s)", flush=True)
            count[0] += 1
            return done[key]

        br = _bisect(label, v_field, width, rtol, max_runs)
        v3 = math.sqrt(br[0] * br[1]) if br else math.nan
        points.append(dict(dF=float(dF), field=v_field, rod3d=v3, bracket=list(br) if br else None,
                           runs=count[0], seconds_new_runs=round(count[1], 1),
                           seconds=round(time.perf_counter() - t0, 1)))
        if progress:
            print(f"ΔF = {dF:g} N: 3D {1e3 * v3:.3f} mm/s, field {1e3 * v_field:.3f} mm/s "
                  f"({100 * (v3 / v_field - 1):+.1f} %)", flush=True)
    ok = [p for p in points if p["bracket"]]
    p3, se3, c3 = fit_power_law([p["dF"] for p in ok], [p["rod3d"] for p in ok])
    pf, sef, cf = fit_power_law([p["dF"] for p in points], [p["field"] for p in points])
    return dict(points=points, exponent_rod3d=p3, exponent_rod3d_stderr=se3, prefactor_rod3d=c3,
                exponent_field=pf, exponent_field_stderr=sef, prefactor_field=cf, exponent_theory=-0.5,
                n_segments=n, mu=mu, friction_at=friction_at, ends=ends, sink=sink, scheme=scheme, t1=t1, dt=dt, rtol=rtol, F0=float(theory.reference_load(rod)))


def plot_boundary_3d(res, path=None):
    """The 3D and field boundaries with their fitted power laws (log–log); returns the Figure."""
    from ...output import subplots

    fig, ax = subplots(figsize=(5.5, 4.2))
    pts = res["points"]
    dF = np.array([p["dF"] for p in pts])
    fine = np.geomspace(dF.min(), dF.max(), 50)
    ax.loglog(dF, [1e3 * p["field"] for p in pts], "s", mfc="none", label="field model (boundary search)")
    ax.loglog(fine, 1e3 * res["prefactor_field"] * fine ** res["exponent_field"], "C0-", lw=0.8,
              label=f"fit: ΔF^({res['exponent_field']:.3f} ± {res['exponent_field_stderr']:.3f})")
    ok = [p for p in pts if p["bracket"]]
    ax.errorbar([p["dF"] for p in ok], [1e3 * p["rod3d"] for p in ok],
                yerr=np.array([[1e3 * (p["rod3d"] - p["bracket"][0]), 1e3 * (p["bracket"][1] - p["rod3d"])] for p in ok]).T,
                fmt="o", color="C3", ms=4, label=f"3D rod, {res['n_segments']} segments (bracket)")
    ax.loglog(fine, 1e3 * res["prefactor_rod3d"] * fine ** res["exponent_rod3d"], "C3--", lw=0.8,
              label=f"fit: ΔF^({res['exponent_rod3d']:.3f} ± {res['exponent_rod3d_stderr']:.3f})")
    ax.set_xlabel("ΔF = F − F⁰₆ [N]")
    ax.set_ylabel("critical sine velocity v₀* [mm/s]")
    ax.set_title(f"E3 boundary, μ = {res['mu']}: 3D rod against the field model", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    if path:
        fig.savefig(path, dpi=130)
    return fig


def write_boundary(res: dict, stem: str) -> None:
    """`boundary_3d`'s result as `stem.json` (all of it), `stem.csv` (one row per load,
    plain numbers) and `stem.png`."""
    import json

    with open(stem + ".json", "w") as fh:
        json.dump(res, fh, indent=1)
    write_csv(stem + ".csv", [dict(dF=p["dF"], n_segments=res["n_segments"], mu=res["mu"], t1=res["t1"], dt=res["dt"],
                                   field_mm_s=1e3 * p["field"], rod3d_mm_s=1e3 * p["rod3d"],
                                   bracket_lo_mm_s=1e3 * p["bracket"][0] if p["bracket"] else math.nan,
                                   bracket_hi_mm_s=1e3 * p["bracket"][1] if p["bracket"] else math.nan,
                                   difference_percent=100 * (p["rod3d"] / p["field"] - 1), runs=p["runs"])
                              for p in res["points"]])
    plot_boundary_3d(res, stem + ".png")


def e3(out, quick=False, progress=True, n=None) -> dict:
    """E3's boundary of the 3D rod at `n` segments (default: the setting's): writes
    `rod3d_boundary_n{n}_{scheme}.{json,csv,png}` (the 3D rod's default scheme: `implicit`) and
    the runs file under `out`."""
    s = _settings(quick, n)
    res = boundary_3d(s["loads"], n=s["n"], rtol=s["rtol"], t1=s["t1_e3"],
                      runs_csv=os.path.join(out, "rod3d_runs.csv"), progress=progress)
    write_boundary(res, os.path.join(out, f"rod3d_boundary_n{s['n']}_{res['scheme']}"))
    return dict(n=s["n"], loads=list(s["loads"]), exponent_rod3d=res["exponent_rod3d"],
                exponent_rod3d_stderr=res["exponent_rod3d_stderr"], exponent_field=res["exponent_field"],
                exponent_field_stderr=res["exponent_field_stderr"], exponent_paper=PAPER_E3_EXPONENT,
                runs=[p["runs"] for p in res["points"]], converged=sum(p["bracket"] is not None for p in res["points"]))
