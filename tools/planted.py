"""Bugs planted by hand in the 3D rod's step and stiffness and in the lock-up staircase, each run
against the default suite (`python tools/planted.py`): which test kills it, or that none does.

Mutation testing (tools/mutants.py) draws small syntactic changes; these are the bugs a person
would make: a coefficient of Newmark's system, a sign of the gyroscopic couple, the damping's
work, a stiffness doubled in the energy and the couple, the wall's law, the friction bound of a
sliding contact, the staircase's bracket rule. Each bug is one or two text replacements in one module; it
is applied in a detached worktree of HEAD (`git worktree`, under a temporary folder), and the
default tests (`-m "not slow"`) of the files that use the changed module run there with `-x`
(the first failure kills the bug). The report, `results/planted/report.md`, gives per bug the
killing test (and whether an assertion or an exception failed) or "survived", and the commit.

    python tools/planted.py                 # every bug
    python tools/planted.py kick_beta wall  # some bugs, by name
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

ROD3D_TESTS = ["test_rod3d.py", "test_rod3d_contact.py", "test_rod3d_coupled.py", "test_rod3d_implicit.py",
               "test_rod3d_rest.py", "test_rod3d_step_limit.py", "test_rod3d_stiffness.py", "test_rod3d_helix.py",
               "test_rod3d_random_position.py", "test_rod3d_physics.py", "test_engine.py", "test_leapfrog.py",
               "test_independent_reference.py", "test_experiments_rod3d_fast.py", "test_e3_rod3d.py",
               "test_lockup_push.py"]
ADAPTIVE_TESTS = ["test_adaptive.py", "test_rod3d_implicit.py", "test_engine.py", "test_sweep.py"]
LOCKUP_TESTS = ["test_lockup_drivers_fast.py", "test_lockup_staircase.py", "test_lockup_push.py",
                "test_lockup_verdict.py", "test_lockup_curve_data.py"]

# name: (module, text, replacement, what the bug is, the test files run)
BUGS = {
    "kick_beta": ("jaxrod/rod3d/hessian.py", "    c = h * h\n", "    c = 0.5 * h * h\n",
                  "Newmark's matrix with half of its stiffness term (β h² → β h²/2)", ROD3D_TESTS),
    "kick_gyro_sign": ("jaxrod/rod3d/hessian.py", "a.tau - gyro", "a.tau + gyro",
                       "the implicit kick's gyroscopic couple with the wrong sign", ROD3D_TESTS),
    "damping_work": ("jaxrod/rod3d/hessian.py", "hk * system.vel + h * step), 0.0)", "hk * system.vel), 0.0)",
                     "the damping's impulse without its implicit part (what `dissipated` counts)", ROD3D_TESTS),
    "damping_loss_mean": ("jaxrod/rod3d/hessian.py", "lost = -impulse * 0.5 *", "lost = -impulse * 1.0 *",
                          "the damping's work at twice the mean velocity", ROD3D_TESTS),
    "damp_stretch": ("jaxrod/rod3d/hessian.py", "DAMPED = (1.0, 1.0, 1.0, 1.0), (0.0, 1.0, 1.0, 1.0)",
                     "DAMPED = (1.0, 1.0, 1.0, 1.0), (1.0, 1.0, 1.0, 1.0)",
                     "the numerical damping also on stretch", ROD3D_TESTS),
    "bend_doubled": ("jaxrod/rod3d/energy.py",
                     ("(rod.EI * psi[0] / l0, rod.EI * psi[1] / l0,", "bend=0.5 * l0 * rod.EI *"),
                     ("(2 * rod.EI * psi[0] / l0, 2 * rod.EI * psi[1] / l0,", "bend=1.0 * l0 * rod.EI *"),
                     "EI doubled in the bending energy and couple", ROD3D_TESTS),
    "twist_doubled": ("jaxrod/rod3d/energy.py",
                      ("rod.GJ * psi[2] / l0), cj)", "twist=0.5 * l0 * rod.GJ *"),
                      ("2 * rod.GJ * psi[2] / l0), cj)", "twist=1.0 * l0 * rod.GJ *"),
                      "GJ doubled in the twisting energy and couple", ROD3D_TESTS),
    "wall_linear": ("jaxrod/rod3d/energy.py",
                    ("model.contact_stiffness * 0.4 * pen**2.5)", "return jnp.where(pos, pen * jnp.sqrt(jnp.where(pos, pen, 1.0)), 0.0)"),
                    ("model.contact_stiffness * 0.5 * pen**2)", "return jnp.where(pos, pen, 0.0)"),
                    "the wall linear (energy ½kδ², force kδ) instead of Hertz's δ^{3/2}", ROD3D_TESTS),
    "ends_full_length": ("jaxrod/rod3d/model.py", "w = jnp.ones(self.n + 1).at[0].set(0.5).at[-1].set(0.5)",
                         "w = jnp.ones(self.n + 1)",
                         "the end nodes carry a whole segment's length (mass, weight, wall)", ROD3D_TESTS),
    "step_limit_lateral": ("jaxrod/rod3d/stiffness.py", "    d = (k_s * l0**2 + 4.0 * k_b + N * l0) / J_t",
                           "    d = (k_s * l0**2 + 4.0 * k_b + N * l0) / (2.0 * J_t)",
                           "the step limit's lateral block with the segment's rotary inertia doubled", ROD3D_TESTS),
    "coupled_bound_static": ("jaxrod/rod3d/coupled.py", "bound = hk * jnp.where(v.stuck, model.rod.mu_s, model.rod.mu_d) * N",
                             "bound = hk * model.rod.mu_s * N",
                             "the coupled solve bounds a sliding contact by μ_s", ROD3D_TESTS),
    "local_slip_static": ("jaxrod/rod3d/contact.py", "bound_d=model.rod.mu_d.astype(dtype) * N",
                          "bound_d=model.rod.mu_s.astype(dtype) * N",
                          "the local friction pass bounds a sliding contact by μ_s", ROD3D_TESTS),
    "inadequate_never": ("jaxrod/integrators/implicit.py", "& check(self.coupled), RESULTS.inadequate",
                         "& check(self.coupled) & False, RESULTS.inadequate",
                         "the implicit scheme never reports `inadequate` past the wrinkling load", ROD3D_TESTS),
    "staircase_bracket": ("jaxrod/lockup/staircase.py", "(p - lane[\"lo\"]) <= rel * p", "(p - lane[\"lo\"]) <= 2 * rel * p",
                          "the staircase calls a bracket closed at twice its width", LOCKUP_TESTS),
    "staircase_repeat": ("jaxrod/lockup/staircase.py", "status == TRANSIENT and lane[\"repeats\"] < repeats",
                         "status == TRANSIENT and lane[\"repeats\"] <= repeats",
                         "a transient stage repeated once more than `repeats`", LOCKUP_TESTS),
    "staircase_lo_above": ("jaxrod/lockup/staircase.py", "    if status == SLIDING and f_bar <= f_c:",
                           "    if status == SLIDING and f_bar <= 1.05 * f_c:",
                           "a steady stage up to 5 % above the bound counted as a lower bound", LOCKUP_TESTS),
    "crossing_nearest_stage": ("jaxrod/lockup/staircase.py", "linear = x0 + (f_c - f0) * (x1 - x0) / (f1 - f0)",
                               "linear = x0 if f_c - f0 < f1 - f_c else x1",
                               "the crossing read as the nearer stage instead of interpolated", LOCKUP_TESTS),
    "error_estimate_beta": ("jaxrod/rod3d/step_error.py", "jnp.abs(beta - 1.0 / 6.0)", "jnp.abs(beta - 1.0 / 3.0)",
                            "the step's error estimate with |β − 1/3| for |β − 1/6| (equal at β = ¼)", ADAPTIVE_TESTS),
    "controller_accept_2": ("jaxrod/integrators/adaptive.py", "(frozen | (err <= 1.0) | at_min)",
                            "(frozen | (err <= 2.0) | at_min)",
                            "the step controller accepts a step at twice the tolerance", ADAPTIVE_TESTS),
    "controller_grows_after_reject": ("jaxrod/integrators/adaptive.py",
                                      "grow = jnp.where(accept, jnp.where(c.rejected_last, 1.0, FACTOR_MAX), 0.9)",
                                      "grow = jnp.where(accept, FACTOR_MAX, 0.9)",
                                      "the step grows right after a rejected attempt", ADAPTIVE_TESTS),
}


def _run(names, out):
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    python = os.path.join(ROOT, ".venv", "bin", "python")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tree = os.path.join(tmp, "tree")
        subprocess.run(["git", "worktree", "add", "--detach", tree, "HEAD"], cwd=ROOT, check=True, capture_output=True)
        try:
            for name in names:
                module, old, new, what, tests = BUGS[name]
                path = os.path.join(tree, module)
                text = open(path).read()
                planted = text
                for a, b in zip(*((x,) if isinstance(x, str) else x for x in (old, new))):
                    if planted.count(a) != 1:
                        raise SystemExit(f"bug {name}: {a!r} is not found once in {module}")
                    planted = planted.replace(a, b)
                with open(path, "w") as fh:
                    fh.write(planted)
                files = [os.path.join("tests", f) for f in tests if os.path.exists(os.path.join(tree, "tests", f))]
                t = time.time()
                env = dict(os.environ, PYTHONPATH=tree)
                proc = subprocess.run([python, "-m", "pytest", "-m", "not slow", "-x", "-q", "-rf", "--tb=line", "-p", "no:cacheprovider",
                                       "-n", "0", *files], cwd=tree, env=env, capture_output=True, text=True)
                with open(path, "w") as fh:
                    fh.write(text)
                failed = re.findall(r"^FAILED (\S+)(?: - (.*))?$", proc.stdout, re.M)
                if failed:
                    verdict = f"killed by `{failed[0][0]}`"
                elif proc.returncode == 0:
                    verdict = "**survived**"
                else:
                    verdict = f"error (pytest exit {proc.returncode})"
                rows.append((name, module, what, verdict, time.time() - t))
                print(f"{name}: {verdict} ({time.time() - t:.0f} s)", flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", tree], cwd=ROOT, capture_output=True)
    killed = sum(r[3].startswith("killed") for r in rows)
    lines = [f"# Bugs planted by hand against the default suite (`python tools/planted.py`)", "",
             f"At {head}, {datetime.date.today()}, this 2-core CPU: **{killed} of {len(rows)} killed**. Each bug is one",
             "replacement (tools/planted.py, `BUGS`); the default tests of the files that use its module ran with `-x`.", "",
             "| bug | module | what | verdict | s |", "|---|---|---|---|---|"]
    lines += [f"| {n} | `{m}` | {w} | {v} | {s:.0f} |" for n, m, w, v, s in rows]
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print(f"{killed} of {len(rows)} killed; {out}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help=f"bugs to plant (default: all of {', '.join(BUGS)})")
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "planted", "report.md"))
    args = ap.parse_args(argv)
    unknown = [n for n in args.names if n not in BUGS]
    if unknown:
        raise SystemExit(f"names = {unknown!r} are invalid: expected some of {', '.join(BUGS)}.")
    _run(args.names or list(BUGS), args.out)


if __name__ == "__main__":
    sys.exit(main())
