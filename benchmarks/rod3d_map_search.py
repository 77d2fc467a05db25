"""The 3D E3 stability map as a user runs it: `jaxrod map --model rod3d --n 500` (its default grid,
20 × 24 at μ = 0.3 and 0, columns searched by bisection: `jaxrod.map_columns`) end to end in a
fresh process with an empty compilation cache (cold), and its labels against the committed map
that ran every cell (`results/paper/e3/map_rod3d_n500.csv`).

    python benchmarks/rod3d_map_search.py [--n 500] [--out DIR]

Writes the map under `results/paper/e3/map_rod3d_n500_search/` and `rod3d_map_search.json`
(commit, date, machine, wall, runs, label agreement) under `--out` (default benchmarks/results/).
Run it alone on a quiet machine: the figure is a wall-clock time. The map's sweep folders left by an
earlier run are deleted first (a sweep resumes from its folder: the command would not run again).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import glob
import json
import os
import platform
import shutil
import tempfile

from _common import commit, jaxrod_command  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FULL = os.path.join(ROOT, "results", "paper", "e3", "map_rod3d_n500.csv")



def _labels(path):
    with open(path) as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    return {(round(float(r["mu"]), 6), round(float(r["dF"]), 9), round(float(r["v0"]), 12)): r for r in rows}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=500)
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results"))
    a = ap.parse_args()
    folder = os.path.join(ROOT, "results", "paper", "e3", f"map_rod3d_n{a.n}_search")
    at = commit()  # before the run: it rewrites the committed map's files
    argv = ["map", "--model", "rod3d", "--n", str(a.n), "--out", folder]
    for old in glob.glob(os.path.join(folder, "sweep_*")):
        shutil.rmtree(old)
    with tempfile.TemporaryDirectory() as cache:
        wall, stdout = jaxrod_command(argv, cache, ROOT)
    with open(os.path.join(folder, "map.log"), "w") as fh:
        fh.write(f"$ jaxrod {' '.join(argv)}\n{stdout}")
    summary = json.load(open(os.path.join(folder, "map.json")))
    found = _labels(os.path.join(folder, "map.csv"))
    record = dict(command="jaxrod " + " ".join(argv), commit=at, date=datetime.date.today().isoformat(),
                  machine=f"{platform.machine()}, {os.cpu_count()} cores", cold_wall_s=wall,
                  runs=summary["fill"]["runs"], cells=summary["fill"]["cells"],
                  exponent={k: (m["exponent"], m["exponent_stderr"]) for k, m in summary["maps"].items()})
    if a.n == 500 and os.path.exists(FULL):
        full = _labels(FULL)
        same = [k for k in found if k in full and found[k]["buckled"] == full[k]["buckled"]]
        ran = [k for k in found if found[k]["ran"] == "1"]
        record.update(compared_with=os.path.relpath(FULL, ROOT), cells_compared=len([k for k in found if k in full]),
                      same_labels=len(same), ran_same=len([k for k in ran if k in same]), ran=len(ran))
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "rod3d_map_search.json"), "w") as fh:
        json.dump(record, fh, indent=1)
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
