"""The 3D rod's lock-up length: rods of L = 5ℓ (r/ℓ = 0.02, the reference nitinol, 90
segments) injected with no far load at μ = 0.6, 0.8, 0.9, 1.0 (μL/ℓ = 3, 4, 4.5, 5) as the lanes
of one run (`jaxrod.lockup.push.inject_lanes`), 0.075 L at 5 mm/s, damping 20/s; a lane locks
up (`locked`) when its far end falls behind or its entry force passes ℓ/r F₀. The soft string's
μL_lock/ℓ is 4.06 (Chen, with weight), 4.24 (Chen, without), 4.66 / 4.75 (Wu & Juvkam-Wold).
Writes lockup_length.csv (one row per lane, with commit, date and wall time).

    python studies/lockup/lockup_length.py"""

import csv
import datetime
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from jaxrod.lockup.push import inject_lanes, lane, locked, push_rod, units  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
L_OVER_ELL, X = 5.0, (3.0, 4.0, 4.5, 5.0)


def main():
    rod = push_rod(L_OVER_ELL, 0.02, 1.0)  # μ = 1: L = 5ℓ; each lane sets its own μ
    F0, ell = units(rod)
    mus = np.array(X) / L_OVER_ELL
    push = 0.075 * float(rod.L)
    t = time.perf_counter()
    rec = inject_lanes(rod, mus, np.zeros_like(mus), 5e-3, push / 5e-3, n_save=201, damping=20.0, progress=True)
    wall = time.perf_counter() - t
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rows = []
    for k, x in enumerate(X):
        r = lane(rec, k)
        tail = r["push"] >= 0.8 * r["push"][-1]
        lk = locked(r)
        rows.append(dict(mu_L_over_ell=x, mu=mus[k], n=int(rec["n"]), locked="" if lk is None else int(lk),
                         held_from_s=float(r["held_from"]), result=int(r["result"]),
                         entry_force_over_F0=float(np.mean(r["f_in"][tail])), entry_force_max_over_F0=float(np.max(r["f_in"])),
                         far_advance=float(r["u"][-1, 0]), push=float(r["push"][-1]),
                         helical_over_ell=float(r["helical"][-1] / ell), sinusoidal_over_ell=float(r["sinusoidal"][-1] / ell),
                         wall_s_all_lanes=round(wall, 1), commit=commit, date=datetime.date.today().isoformat()))
        print(rows[-1], flush=True)
    with open(os.path.join(HERE, "lockup_length.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
