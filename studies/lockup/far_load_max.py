"""F_far,max(μL/ℓ) of the injected 3D rod: at each μL/ℓ, bisection (in log F_far, to a factor
`--rtol`) of the largest far-end load the rod can be injected against without locking up
(`jaxrod.lockup.push.locked`: over the last fifth of the push the far end advances less than
half as far as the entry, or the entry force passes ℓ/r F₀), beside the soft-string closed forms.
r/ℓ = 0.02, μ = 0.5, the reference nitinol, 5 mm/s, a push of 0.075 L, damping 20/s.

Every run is appended to far_load_max_runs_muL<X>.csv as it finishes and replayed from it on a rerun
(a stopped search loses nothing); the result per μL/ℓ goes to far_load_max_muL<X>.csv.

    python studies/lockup/far_load_max.py --muL 0.5 1 --bracket 5 12 3.5 5
"""

import argparse
import csv
import math
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

from jaxrod.lockup import chain  # noqa: E402
from jaxrod.lockup.closed_forms import HELICAL_LAWS, HELICAL_ONSETS  # noqa: E402
from jaxrod.lockup.push import inject, locked, push_rod, units  # noqa: E402
from jaxrod.output import write_csv  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
SPEED, DAMPING, PUSH_PER_LENGTH = 5e-3, 20.0, 0.075


def _runs(X):
    return os.path.join(HERE, f"far_load_max_runs_muL{X:g}.csv")


def run(X, f_far, done):
    key = (f"{X:g}", f"{f_far:.6g}")
    if key in done:
        return done[key]
    rod = push_rod(X, 0.02, 0.5)
    F0, _ = units(rod)
    push = PUSH_PER_LENGTH * float(rod.L)
    t = time.perf_counter()
    rec = inject(rod, f_far * F0, SPEED, push / SPEED, n_save=201, damping=DAMPING)
    loading = rec["phase"] == 0
    lk = locked(rec)  # None: the run failed (non-finite) before telling
    row = dict(mu_L_over_ell=f"{X:g}", far_load_over_F0=f"{f_far:.6g}", locked="" if lk is None else int(lk),
               entry_force_max_over_F0=float(max(rec["f_in"][loading])), far_advance=float(rec["u"][loading, 0][-1]),
               push=push, n=int(rec["n"]), result=int(rec["result"]), wall_s=time.perf_counter() - t)
    path = _runs(X)
    new = not os.path.exists(path)
    with open(path, "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(row))
        if new:
            w.writeheader()
        w.writerow(row)
    print(row, flush=True)
    done[key] = row
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--muL", type=float, nargs="+", required=True)
    ap.add_argument("--bracket", type=float, nargs="+", required=True, help="lo hi [F0] per muL (lo slides, hi locks)")
    ap.add_argument("--rtol", type=float, default=0.05)
    a = ap.parse_args()
    done = {}
    for X in a.muL:
        if os.path.exists(_runs(X)):
            with open(_runs(X)) as fh:
                done.update({(r["mu_L_over_ell"], r["far_load_over_F0"]): r for r in csv.DictReader(fh)})
    out = []
    for k, X in enumerate(a.muL):
        lo, hi = a.bracket[2 * k], a.bracket[2 * k + 1]
        ends = [run(X, lo, done)["locked"], run(X, hi, done)["locked"]]
        if "" in ends or int(ends[0]) or not int(ends[1]):
            print(f"muL/ell = {X:g}: [{lo:g}, {hi:g}] F0 does not bracket the lock-up (or a run failed); skipped",
                  flush=True)
            continue
        while hi / lo > 1 + a.rtol:
            mid = math.sqrt(lo * hi)
            label = run(X, mid, done)["locked"]
            if label == "":  # a failed run tells nothing: the bracket so far is the result
                print(f"muL/ell = {X:g}: the run at {mid:.4g} F0 failed; stopped at [{lo:g}, {hi:g}]", flush=True)
                break
            lo, hi = (mid, hi) if not int(label) else (lo, mid)
        rod = push_rod(X, 0.02, 0.5)
        F0, _ = units(rod)
        geometry = (float(rod.L), float(rod.EI), float(rod.rho * rod.g), float(rod.R), 0.5)
        row = dict(mu_L_over_ell=X, far_load_max_lo=lo, far_load_max_hi=hi)
        for onset in HELICAL_ONSETS:
            for law in HELICAL_LAWS:
                row[f"soft_string_{onset}_{law}"] = float(chain.far_force_max(*geometry, helical_onset=onset,
                                                                              helical_law=law)) / F0
        out.append(row)
        print(row, flush=True)
    for row in out:  # one file per muL/ell: searches of different muL/ell may run side by side
        write_csv(os.path.join(HERE, f"far_load_max_muL{row['mu_L_over_ell']:g}.csv"), [row])


if __name__ == "__main__":
    main()
