"""The held-out mutation score of the whole engine (`python tools/mutants.py --held-out N --seed S`).

mutmut mutates every module of `jaxrod/` but those in `EXCLUDED` (and the plotting functions that
`PLOTTING` names), in a copy of the checkout, and its stats run (the default suite, `-m 'not
slow'`, once) maps each function to the tests that called it. A uniform sample of N mutants is
drawn from all of them (`random.Random(seed).sample` over the sorted names) and each is run here,
not by `mutmut run`: `pytest -x` on the tests mapped to its function, with the mutant active
(`MUTANT_UNDER_TEST`, as mutmut's workers set it) and tools/mutants_plugin.py recording the
failing tests and how each failed. Per mutant:

- tests: the mapped tests, fastest first (their call time in the stats run), as many as fit in
  `--budget` seconds of that time (at least one): the cap keeps a mutant of a function that
  hundreds of tests reach (the integrators, the models) to minutes; the tests left out are
  counted in the json (`tests_mapped` against `tests_run`);
- timeout: `--timeout-base` + 3 × the chosen tests' stats time (wall clock; the process group is
  killed); a timed-out mutant counts as not killed, as does one no test reaches ("no tests") and
  one whose pytest crashed (a signal); a mutant that breaks a test module's import (pytest's exit 4,
  "found no collectors", with the collection error recorded) is killed like any failure, its
  killing "test" the module, and the control below runs that module's chosen tests with no mutant;
- a mutant whose first failure is an exception (not an assertion) is run once more on the same
  tests without `-x`: "exception only" when none of them fails on an assertion;
- control: the killing test is run alone with no mutant active (once per test); if it fails
  there too, the mutant is "control failed", not killed.

The copy is of a commit (`--rev`, default HEAD: the headline's commit is exactly the code and
tests run; `--rev ''` copies the working tree and records it as dirty). The mutants run in the
order drawn, so a run stopped early (Ctrl-C) is itself a uniform sample; `--resume` goes on with
the same draw in the same work folder (the same copy of jaxrod/ and tests/), or, where that folder
is gone (another machine), in a new copy of the same commit, mutated and mapped again: the draw
must come out the same, and the json records the rebuild (`rebuilt`). A seed is used once
(heldout.json keeps the seeds used and the earlier headlines): the draw is never rerun after tests
were written against what it showed; a new estimate takes a new seed.
"""

from __future__ import annotations

import io
import concurrent.futures
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tarfile
import tempfile
import time

from mutants_lib import ROOT, commit, diff_key, dirty, sha256, wilson

EXCLUDED = {
    "jaxrod/cli/*": "the command line: argument parsing, the arguments' checks, dispatch to the engine",
    "jaxrod/figures/*": "figures: plot styling, the VTK and animation export of a 3D run",
    "jaxrod/__main__.py": "`python -m jaxrod`: calls the command line",
    "jaxrod/_version.py": "the installed version, read from the package metadata",
}
PLOTTING = re.compile(r"(^|_)plot|_figure$|^subplots$")
"""Functions left out of the population (figure styling in numerical modules): the experiments'
`_plot`, `_plot_e4`, `_plot_e5`, `_figure`, `plot_boundary_3d`, stability_map's `plot_maps`,
output's `subplots`."""
INFRASTRUCTURE = ("jaxrod/_cache.py", "jaxrod/_xla.py", "jaxrod/distributed.py", "jaxrod/output.py",
                  "jaxrod/reproduce.py", "jaxrod/__init__.py")
"""Mutated but not numerical code: left out of the review list of exception-only kills."""


def _function(name: str) -> str:
    f = name.partition("__mutmut_")[0].rpartition(".")[2]
    return f.split("ǁ")[-1] if "ǁ" in f else f[2:]


def module_path(name: str, root: str) -> str:
    mod = name.partition("__mutmut_")[0].rpartition(".")[0].replace(".", "/")
    return mod + ".py" if os.path.exists(os.path.join(root, mod + ".py")) else mod + "/__init__.py"


def _config(work: str) -> str:
    tops = sorted(set(os.listdir(work)) - {"jaxrod", "mutants"})
    return "\n".join([
        "[tool.mutmut]", 'source_paths = ["jaxrod/"]',
        f"do_not_mutate = {json.dumps(sorted(EXCLUDED))}",
        f"also_copy = {json.dumps(tops)}",
        'pytest_add_cli_args = ["-p", "no:xdist", "-p", "no:cacheprovider", "-p", "mutants_plugin"]',
        'pytest_add_cli_args_test_selection = ["tests/"]',
        'process_isolation = "forkserver"', 'forkserver_warmup = "none"', ""])


def _files() -> list[str]:
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout
    return [p for p in out.split("\0") if p and os.path.isfile(os.path.join(ROOT, p))]


def _env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("MUTANT_UNDER_TEST", "PYTEST_ADDOPTS")}
    env["PYTHONPATH"] = os.path.join(ROOT, "tools")
    env.update(extra)
    return env


def prepare(work: str, rev: str | None, clear_jit: bool) -> float:
    """Copy the commit `rev` (None: the working tree) to `work`, make the mutants and mutmut's
    stats there; the seconds taken."""
    t0 = time.time()
    os.makedirs(work)
    if rev:
        tar = subprocess.run(["git", "archive", "--format=tar", rev], cwd=ROOT, capture_output=True, check=True)
        tarfile.open(fileobj=io.BytesIO(tar.stdout)).extractall(work)
    else:
        for p in _files():
            os.makedirs(os.path.dirname(os.path.join(work, p)) or work, exist_ok=True)
            shutil.copy2(os.path.join(ROOT, p), os.path.join(work, p))
    text = open(os.path.join(work, "pyproject.toml")).read()
    text = re.sub(r"\n\[tool\.mutmut\].*?(?=\n\[|\Z)", "\n", text, flags=re.S)
    with open(os.path.join(work, "pyproject.toml"), "w") as f:
        f.write(text + "\n" + _config(work))
    cache = os.path.join(ROOT, ".pytest_cache", "jax")  # compiled programs of the unmutated code
    if os.path.isdir(cache):
        shutil.copytree(cache, os.path.join(work, "mutants", ".pytest_cache", "jax"), dirs_exist_ok=True)
    mutmut = os.path.join(os.path.dirname(sys.executable), "mutmut")
    env = _env(JAXROD_MUTANTS_STATS_FAILED=os.path.join(work, "stats_failed.txt"),
               JAXROD_MUTANTS_CLEAR="1" if clear_jit else "0")
    with open(os.path.join(work, "mutmut.log"), "w") as log:  # mutmut stops at the unknown name
        subprocess.run([mutmut, "run", "--max-children", "1", "no-such-mutant"], cwd=work, env=env,
                       stdout=log, stderr=subprocess.STDOUT, check=False)
    if not os.path.exists(os.path.join(work, "mutants", "mutmut-stats.json")):
        raise RuntimeError(f"mutmut made no stats: see {work}/mutmut.log")
    return time.time() - t0


def population(work: str) -> list[str]:
    names = []
    for dirpath, _, files in os.walk(os.path.join(work, "mutants", "jaxrod")):
        for f in files:
            if f.endswith(".py.meta"):
                names += json.load(open(os.path.join(dirpath, f)))["exit_code_by_key"]
    return sorted(n for n in names if not PLOTTING.search(_function(n)))


def select(name: str, stats: dict, failed: set[str], budget: float) -> tuple[list[str], int]:
    mapped = set(stats["tests_by_mangled_function_name"].get(name.partition("__mutmut_")[0], [])) - failed
    tests, total = [], 0.0
    for t in sorted(mapped, key=lambda t: (stats["duration_by_test"].get(t, 0.0), t)):
        d = stats["duration_by_test"].get(t, 0.0)
        if tests and total + d > budget:
            break
        tests.append(t)
        total += d
    return tests, len(mapped)


def _pytest(work: str, name: str, tests: list[str], timeout: float, first_only: bool) -> tuple[str, dict, float]:
    fd, record = tempfile.mkstemp(suffix=".json")
    os.close(fd)
    args = [sys.executable, "-m", "pytest", "--rootdir=.", "-q", "--tb=line", "-p", "no:cacheprovider",
            "-p", "no:xdist", "-p", "no:randomly", "-p", "mutants_plugin", *(["-x"] if first_only else []), *tests]
    env = _env(MUTANT_UNDER_TEST=name, JAXROD_MUTANTS_RECORD=record)
    t0 = time.time()
    p = subprocess.Popen(args, cwd=os.path.join(work, "mutants"), env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        rc = p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        rc = None
    seconds = time.time() - t0
    try:
        rec = json.load(open(record)) if os.path.getsize(record) else {}
    finally:
        os.unlink(record)
    where = rec.get("jaxrod")
    if where and not os.path.abspath(where).startswith(os.path.join(work, "mutants") + os.sep):
        raise RuntimeError(f"the tests imported jaxrod from {where}, not the mutated copy")
    if rc is None:
        return "timeout", rec, seconds
    if rc == 0:
        return "survived", rec, seconds
    if rc == 5:
        return "no tests", rec, seconds
    if rc in (1, 2, 3) and rec.get("failures"):
        return "killed", rec, seconds
    if rc == 4 and any(f["when"] == "collect" for f in rec.get("failures", [])):
        return "killed", rec, seconds  # a test module no longer imports: pytest found no collectors
    return ("crashed" if rc < 0 else f"error {rc}"), rec, seconds


def run_one(work: str, name: str, stats: dict, failed: set[str], budget: float, base: float,
            controls: dict[str, str]) -> dict:
    tests, mapped = select(name, stats, failed, budget)
    est = sum(stats["duration_by_test"].get(t, 0.0) for t in tests)
    out = {"tests_mapped": mapped, "tests_run": len(tests), "estimate_s": round(est, 1),
           "timeout_s": round(base + 3 * est)}
    if not tests:
        return {**out, "status": "no tests", "seconds": 0.0}
    status, rec, seconds = _pytest(work, name, tests, out["timeout_s"], True)
    out.update(status=status, seconds=round(seconds, 1))
    if status == "killed":
        f = rec["failures"][0]
        out.update(test=f["test"], how=f["how"], exception=f["type"], message=f["message"])
        if f["how"] == "exception":  # does any of its tests also fail on an assertion?
            s2, rec2, sec2 = _pytest(work, name, tests, out["timeout_s"], False)
            assertion = [g["test"] for g in rec2.get("failures", []) if g["how"] == "assertion"]
            out.update(exception_only=not assertion and s2 == "killed", recheck=s2, recheck_s=round(sec2, 1),
                       assertion_test=assertion[0] if assertion else None)
        if f["test"] not in controls:  # the killing test alone, no mutant active: it must pass
            alone = [f["test"]]  # a module that failed to import: its tests of this mutant
            if f["when"] == "collect":
                alone = [t for t in tests if t.split("::")[0] == f["test"].split("::")[0]] or alone
            s3, _, sec3 = _pytest(work, "", alone, out["timeout_s"], True)
            controls[f["test"]] = s3
            out["control_s"] = round(sec3, 1)
        if controls[f["test"]] != "survived":
            out["status"] = "control failed"  # the test fails without the mutant: no kill
    return out


def diffs(work: str, names: list[str]) -> dict[str, str]:
    code = ("import json, sys\nfrom mutmut.mutation.diff_apply import get_diff_for_mutant\n"
            "todo = json.load(sys.stdin)\n"
            "print(json.dumps({n: get_diff_for_mutant(n, path=p) for n, p in todo.items()}))\n")
    todo = {n: module_path(n, os.path.join(work, "mutants")) for n in names}
    out = subprocess.run([sys.executable, "-c", code], cwd=work, input=json.dumps(todo), capture_output=True,
                         text=True, env=_env())
    return json.loads(out.stdout) if out.returncode == 0 else {n: "" for n in names}


def _short(rev: str) -> str:
    return subprocess.run(["git", "rev-parse", "--short", rev], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.strip()


def _cost(r: dict) -> float:
    return r["seconds"] + r.get("recheck_s", 0.0) + r.get("control_s", 0.0)


def heldout(n: int, seed: int, out: str, work: str | None, budget: float, base: float, resume: bool,
            clear_jit: bool, rev: str | None, jobs: int = 1) -> dict:
    """Draw and run the sample (`rev`: the commit copied, None: the working tree), writing
    `out`/heldout.json after each mutant. `resume` goes on in the same work folder, whose copy of
    jaxrod/ and tests/ is the one the run started on. `jobs` mutants run side by side (each its own
    pytest process; they are taken in the order drawn, so a stopped run is still a uniform sample
    up to the `jobs` − 1 last ones in flight)."""
    path = os.path.join(out, "heldout.json")
    old = json.load(open(path)) if os.path.exists(path) else None
    used = (old or {}).get("seeds_used", [])
    rebuilt = False
    if resume:
        if not old or old["seed"] != seed:
            raise SystemExit(f"--resume: no unfinished run of seed {seed} ({path})")
        if os.path.exists(os.path.join(old["work"], "mutants", "mutmut-stats.json")):
            work = old["work"]
        elif old.get("dirty") or old["rev"] == "working tree":
            raise SystemExit(f"--resume: the run of seed {seed} mutated an uncommitted working tree and its work "
                             f"folder ({old['work']}) is gone")
        else:  # another machine, or the folder removed: the same commit is copied, mutated and mapped again
            rev, clear_jit, rebuilt = old["rev"], old.get("clear_jit", False), True
    elif seed in used:
        raise SystemExit(f"seed {seed} was used already ({path}): a held-out estimate takes a new seed")
    work = os.path.abspath(work or os.path.join(ROOT, "mutants", f"heldout-seed{seed}"))
    rev = _short(rev) if rev else None  # the commit itself: HEAD may move while the run goes on
    if not os.path.exists(os.path.join(work, "mutants", "mutmut-stats.json")):
        if resume and not rebuilt:
            raise SystemExit(f"--resume: {work} has no mutmut stats")
        if os.path.exists(work):
            shutil.rmtree(work)
        print(f"== held-out: mutating jaxrod/ of {rev or 'the working tree'} in {work} "
              "(mutmut's stats run: the default suite once)", flush=True)
        prep = prepare(work, rev, clear_jit)
    else:
        prep = (old or {}).get("prepare_s", 0.0)
    names = population(work)
    stats = json.load(open(os.path.join(work, "mutants", "mutmut-stats.json")))
    sf = os.path.join(work, "stats_failed.txt")
    failed = set(open(sf).read().split()) if os.path.exists(sf) else set()
    drawn = random.Random(seed).sample(names, min(n, len(names)))
    if resume and drawn != old["drawn"]:
        raise SystemExit(f"--resume: the mutants of {work} differ from the run's (the draw of seed {seed} changed)")
    mutated = {module_path(x, os.path.join(work, "mutants")) for x in names}
    res = old if resume else {
        "seed": seed, "n": len(drawn), "population": len(names), "rev": rev or "working tree",
        "commit": rev or commit(), "dirty": not rev and dirty(["jaxrod", "tests"]),
        "date": time.strftime("%Y-%m-%d"), "work": work, "drawn": drawn,
        "excluded": EXCLUDED, "excluded_functions": PLOTTING.pattern, "budget_s": budget, "timeout_base_s": base,
        "clear_jit": clear_jit, "prepare_s": round(prep, 1), "stats_failed": sorted(failed),
        "module_hashes": {p: sha256(p, work) for p in sorted(mutated)}, "seeds_used": sorted(set(used) | {seed}),
        "history": (old or {}).get("history", []) + ([headline(old)] if old and old.get("mutants") else []),
        "mutants": {}}
    if rebuilt:  # the rest runs against a new stats run of the same commit (the same mutants, the same draw)
        res["work"] = work
        res.setdefault("rebuilt", []).append({"date": time.strftime("%Y-%m-%d"), "prepare_s": round(prep, 1),
                                              "after": len(res["mutants"])})
    todo = [x for x in drawn if x not in res["mutants"]]
    dmap = diffs(work, todo)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    controls = res.setdefault("controls", {})
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs))
    running = [pool.submit(run_one, work, name, stats, failed, budget, base, controls) for name in todo]
    for i, (name, fut) in enumerate(zip(todo, running)):
        r = fut.result()
        r["module"], r["diff"] = module_path(name, os.path.join(work, "mutants")), dmap.get(name, "")
        res["mutants"][name] = r
        res["seconds"] = round(res.get("seconds", 0.0) + _cost(r), 1)
        with open(path, "w") as f:
            json.dump(res, f, indent=1, ensure_ascii=False)
        how = f" ({r['how']}: {r['test']})" if r["status"] == "killed" else ""
        print(f"   [{i + 1}/{len(todo)}] {name}: {r['status']}{how}, {r['seconds']:.0f} s, "
              f"{r['tests_run']} of {r['tests_mapped']} tests, {time.time() - t0:.0f} s so far", flush=True)
    return res


def headline(h: dict) -> str:
    ran = [m for m in h["drawn"] if m in h["mutants"]]
    k, n = sum(h["mutants"][m]["status"] == "killed" for m in ran), len(ran)
    lo, hi = wilson(k, n) if n else (float("nan"), float("nan"))
    pct = 100 * k / n if n else float("nan")
    return f"held-out: {k} killed of {n} ({pct:.1f} %, Wilson {100 * lo:.1f}–{100 * hi:.1f} %), seed {h['seed']}, commit {h['commit']}"


def section(h: dict, equivalent: dict) -> list[str]:
    ms = {m: h["mutants"][m] for m in h["drawn"] if m in h["mutants"]}
    killed = {m: r for m, r in ms.items() if r["status"] == "killed"}
    by_exc = {m: r for m, r in killed.items() if r["how"] == "exception"}
    only = {m: r for m, r in by_exc.items() if r.get("exception_only") and r["module"] not in INFRASTRUCTURE}
    counts: dict[str, int] = {}
    for r in ms.values():
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    eq = {m: equivalent.get(diff_key(r["diff"]) or ("", "", "")) for m, r in ms.items() if r["status"] != "killed"}
    eq = {m: why for m, why in eq.items() if why}
    k, n = len(killed), len(ms)
    secs = [_cost(r) for r in ms.values()]
    unfinished = ([f"**Unfinished:** {n} of the {h['n']} drawn mutants have run (taken in the order drawn, so "
                   "those run are themselves a uniform sample of the population); `python tools/mutants.py "
                   f"--held-out {h['n']} --seed {h['seed']} --resume` runs the rest.", ""] if n < h["n"] else [])
    earlier = ([f"Earlier estimates (each its own seed and commit): {'; '.join(h['history'])}.", ""]
               if h.get("history") else [])
    lines = ["## Held-out estimate", "", headline(h), "", *unfinished, *earlier,
             f"A uniform sample of {h['n']} of the {h['population']} mutants of the engine (seed {h['seed']}, drawn "
             f"{h['date']}{', uncommitted changes' if h.get('dirty') else ''}), {n} run; each against the default "
             f"tests mapped to its function, the fastest first within {h['budget_s']:.0f} s of their stats time. "
             "No tests, timeout, crash: not killed. Left out: "
             + "; ".join(f"`{p}` ({why})" for p, why in h["excluded"].items())
             + f"; functions matching `{h['excluded_functions']}` (plot styling).", "",
             "| " + " | ".join(counts) + " |", "|" + "---|" * len(counts),
             "| " + " | ".join(str(v) for v in counts.values()) + " |", "",
             f"Killed by an exception (the first failing test raised something other than an assertion): "
             f"{len(by_exc)} of {k} ({100 * len(by_exc) / max(k, 1):.0f} %); by an exception only (no test of the "
             f"mutant fails on an assertion), in numerical code: {len(only)}. "
             f"Non-killed mutants that match a recorded equivalence: {len(eq)}"
             + (f" (without them: {k} of {n - len(eq)}, {100 * k / max(n - len(eq), 1):.1f} %)" if eq else "") + ".",
             f"Time: {sum(secs):.0f} s for {n} mutants ({sum(secs) / max(n, 1):.0f} s each on average, the longest "
             f"{max(secs, default=0):.0f} s), after {h['prepare_s']:.0f} s of mutmut's mutants and stats run.", ""]
    none: dict[str, int] = {}
    for r in ms.values():
        if r["status"] == "no tests":
            none[r["module"]] = none.get(r["module"], 0) + 1
    if none:
        lines += ["No test of the default suite reaches: " + ", ".join(
            f"{k} in `{m}`" for m, k in sorted(none.items(), key=lambda x: -x[1])) + ".", ""]
    if h.get("stats_failed"):
        lines += ["Tests left out (they fail on the mutated copy with no mutant active): "
                  + ", ".join(f"`{t}`" for t in h["stats_failed"]), ""]
    lines += ["### Exception-only kills in numerical code (for review)", ""]
    for m, r in only.items():
        key = diff_key(r["diff"]) or ("", "", "")
        lines.append(f"- `{m}` by `{r['test']}`: {r['exception']}: {r['message'][:120]} — `{key[1][:100]}` → "
                     f"`{key[2][:100]}`")
    lines += ["" if only else "(none)", "", "### Per mutant", "", "| mutant | status | killing test | how | tests run of mapped | s |",
              "|---|---|---|---|---|---|"]
    for m, r in ms.items():
        how = f"{r['how']} ({r['exception']})" if r["status"] == "killed" else ("equivalent: " + eq[m][:60] if m in eq else "")
        lines.append(f"| `{m}` | {r['status']} | {('`' + r['test'] + '`') if r.get('test') else ''} | {how} | "
                     f"{r['tests_run']} of {r['tests_mapped']} | {r['seconds']:.0f} |")
    lines += ["", "### Held-out mutants not killed", ""]
    for m, r in ms.items():
        if r["status"] != "killed":
            lines += [f"#### {m}: {r['status']}", "", "```diff", r["diff"].strip(), "```", ""]
    return lines
