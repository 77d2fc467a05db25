"""Time to first answer: what a user waits for, from pressing enter to the answer, in a fresh
process — cold (empty compilation cache) and warm (the same command again) — split into
import, tracing, XLA compilation and the rest (the run, and Python around it).

    python benchmarks/first_answer.py [--ref REV ...] [--only NAME ...] [--out DIR]
                                      [--variant 'LABEL:KEY=VALUE,...' ...]

Each case runs as its own process with `JAX_LOG_COMPILES=1`: tracing and compilation are the
sums of JAX's "Finished tracing" / "Finished jaxpr to MLIR" and "Finished XLA compilation"
log lines (a compilation served from the persistent cache is logged too, at the time its
read took); import is `python -c "import jaxrod"` timed the same way. A reference revision
(`--ref`) runs from a git worktree with the same virtual environment (PYTHONPATH first), its
commands through `python -m jaxrod`; revisions without jaxrod's persistent cache have none, so
their warm call compiles again. Writes `first_answer.csv` and `first_answer.md` (commit, date,
machine) under `--out`. Run it on a quiet machine: the figures are wall-clock times.
"""

from __future__ import annotations

import argparse
import csv
import datetime
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "benchmarks", "results", "first_answer")

README_EXAMPLE = """
import jax
jax.config.update("jax_enable_x64", True)
import jaxrod as jr

rod = jr.RodChannel.reference(mu=0.3)
mode = jr.SingleMode.from_rod(rod, dF=5.0)
v_cr = jr.theory.velocity_intercept(mode.k, mode.f_d)
print(f"critical lateral speed: {1e3 * rod.R * v_cr:.2f} mm/s")
for scale in (0.99, 1.01):
    sol = jr.simulate(mode, jr.ProjectedVerlet(dt=1e-5), 0.0, scale * v_cr, t1=0.1)
    print(scale, "stuck" if sol.stuck[-1] else "buckling", float(sol.q[-1]))
"""

# what a user types: (name, kind, argv or code); "cli" runs `jaxrod ARGS` (`OUT` in ARGS becomes a
# fresh folder), "python" runs `python -c CODE`, "notebook" the code cells of a notebook up to
# and including the first that draws a figure
CASES = [
    ("import jax", "python", "import jax"),
    ("import jaxrod", "python", "import jaxrod"),
    ("jaxrod --help", "cli", ["--help"]),
    ("simulate rod3d, 1 s", "cli", ["simulate", "--model", "rod3d", "--control", "load", "--mu", "0.3", "--dF", "5",
                                    "--amplitude", "0.005", "--t1", "1.0", "--json"]),
    ("map --mu 0.3", "cli", ["map", "--mu", "0.3", "--out", "OUT"]),
    ("boundary --dF 1:20:3", "cli", ["boundary", "--mu", "0.3", "--dF", "1:20:3", "--json"]),
    ("critical-load --mu 0.1:0.4:3", "cli", ["critical-load", "--mu", "0.1:0.4:3", "--amplitude", "0.015", "--json"]),
    ("README example", "python", README_EXAMPLE),
    ("notebook 01, first figure", "notebook", "notebooks/01_quick_start.ipynb"),
]

# issue [first-answer]'s targets on the 2-core CPU, cold / warm [s] ("import jaxrod": at most 0.5 s
# more than "import jax")
TARGETS = {"simulate rod3d, 1 s": "≤ 15 / ≤ 8", "map --mu 0.3": "≤ 10 / ≤ 4", "import jaxrod": "import jax + 0.5"}

_TRACE = re.compile(r"Finished (?:tracing|jaxpr to MLIR module conversion)\b.* in ([0-9.e+-]+) sec")
_COMPILE = re.compile(r"Finished XLA compilation of .* in ([0-9.e+-]+) sec")


def _notebook_code(path: str) -> str:
    import json

    cells = json.load(open(path))["cells"]
    code = []
    for c in cells:
        if c["cell_type"] != "code":
            continue
        src = "".join(c["source"])
        src = "\n".join(line for line in src.splitlines() if not line.startswith("%"))
        code.append(src)
        if "plot_simulation" in src or "plt.show" in src or re.search(r"^fig\s*$", src, re.M):
            break
    return "import matplotlib\nmatplotlib.use('Agg')\n" + "\n".join(code)


def _run(case, src: str, cache: str, env_base: dict, variant: dict | None = None) -> dict:
    name, kind, what = case
    env = {**env_base, "JAX_LOG_COMPILES": "1", "JAXROD_CACHE_DIR": cache, "MPLBACKEND": "Agg", **(variant or {})}
    out = tempfile.mkdtemp(prefix="jaxrod-first-")
    if kind == "cli":
        cmd = [sys.executable, "-m", "jaxrod", *[out if a == "OUT" else a for a in what]]
    elif kind == "python":
        cmd = [sys.executable, "-c", what]
    else:
        cmd = [sys.executable, "-c", _notebook_code(os.path.join(src, what))]
    t0 = time.perf_counter()
    res = subprocess.run(cmd, env=env, cwd=out, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    shutil.rmtree(out, ignore_errors=True)
    trace = sum(float(x) for x in _TRACE.findall(res.stderr))
    comp = sum(float(x) for x in _COMPILE.findall(res.stderr))
    return {"wall": wall, "trace": trace, "compile": comp, "rc": res.returncode,
            "tail": (res.stderr.strip().splitlines() or [""])[-1][:200]}


def _revision(rev: str) -> tuple[str, str]:
    """(source folder, short commit) of `rev`: the checkout itself for HEAD's working tree."""
    if rev == "WORKTREE":
        sha = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                             text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "jaxrod"], cwd=ROOT, capture_output=True,
                               text=True).stdout.strip()
        return ROOT, sha + ("+changes" if dirty else "")
    sha = subprocess.run(["git", "rev-parse", "--short", rev], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    path = os.path.join(tempfile.gettempdir(), f"jaxrod-ref-{sha}")
    if not os.path.exists(path):
        subprocess.run(["git", "worktree", "add", "--detach", path, sha], cwd=ROOT, check=True,
                       capture_output=True)
    return path, sha


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", nargs="*", default=[], help="reference revisions, run side by side")
    p.add_argument("--only", nargs="*", default=None, help="case names to run (default: all)")
    p.add_argument("--out", default=OUT, help="folder for first_answer.csv and .md")
    p.add_argument("--variant", nargs="*", default=[], metavar="LABEL:KEY=VALUE[,KEY=VALUE]",
                   help="this revision again with these environment variables (e.g. 'no cache:JAXROD_CACHE_DIR=off')")
    a = p.parse_args(argv)
    cases = [c for c in CASES if a.only is None or c[0] in a.only]
    variants = []
    for spec in a.variant:
        label, _, pairs = spec.partition(":")
        variants.append((label, dict(kv.split("=", 1) for kv in pairs.split(",") if kv)))
    rows = []
    for rev, label, variant in [("WORKTREE", None, None), *[("WORKTREE", lb, v) for lb, v in variants],
                                *[(r, None, None) for r in a.ref]]:
        src, sha = _revision(rev)
        sha = sha if label is None else f"{sha} ({label})"
        env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "JAXROD_", "XLA_"))}
        env["PYTHONPATH"] = src
        for case in cases:
            cache = tempfile.mkdtemp(prefix="jaxrod-cache-")
            for state in ("cold", "warm"):
                r = _run(case, src, cache, env, variant)
                rows.append({"commit": sha, "case": case[0], "state": state, **{k: r[k] for k in ("wall", "trace", "compile")},
                             "rest": r["wall"] - r["trace"] - r["compile"], "rc": r["rc"]})
                print(f"{sha:>16} {case[0]:<30} {state}: {r['wall']:6.1f} s (trace {r['trace']:5.1f}, compile "
                      f"{r['compile']:5.1f}){'' if r['rc'] == 0 else '  EXIT ' + str(r['rc']) + ': ' + r['tail']}",
                      flush=True)
            shutil.rmtree(cache, ignore_errors=True)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "first_answer.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.2f}" if isinstance(v, float) else v) for k, v in r.items()})
    head = rows[0]["commit"]
    revs = list(dict.fromkeys(r["commit"] for r in rows))
    lines = [f"# Time to first answer ({head}, {datetime.date.today()}, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores)", "",
             "Wall time of a fresh process [s], cold (empty compilation cache) / warm (second call); "
             "in brackets for this revision: tracing + compilation. Floor: this revision's warm call "
             "without its tracing and compilation (import, the run, Python around it).", "",
             "| case | " + " | ".join(revs) + " | target | floor |", "|---|" + "---|" * (len(revs) + 2)]
    for case in dict.fromkeys(r["case"] for r in rows):
        cells = []
        for rev in revs:
            c = {r["state"]: r for r in rows if r["case"] == case and r["commit"] == rev}
            if not c:
                cells.append("—")
                continue
            cell = f"{c['cold']['wall']:.1f} / {c['warm']['wall']:.1f}"
            if rev == head:
                cell += (f" ({c['cold']['trace']:.1f} + {c['cold']['compile']:.1f} / "
                         f"{c['warm']['trace']:.1f} + {c['warm']['compile']:.1f})")
            if c["cold"]["rc"] or c["warm"]["rc"]:
                cell += " failed"
            cells.append(cell)
        w = next(r for r in rows if r["case"] == case and r["commit"] == head and r["state"] == "warm")
        lines.append(f"| {case} | " + " | ".join(cells) + f" | {TARGETS.get(case, '—')} | {w['rest']:.1f} |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "first_answer.md"), "w") as fh:
        fh.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
