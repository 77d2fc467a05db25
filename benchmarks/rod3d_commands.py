"""The 3D rod's boundary search as a user runs it: `jaxrod boundary --model rod3d` end to end in a
fresh process, cold (an empty compilation cache) and warm (the same command again), its roots
against the explicit scheme's committed brackets, and the search's horizon checked: the stable
end of each 0.4-s bracket run again to 2 s.

    python benchmarks/rod3d_commands.py [--n 500] [--dF 5,20] [--out DIR]

Writes `rod3d_commands.csv` (one row per load and call) and `rod3d_commands.md` (commit, date,
machine) under `--out` (default benchmarks/results/). Run it on a quiet machine: the figures are
wall-clock times.
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import platform
import tempfile
import time

from _common import commit, jaxrod_command  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXPLICIT = os.path.join(ROOT, "results", "paper", "e3", "rod3d_boundary_n500_leapfrog.csv")



def _command(argv, cache):
    """`jaxrod ARGV` in a fresh process with the compilation cache folder `cache`: (seconds, JSON)."""
    seconds, out = jaxrod_command(argv, cache, ROOT)
    return seconds, json.loads(out.strip().splitlines()[-1])


def _explicit(n):
    rows = {}
    if n != 500 or not os.path.exists(EXPLICIT):
        return rows
    with open(EXPLICIT) as f:
        for r in csv.DictReader(f):
            rows[float(r["dF"])] = (float(r["bracket_lo_mm_s"]), float(r["bracket_hi_mm_s"]))
    return rows


def _horizon_check(n, dFs, rtol):
    """The 0.4-s brackets in this process, and the label of each bracket end at a 2-s horizon."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jaxrod as jr
    from jaxrod import boundary as bd
    from jaxrod.boundary.search import _scene

    rod = jr.RodChannel.reference(mu=0.3)
    res, _ = bd.boundary_curve(rod, dFs, model="rod3d", n=n, bracket=(1e-5, 2.0), rtol=rtol, sensitivities=())
    probe = jr.scene.Scene(rod, max(dFs), kind="rod3d", n=n)
    dt = probe.step()
    out = []
    for i, dF in enumerate(dFs):
        labels = {}
        for end in ("lo", "hi"):
            v0 = float(getattr(res, end)[i])
            t = time.perf_counter()
            label = float(bd.crossing_state(_scene(rod, dF, v0, "rod3d", n, 6, dt, "sine", jax.random.key(0)), 2.0)[1])
            labels[end] = (v0, label, time.perf_counter() - t)
        out.append(labels)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=500)
    ap.add_argument("--dF", default="5,20")
    ap.add_argument("--rtol", type=float, default=1e-2)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results"))
    args = ap.parse_args()
    dFs = [float(x) for x in args.dF.split(",")]
    argv = ["boundary", "--mu", "0.3", "--dF", args.dF, "--model", "rod3d", "--n", str(args.n), "--rtol",
            str(args.rtol), "--json"]
    explicit = _explicit(args.n)
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        for call in ("cold", "warm"):
            seconds, answer = _command(argv, cache)
            print(f"jaxrod {' '.join(argv)}: {call} {seconds:.1f} s", flush=True)
            for a in answer:
                ref = explicit.get(a["dF"])
                mid = None if ref is None else 0.5 * (ref[0] + ref[1])
                v = None if a["v0_star"] is None else 1e3 * a["v0_star"]
                rows.append(dict(call=call, seconds=round(seconds, 1), dF=a["dF"], v0_star_mm_s=v,
                                 evaluations=a["evaluations"], result=a["result"],
                                 explicit_lo_mm_s=None if ref is None else ref[0],
                                 explicit_hi_mm_s=None if ref is None else ref[1],
                                 difference_percent=None if (v is None or mid is None) else round(100 * (v / mid - 1), 3)))
                print(f"  dF = {a['dF']:g} N: {v} mm/s ({a['evaluations']} runs); explicit {ref}", flush=True)
    checks = _horizon_check(args.n, dFs, args.rtol)
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "rod3d_commands.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    stamp = (f"commit {commit()}, {datetime.date.today().isoformat()}, {platform.machine()} "
             f"{os.cpu_count()} cores, Python {platform.python_version()}")
    lines = [f"# `jaxrod {' '.join(argv)}`", "", stamp, "",
             "| call | wall [s] | ΔF [N] | v₀* [mm/s] | runs | explicit bracket [mm/s] | difference |",
             "|---|---:|---:|---:|---:|---|---:|"]
    for r in rows:
        lines.append(f"| {r['call']} | {r['seconds']} | {r['dF']:g} | {r['v0_star_mm_s']:.4f} | {r['evaluations']} | "
                     f"{r['explicit_lo_mm_s']}–{r['explicit_hi_mm_s']} | {r['difference_percent']:+.2f} % |")
    lines += ["", "Horizon: the ends of each bracket found with the 0.4-s horizon, labelled again at 2 s "
              "(1 buckled, 0 stable):", "", "| ΔF [N] | end | v₀ [mm/s] | label at 2 s | wall [s] |",
              "|---:|---|---:|---:|---:|"]
    for dF, c in zip(dFs, checks):
        for end, (v0, label, sec) in c.items():
            lines.append(f"| {dF:g} | {end} | {1e3 * v0:.4f} | {label:g} | {sec:.1f} |")
            print(f"  dF = {dF:g} N, {end} = {1e3 * v0:.4f} mm/s: label at 2 s = {label:g}", flush=True)
    with open(os.path.join(args.out, "rod3d_commands.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {path} and rod3d_commands.md")


if __name__ == "__main__":
    main()
