"""The lock-up curve's convergence (`jaxrod.experiments.lockup`): from a point's staircase brackets
at the base (n segments, push speed v), at 2n (and at 4n where run) and at v/2 and v/4, its
converged value and error bar, and whether it has converged in segments and in speed.
"""

from __future__ import annotations

import math

__all__ = ["FAR", "LOCK", "SEGMENTS_TOL", "SPEED_TOL", "converged"]

FAR, LOCK = "F_far_max", "muL_lock"
"""The two quantities of `curve.csv`: F_far,max(f_c)/F₀ at a μL/ℓ, and μL_lock(f_c)/ℓ."""
SEGMENTS_TOL, SPEED_TOL = 0.02, 0.01
"""Converged in segments: n against 2n within 2 %; in push speed: v/2 against v/4 within 1 %."""


def _mid(row):
    return 0.5 * (row["lo"] + row["hi"]), 0.5 * (row["hi"] - row["lo"])


def converged(rows, S) -> list:
    """One `kind="converged"` row per point (quantity, μL/ℓ) with runs at the base (n, v), 2n and
    v/2, v/4 (`S["runs"]`), from the bracket midpoints m and half-widths w:

    - in push speed: converged when v/4 and v/2 agree within `SPEED_TOL`; then the value is
      m(v/4) and its speed error |m(v/4) − m(v/2)|; otherwise the value is extrapolated to v → 0,
      linearly through v/2 and v/4 (2 m(v/4) − m(v/2)), its speed error the distance to the
      quadratic extrapolation through v, v/2 and v/4 ((8 m(v/4) − 6 m(v/2) + m(v))/3);
    - the error bar: that speed error, plus the brackets' half-widths as the value carries them
      (w(v/4); extrapolated 2 w(v/4) + w(v/2)), plus the segment error: |m(2n) − m(n)| at v, or,
      where the point also ran at 4n (`S["refine"]`: n against 2n failed), the larger of the
      last refinement's change |m(4n) − m(2n)| and the distance of the value (at n, v → 0) from
      m(2n) (at v, resolved in segments) — an estimate, not a bound, that says whether the
      speed-converged value at n and the segment-converged value at v agree;
      `lo`, `hi` the value ± the bar;
    - `d_segments` (2n against n, or 4n against 2n: `segments_pair`), `d_half_speed` (v/2
      against v), `d_quarter_speed` (v/4 against v/2): relative differences of the midpoints;
      `converged_segments`, `converged_speed`: within `SEGMENTS_TOL`, `SPEED_TOL`.

    A point without the four runs at n, 2n, v/2, v/4 bracketed gets none."""
    w0, v0 = S["runs"][0]
    want = {"base": (w0, v0), "fine": (2 * w0, v0), "half": (w0, v0 / 2), "quarter": (w0, v0 / 4)}
    if any(r not in S["runs"] for r in want.values()):
        return []
    want["finer"] = (4 * w0, v0)  # where run (`S["refine"]`)
    out = []
    points = sorted({(r["quantity"], r["muL_over_ell"]) for r in rows if r["kind"] == "run"},
                    key=lambda k: (k[0], 0.0 if math.isnan(k[1]) else k[1]))
    for quantity, X in points:
        runs = {}
        for name, (w, v) in want.items():
            hit = [r for r in rows if r["kind"] == "run" and r["quantity"] == quantity
                   and (r["muL_over_ell"] == X or (math.isnan(X) and math.isnan(r["muL_over_ell"])))
                   and r["segments_per_wave"] == w and math.isclose(r["push_speed"], v) and r["status"] == "bracketed"]
            if hit:
                runs[name] = hit[0]
        if any(k not in runs for k in ("base", "fine", "half", "quarter")):
            continue
        (mb, _), (mf, _), (mh, wh), (mq, wq) = (_mid(runs[k]) for k in ("base", "fine", "half", "quarter"))
        d_seg, d_half, d_quarter = mf / mb - 1, mh / mb - 1, mq / mh - 1
        pair, seg_err = f"{2 * w0}/{w0}", abs(mf - mb)
        speed_ok = abs(d_quarter) <= SPEED_TOL
        if speed_ok:
            value, speed_err, bracket = mq, abs(mq - mh), wq
        else:
            value = 2 * mq - mh
            speed_err, bracket = abs(value - (8 * mq - 6 * mh + mb) / 3), 2 * wq + wh
        if "finer" in runs:
            mff, _ = _mid(runs["finer"])
            d_seg, pair, seg_err = mff / mf - 1, f"{4 * w0}/{2 * w0}", max(abs(mff - mf), abs(value - mf))
        bar = speed_err + bracket + seg_err
        out.append(dict(runs["base"], kind="converged", push_speed=0.0, lo=value - bar, hi=value + bar,
                        status="converged in speed" if speed_ok else "extrapolated to v = 0", stages=math.nan,
                        quasi_static=value, error_bar=bar, d_segments=d_seg, segments_pair=pair, d_half_speed=d_half,
                        d_quarter_speed=d_quarter, converged_segments=abs(d_seg) <= SEGMENTS_TOL,
                        converged_speed=speed_ok))
    return out
