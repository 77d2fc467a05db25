"""The lock-up curve read by interpolation instead of by brackets: for every staircase run in
`results/lockup/stages.csv`, the parameter (far load [F₀], or μL/ℓ for the lock-up lane) at which
the steady entry force crosses the bound f_c = 6 F₀, linearly between the last steady stage at or
below f_c and the first steady stage above it (adjacent stages are 2.7–12 % apart in the
parameter). Then the same convergence tests as `jaxrod.experiments.lockup_convergence` on these
crossings: v/2 against v/4 within 1 %, n against 2n (2n against 4n where run) within 2 %. Writes
crossings.csv in results/lockup/.

    python studies/lockup/crossings.py   # a second
"""

import collections
import csv
import os

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
F_C = 6.0


def crossing(stages):
    """The parameter where the steady entry force crosses F_C, or None without steady stages on both sides."""
    pts = sorted((float(r["parameter"]), float(r["f_in"])) for r in stages if r["status"] == "sliding")
    below, above = [p for p in pts if p[1] <= F_C], [p for p in pts if p[1] > F_C]
    if not below or not above:
        return None
    (x0, f0), (x1, f1) = below[-1], above[0]
    return x0 + (F_C - f0) * (x1 - x0) / (f1 - f0)


def main():
    groups = collections.defaultdict(list)
    for r in csv.DictReader(open(os.path.join(HERE, "stages.csv"))):
        groups[("lock" if r["varies"] == "mu" else float(r["muL_over_ell"]), int(r["n_segments"]), float(r["push_speed"]))].append(r)
    rows = [dict(point=k[0], n_segments=k[1], push_speed=k[2], crossing=crossing(v)) for k, v in groups.items()]
    rows.sort(key=lambda r: (str(r["point"]), r["n_segments"], -r["push_speed"]))
    with open(os.path.join(HERE, "crossings.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for point in sorted({r["point"] for r in rows}, key=str):
        mine = {(r["n_segments"], r["push_speed"]): r["crossing"] for r in rows if r["point"] == point}
        ns = sorted({n for n, _ in mine})
        base_n = ns[0]
        c = {v: mine.get((base_n, v)) for v in (0.01, 0.005, 0.0025)}
        seg = [(n, mine.get((n, 0.01))) for n in ns]
        if None in c.values():
            print(point, "no crossing at every speed:", c)
            continue
        speed = c[0.0025] / c[0.005] - 1
        pair = seg[-2:] if len(seg) >= 2 else seg
        d_seg = pair[-1][1] / pair[0][1] - 1 if len(pair) == 2 and None not in (pair[0][1], pair[1][1]) else float("nan")
        print(f"{point}: v {c[0.01]:.4f}, v/2 {c[0.005]:.4f}, v/4 {c[0.0025]:.4f} (v/4 on v/2 {100 * speed:+.2f} %); "
              f"segments {[(n, round(x, 4) if x else x) for n, x in seg]} (last pair {100 * d_seg:+.2f} %)")


if __name__ == "__main__":
    main()
