"""Mutation testing of jaxrod's physics and reporting modules (`make mutants`).

Each group mutates some modules with mutmut and runs, for every mutant, the default-suite tests
of the group's test files that executed the mutated function (mutmut's stats run maps them).
A group's tests are files or pytest node ids (`file::test`): a node id maps a module to a
documented fast subset of a slow file (each such subset says why next to its group). Every
group runs in a copy of the checkout (`mutmut` keeps its state in `mutants/` there), so
groups do not disturb each other or the working tree. The report (`report.md`, `report.json`
under `--out`) gives per group the mutants made, killed, survived, without a test, timed out,
and the equivalent ones (listed with their reason in `tools/mutants_equivalent.json`), the score
killed / (made − equivalent), and the diff of every survivor.

    python tools/mutants.py                  # every group
    python tools/mutants.py theory friction  # some groups
    python tools/mutants.py rod3d --sample 60  # a random sample of a group's mutants
    python tools/mutants.py --full             # every mutant (models, rod3d, boundary: days)

Held-out estimate of the whole engine (tools/mutants_heldout.py: what is mutated, what is left out
and why, the per-mutant test cap and timeout, how a kill's cause is recorded):

    python tools/mutants.py --held-out 400 --seed 7   # a fresh uniform sample; a seed is used once

Staleness: the report keeps the sha256 of every mutated module (per group, and of the held-out
run); `--stale` prints and writes into the report (and README.md's copy of its preamble)
`stale: M of T mutated modules changed since their run`; `--changed` (`make mutants`) reruns
the groups with a changed module (a stale held-out estimate takes a new seed, never a rerun).
Equivalent mutants are keyed by their mutated line's text (tools/mutants_lib.py).

A group whose every mutant would take hours on this CPU (each mutant compiles JAX functions for
its tests) is run on a uniform random sample (`--sample K`, seed 0; by default the sizes in
`SAMPLE`): the report then gives the sample's score with its 95 % Wilson interval, and the
mutants left out as "not sampled". A sampled group interrupted (Ctrl-C) keeps the mutants it
ran; those drawn but not reached count as not sampled (mutmut runs the drawn mutants in order of their tests' estimated time, so an
interrupted sample leans towards mutants covered by fewer or faster tests).
"""

from __future__ import annotations

import argparse
import datetime
import glob
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

import mutants_heldout
from mutants_lib import (ROOT, commit, equivalent_reason, load_equivalent, sha256, sha256_at, stale, stale_line,
                         update_readme_frame, wilson)

# group: (modules mutated, test files whose default tests may kill them)
GROUPS = {
    "theory": (["jaxrod/theory.py"], ["tests/test_theory.py", "tests/test_theory_hand.py"]),
    # + the one quick test of the 3D rod's vector law (an independent minimiser over the disc);
    # the rest of test_rod3d.py compiles rods for tens of seconds and tests the law only through them
    "friction": (["jaxrod/friction.py"], ["tests/test_single_mode.py", "tests/test_leapfrog.py",
                 "tests/test_rod3d.py::test_vector_coulomb_impulse_minimises_the_kinetic_energy_over_the_disc"]),
    # the tests of the perturbations themselves; left out: test_fidelity's ΔF* convergence in n
    # (boundary searches on up to 768 nodes) and the rest of test_field.py (runs of the field
    # model that merely start from a perturbation), minutes per mutant for no other check of it
    "perturbations": (["jaxrod/perturbations.py"], [
        "tests/test_fidelity.py::test_modal_amplitudes_do_not_depend_on_the_model_resolution",
        "tests/test_fidelity.py::test_the_scene_field_on_its_own_grid_is_the_nodal_draw",
        "tests/test_fidelity.py::test_galerkin_and_single_mode_get_the_same_modes",
        "tests/test_fidelity.py::test_the_3d_rod_gets_the_same_modes_at_its_nodes",
        "tests/test_fidelity.py::test_scene_noise_on_a_small_grid_by_hand",
        "tests/test_fidelity.py::test_sine_velocity_user_state_and_mode_projection_by_hand",
        "tests/test_fidelity.py::test_random_force_over_a_duration_that_is_not_a_whole_number_of_steps",
        "tests/test_fidelity.py::test_the_forcing_phase_model_is_the_rod_plus_a_constant_acceleration",
        "tests/test_fidelity.py::test_random_force_on_a_ramped_load_sees_the_load_at_each_step",
        "tests/test_fidelity.py::test_noise_fields_keep_the_points_dtype_and_the_3d_rod_gets_only_its_resolved_modes",
        "tests/test_field.py::test_random_force_pulse_is_the_exact_forced_response_without_friction",
        "tests/test_field.py::test_perturbations"]),
    "models": (["jaxrod/models/*"], ["tests/test_single_mode.py", "tests/test_field.py", "tests/test_engine.py"]),
    "rod3d": (["jaxrod/rod3d/energy.py", "jaxrod/rod3d/contact.py", "jaxrod/rod3d/model.py"],
              ["tests/test_rod3d.py", "tests/test_rod3d_contact.py", "tests/test_rod3d_rest.py",
               "tests/test_rod3d_loaded.py"]),
    "boundary": (["jaxrod/boundary/*"], ["tests/test_boundary.py", "tests/test_roots.py"]),
    # the map's numbers on hand-built results and one 2 × 2 single-mode map; test_cli.py's
    # field-model map (sweeps, a boundary search and single scenes) takes a minute per mutant.
    # 762 mutants (most in plot_maps' labels, markers and limits), sampled: 200 take about 20 min
    "stability_map": (["jaxrod/stability_map.py"], ["tests/test_mutants_stability_map.py"]),
    "sweeps_result": (["jaxrod/sweeps/result.py"], ["tests/test_sweep.py"]),
}

# the groups run on a sample by default (`make mutants`): every mutant would take a day here
SAMPLE = {"models": 20, "rod3d": 60, "boundary": 40, "stability_map": 200}

STATUS = ("killed", "survived", "no tests", "timeout", "suspicious", "segfault", "skipped", "not checked",
          "not sampled")


def _config(modules, tests) -> str:
    return "\n".join([
        "[tool.mutmut]",
        'source_paths = ["jaxrod/"]',
        'pytest_add_cli_args = ["-p", "no:xdist", "-p", "no:cacheprovider"]',
        f"pytest_add_cli_args_test_selection = {json.dumps(tests)}",
        f"only_mutate = {json.dumps(modules)}",
        # a fresh interpreter per mutant: JAX's threads make forking a warmed-up process unsafe
        'process_isolation = "forkserver"',
        'forkserver_warmup = "none"',
        "",
    ])


def _results(mutmut: str, work: str) -> dict[str, str]:
    out = subprocess.run([mutmut, "results", "--all", "true"], cwd=work, capture_output=True, text=True).stdout
    status = {}
    for line in out.splitlines():
        m = re.match(r"\s*(\S+): (.+)$", line)
        if m:
            status[m.group(1)] = m.group(2).strip()
    return status


def run_group(name: str, jobs: int, only: list[str] | None = None, earlier: dict | None = None,
              sample: int | None = None) -> dict:
    """Run a group's mutants (or only the mutants `only`, keeping the `earlier` result's status
    of the others: `--survivors` after new tests; or a random `sample` of them)."""
    modules, tests = GROUPS[name]
    work = tempfile.mkdtemp(prefix=f"jaxrod-mutants-{name}-")
    for d in ("jaxrod", "tests"):
        shutil.copytree(os.path.join(ROOT, d), os.path.join(work, d),
                        ignore=shutil.ignore_patterns("__pycache__", ".pytest_cache"))
    text = open(os.path.join(ROOT, "pyproject.toml")).read()
    text = re.sub(r"\n\[tool\.mutmut\].*?(?=\n\[|\Z)", "\n", text, flags=re.S)
    with open(os.path.join(work, "pyproject.toml"), "w") as f:
        f.write(text + "\n" + _config(modules, tests))
    mutmut = os.path.join(os.path.dirname(sys.executable), "mutmut")
    t0 = time.time()
    print(f"== {name}: mutating {', '.join(modules)} against {', '.join(tests)}", flush=True)
    drawn = sample is not None and only is None
    if drawn:
        # make the mutants and the test statistics (mutmut stops at the unknown name), then draw
        subprocess.run([mutmut, "run", "--max-children", str(jobs), "no-such-mutant"], cwd=work,
                       check=False, capture_output=True)
        names = sorted(_results(mutmut, work))
        only = sorted(random.Random(0).sample(names, min(sample, len(names))))
        print(f"   {len(only)} of {len(names)} mutants drawn", flush=True)
        earlier = {"status": {k: "not sampled" for k in names}, "seconds": 0.0}
    subprocess.run([mutmut, "run", "--max-children", str(jobs), *(only or [])], cwd=work, check=False)
    status = _results(mutmut, work)
    if drawn:  # drawn but not reached before an interrupt (Ctrl-C): left out of the sample
        status = {k: "not sampled" if v == "not checked" else v for k, v in status.items()}
    if only is not None and earlier is not None:
        status = {**earlier["status"], **{k: status.get(k, "not checked") for k in only}}
    diffs = {}
    for key, s in status.items():
        if s not in ("killed", "not sampled"):
            diffs[key] = subprocess.run([mutmut, "show", key], cwd=work, capture_output=True, text=True).stdout
    shutil.rmtree(work, ignore_errors=True)
    seconds = round(time.time() - t0, 1) + (earlier["seconds"] if only is not None and earlier else 0.0)
    return {"modules": modules, "tests": tests, "seconds": seconds, "status": status, "diffs": diffs,
            "commit": commit(), "date": str(datetime.date.today()),
            "module_hashes": {p: sha256(p) for p in _module_files(modules)}}


def _module_files(modules: list[str]) -> list[str]:
    """The files a group's module patterns name (as mutmut's only_mutate globs them)."""
    return sorted(os.path.relpath(p, ROOT) for m in modules for p in glob.glob(os.path.join(ROOT, m))
                  if p.endswith(".py"))


def _backfill_hashes(results: dict) -> None:
    """Groups run before the hashes were recorded: their modules' sha256 at the group's commit."""
    for g in results.values():
        if "module_hashes" not in g:
            g["module_hashes"] = {p: sha256_at(g.get("commit", "HEAD"), p) for p in _module_files(g["modules"])}


def summarise(group: dict, equivalent: dict) -> dict:
    counts = {s: 0 for s in STATUS}
    for key, s in group["status"].items():
        counts[s if s in counts else "suspicious"] += 1
    made = len(group["status"])
    eq = [k for k, s in group["status"].items()
          if s not in ("killed", "not sampled") and equivalent_reason(group["diffs"].get(k), equivalent)]
    counts["equivalent"] = len(eq)
    counts["made"] = made
    counts["run"] = made - counts["not sampled"]
    n = counts["run"] - len(eq)
    counts["score"] = counts["killed"] / n if n > 0 else float("nan")
    counts["interval"] = wilson(counts["killed"], n) if counts["not sampled"] and n > 0 else None
    return counts


def write_report(results: dict, out: str, stamp: tuple[str, str] | None = None):
    """report.md and report.json under `out` (and README.md's copy of the preamble when `out` is
    results/mutation); `stamp` (commit, date) keeps the report's own when nothing was run."""
    equivalent = load_equivalent()
    _backfill_hashes(results)
    hpath = os.path.join(out, "heldout.json")
    held = json.load(open(hpath)) if os.path.exists(hpath) else None
    st = stale({"groups": results}, held)
    stamp = stamp or (commit(), str(datetime.date.today()))
    os.makedirs(out, exist_ok=True)
    rows, body = [], []
    total = {"made": 0, "run": 0, "killed": 0, "equivalent": 0}
    for name, g in results.items():
        c = summarise(g, equivalent)
        for k in total:
            total[k] += c[k]
        score = f"{100 * c['score']:.1f} %"
        if c["interval"]:
            score += f" ({100 * c['interval'][0]:.0f}–{100 * c['interval'][1]:.0f} %)"
        rows.append(f"| {name} ({g.get('commit', '?')}, {g.get('date', '?')}) | {c['made']} | {c['run']} | {c['killed']} | {c['survived']} | {c['no tests']} | {c['timeout']} | "
                    f"{c['equivalent']} | {score} | {g['seconds']:.0f} s |")
        for key, diff in g["diffs"].items():
            why = equivalent_reason(diff, equivalent)
            body.append(f"### {key}: {g['status'][key]}{f' — equivalent: {why}' if why else ''}\n\n"
                        f"```diff\n{diff.strip()}\n```\n")
    score = total["killed"] / max(total["run"] - total["equivalent"], 1)
    head = [f"# Mutation testing (mutmut), commit {stamp[0]}, {stamp[1]}", "",
            "Score = killed / (run − equivalent); a mutant without a test or that timed out counts as not killed. "
            "A group with fewer mutants run than made was run on a uniform random sample (seed 0); "
            "its score has the sample's 95 % Wilson interval.", "",
            "| group | made | run | killed | survived | no tests | timeout | equivalent | score | time |",
            "|---|---|---|---|---|---|---|---|---|---|", *rows, "",
            f"**All groups: {total['killed']} killed of {total['run'] - total['equivalent']} non-equivalent "
            f"mutants run, {100 * score:.1f} %.**", "",
            *([mutants_heldout.headline(held), ""] if held else []), stale_line(st), ""]
    extra = mutants_heldout.section(held, equivalent) if held else []
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(head + extra + ["## Mutants not killed", ""] + body))
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump({"commit": stamp[0], "date": stamp[1], "stale": st, "groups": results}, f, indent=1)
    if os.path.abspath(out) == os.path.join(ROOT, "results", "mutation"):
        update_readme_frame(os.path.join(out, "report.md"))
    print("\n".join(head))
    return st


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("groups", nargs="*", help=f"groups to run (default: all): {', '.join(GROUPS)}")
    p.add_argument("--out", default=os.path.join(ROOT, "results", "mutation"), help="report folder")
    p.add_argument("--jobs", type=int, default=2, help="mutants run side by side")
    p.add_argument("--survivors", action="store_true",
                   help="rerun only the mutants the report lists as not killed (after new tests)")
    p.add_argument("--sample", type=int, default=None,
                   help=f"run a uniform random sample of this many mutants per group (seed 0; default {SAMPLE})")
    p.add_argument("--full", action="store_true", help="every mutant of every group (no default samples)")
    p.add_argument("--stale", action="store_true", help="only rewrite the report with its stale line")
    p.add_argument("--changed", action="store_true",
                   help="rerun the groups with a module changed since their run (`make mutants`)")
    h = p.add_argument_group("held-out estimate (tools/mutants_heldout.py)")
    h.add_argument("--held-out", type=int, metavar="N", help="draw N mutants of the whole engine and run them")
    h.add_argument("--seed", type=int, help="the draw's seed (required with --held-out; used once)")
    h.add_argument("--resume", action="store_true", help="go on with an unfinished draw of this seed")
    h.add_argument("--budget", type=float, default=120.0, help="per mutant: stats seconds of tests run (cap)")
    h.add_argument("--timeout-base", type=float, default=120.0, help="per mutant: timeout = this + 3 × estimate")
    h.add_argument("--work", help="work folder (default: mutants/heldout-seedS)")
    h.add_argument("--clear-jit", action="store_true", help="clear JAX's caches after each test of the stats run")
    h.add_argument("--rev", default="HEAD", help="the commit to mutate (default HEAD; '' for the working tree)")
    a = p.parse_args(argv)
    bad = [g for g in a.groups if g not in GROUPS]
    if bad:
        p.error(f"argument groups: {bad} not among {list(GROUPS)}")
    results, stamp = {}, None
    path = os.path.join(a.out, "report.json")
    if os.path.exists(path):  # earlier groups of the same commit stay in the report
        old = json.load(open(path))
        results.update(old["groups"])  # each group's own commit is in the report
        stamp = (old.get("commit", "?"), old.get("date", "?"))
    if a.held_out is not None:
        if a.seed is None:
            p.error("--held-out needs --seed")
        mutants_heldout.heldout(a.held_out, a.seed, a.out, a.work, a.budget, a.timeout_base, a.resume, a.clear_jit,
                                a.rev or None, jobs=a.jobs)
        write_report(results, a.out)
        return 0
    if a.stale or a.changed:
        _backfill_hashes(results)
        hpath = os.path.join(a.out, "heldout.json")
        st = stale({"groups": results}, json.load(open(hpath)) if os.path.exists(hpath) else None)
        print(stale_line(st) + (f": {', '.join(st['changed'])}" if st["changed"] else ""))
        if st["heldout"]:
            print("the held-out estimate is stale: draw a new one with a new seed (--held-out N --seed S)")
        todo = (a.groups or st["groups"]) if a.changed else []
        for g in todo:
            results[g] = run_group(g, a.jobs, None, None, a.sample if a.sample is not None else SAMPLE.get(g))
            write_report(results, a.out)
        if not todo:
            write_report(results, a.out, stamp)
        return 0
    for g in a.groups or list(GROUPS):
        earlier = results.get(g) if a.survivors else None
        only = [k for k, v in earlier["status"].items() if v not in ("killed", "not sampled")] if earlier else None
        sample = a.sample if a.sample is not None or a.full else SAMPLE.get(g)
        results[g] = run_group(g, a.jobs, only, earlier, sample)
        write_report(results, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
