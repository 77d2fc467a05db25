"""The lock-up curve's convergence (`jaxrod.experiments.lockup`): from a point's staircase runs at
the base (n segments, push speed v), at 2n (and at 4n, or 2n at v/2, where run) and at v/2 and v/4,
read by their crossings of the bound (`jaxrod.lockup.staircase.crossing`), its converged value and
error bar, and whether it has converged in segments and in speed.
"""

from __future__ import annotations

import math

__all__ = ["FAR", "LOCK", "SEGMENTS_TOL", "SPEED_TOL", "converged"]

FAR, LOCK = "F_far_max", "muL_lock"
"""The two quantities of `curve.csv`: F_far,max(f_c)/F₀ at a μL/ℓ, and μL_lock(f_c)/ℓ."""
SEGMENTS_TOL, SPEED_TOL = 0.02, 0.01
"""Converged in segments: n against 2n within 2 %; in push speed: v/2 against v/4 within 1 %."""


def converged(rows, S) -> list:
    """One `kind="converged"` row per point (quantity, μL/ℓ) with runs at the base (n, v), 2n and
    v/2, v/4 (`S["runs"]`), each with its crossing c and interpolation error e (columns `crossing`,
    `crossing_error`; why crossings and not the brackets' midpoints: docs/physics.md §8):

    - in push speed: converged when v/4 and v/2 agree within `SPEED_TOL`; then the value is
      c(v/4), its speed error |c(v/4) − c(v/2)| and its interpolation error e(v/4); otherwise the
      value is extrapolated to v → 0 linearly through v/2 and v/4 (2 c(v/4) − c(v/2)), its speed
      error the distance to the quadratic extrapolation through v, v/2 and v/4
      ((8 c(v/4) − 6 c(v/2) + c(v))/3), its interpolation error 2 e(v/4) + e(v/2);
    - in segments, the pairs run: at v, 2n against n, or 4n against 2n where the point ran at 4n
      (`S["refine"]`); and 2n against n at v/2 where the point ran at 2n there too. Converged when
      each is within `SEGMENTS_TOL`; the segment error is the largest change among them, and where
      the only pair is at v but the point ran at 4n, also the distance of the value (at n, v → 0)
      from c(2n) (at v): an estimate, not a bound. Where the point ran at 2n at v/4 too, that
      pair alone decides (the segments tested at the speed the value is read from; where the
      segments' effect moves with the speed, a faster pair says nothing of the value's): its
      change is the segment error, and the other pairs' largest change is kept as
      `d_segments_faster` (NaN where there is no such pair);
    - the error bar: speed + interpolation + segment errors; `lo`, `hi` the value ± the bar;
      `bracket_lo`, `bracket_hi` the bracket of the run the value is read from (v/4 at n);
    - `d_segments` (the pair named in `segments_pair` with the largest change), `d_half_speed`
      (v/2 against v), `d_quarter_speed` (v/4 against v/2): relative differences of crossings;
      `converged_segments`, `converged_speed`: within `SEGMENTS_TOL`, `SPEED_TOL`;
    - the path band, where `rows` hold runs of other staircase protocols at the base (n, v)
      (`protocol` other than "staircase" and "single_step", with a crossing): `d_path_lo`,
      `d_path_hi`, the smallest and largest of their crossings against the base run's (0 included),
      and `path_protocols`, how many there were.

    A point without a crossing in each of the four runs at n, 2n, v/2, v/4 gets none."""
    w0, v0 = S["runs"][0]
    want = {"base": (w0, v0), "fine": (2 * w0, v0), "half": (w0, v0 / 2), "quarter": (w0, v0 / 4)}
    if any(r not in S["runs"] for r in want.values()):
        return []
    want.update(finer=(4 * w0, v0), fine_half=(2 * w0, v0 / 2), fine_quarter=(2 * w0, v0 / 4))  # where run
    out = []
    points = sorted({(r["quantity"], r["muL_over_ell"]) for r in rows if r["kind"] == "run"},
                    key=lambda k: (k[0], 0.0 if math.isnan(k[1]) else k[1]))

    def same_point(r, quantity, X):
        return r["kind"] == "run" and r["quantity"] == quantity and (
            r["muL_over_ell"] == X or (math.isnan(X) and math.isnan(r["muL_over_ell"])))

    for quantity, X in points:
        runs = {}
        for name, (w, v) in want.items():
            hit = [r for r in rows if same_point(r, quantity, X) and r.get("protocol", "staircase") == "staircase"
                   and r["segments_per_wave"] == w and math.isclose(r["push_speed"], v)
                   and not math.isnan(r.get("crossing", math.nan))]
            if hit:
                runs[name] = hit[0]
        if any(k not in runs for k in want if k not in ("finer", "fine_half", "fine_quarter")):
            continue
        c = {k: r["crossing"] for k, r in runs.items()}
        e = {k: r["crossing_error"] for k, r in runs.items()}
        d_half, d_quarter = c["half"] / c["base"] - 1, c["quarter"] / c["half"] - 1
        speed_ok = abs(d_quarter) <= SPEED_TOL
        if speed_ok:
            value, speed_err, interp = c["quarter"], abs(c["quarter"] - c["half"]), e["quarter"]
        else:
            value = 2 * c["quarter"] - c["half"]
            speed_err = abs(value - (8 * c["quarter"] - 6 * c["half"] + c["base"]) / 3)
            interp = 2 * e["quarter"] + e["half"]
        pairs = [(f"{4 * w0}/{2 * w0}", "finer", "fine") if "finer" in c else (f"{2 * w0}/{w0}", "fine", "base")]
        if "fine_half" in c:
            pairs.append((f"{2 * w0}/{w0} at v/2", "fine_half", "half"))
        changes = [(abs(c[a] / c[b] - 1), c[a] / c[b] - 1, name, abs(c[a] - c[b])) for name, a, b in pairs]
        faster = math.nan
        if "fine_quarter" in c:  # the pair at the value's own speed decides; the faster ones are kept
            faster = max(changes)[1]
            changes = [(abs(c["fine_quarter"] / c["quarter"] - 1), c["fine_quarter"] / c["quarter"] - 1,
                        f"{2 * w0}/{w0} at v/4", abs(c["fine_quarter"] - c["quarter"]))]
        seg_err = max(ch[3] for ch in changes)
        if "finer" in c and "fine_half" not in c and "fine_quarter" not in c:
            seg_err = max(seg_err, abs(value - c["fine"]))
        _, d_seg, pair, _ = max(changes)
        bar = speed_err + interp + seg_err
        q = runs["quarter"]
        others = [r["crossing"] / c["base"] - 1 for r in rows if same_point(r, quantity, X)
                  and r.get("protocol", "staircase") not in ("staircase", "single_step")
                  and r["segments_per_wave"] == w0 and math.isclose(r["push_speed"], v0)
                  and not math.isnan(r.get("crossing", math.nan))]
        out.append(dict(runs["base"], kind="converged", push_speed=0.0, lo=value - bar, hi=value + bar,
                        status="converged in speed" if speed_ok else "extrapolated to v = 0", stages=math.nan,
                        crossing=math.nan, crossing_error=math.nan, bracket_lo=q["lo"], bracket_hi=q["hi"],
                        quasi_static=value, error_bar=bar, d_segments=d_seg, segments_pair=pair,
                        d_segments_faster=faster, d_half_speed=d_half,
                        d_quarter_speed=d_quarter, converged_segments=all(ch[0] <= SEGMENTS_TOL for ch in changes),
                        converged_speed=speed_ok, d_path_lo=min([0.0, *others]), d_path_hi=max([0.0, *others]),
                        path_protocols=len(others)))
    return out
