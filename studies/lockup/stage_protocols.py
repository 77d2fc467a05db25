"""The lock-up curve's path band at μL/ℓ = 1 (L = 2ℓ, μ = 0.5, r/ℓ = 0.02, 16 segments per buckle
wave, 10 mm/s; the setting of `jaxrod reproduce lockup`'s base run): the staircase for
F_far,max(6 F₀) run again with other stage protocols, each a lane of its own —

- `settle 0.3 m`: each stage pushed 0.3 m instead of 0.15 m (a longer settle at each far load);
- `start 0.5x`: the staircase started at half the base's first far load (0.7 × the smallest
  closed form there), so that it climbs through other far loads;

beside the base staircase's bracket (`results/lockup/curve.csv`). Writes stage_protocols.json in
results/lockup/ (the folder of this study under results/), with the commit that ran it.

    python studies/lockup/stage_protocols.py [settle|start]   # each about 10 min on one core
"""

import json
import os
import subprocess
import sys
import time

import jax

jax.config.update("jax_enable_x64", True)

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/

from jaxrod.experiments.lockup import DAMPING, R_OVER_ELL, SETTINGS, _closed  # noqa: E402
from jaxrod.lockup.push import buckle_wavelength, push_rod  # noqa: E402
from jaxrod.lockup.staircase import staircase  # noqa: E402

X, L_OVER_ELL, PER_WAVE, SPEED = 1.0, 2.0, 16, 10e-3


def run(protocol: str) -> dict:
    S = SETTINGS[False]
    rod = push_rod(L_OVER_ELL, R_OVER_ELL, 1.0)
    n = max(8, -(-PER_WAVE * float(rod.L) // buckle_wavelength(rod)).__int__())
    start = max(0.7 * min(v["far_at_fc"] for v in _closed(rod, X, S["f_c"]).values()), 0.1)
    stage_push = S["stage_push"]
    if protocol == "settle":
        stage_push = 0.3
    elif protocol == "start":
        start = 0.5 * start
    t = time.perf_counter()
    res = staircase(rod, [X / L_OVER_ELL], [start], SPEED, f_c=S["f_c"], n=n, first_push=S["first_push"],
                    stage_push=stage_push, max_stages=S["max_stages"], saves_per_stage=S["saves_per_stage"],
                    damping=DAMPING, progress=True, label=f"{protocol}: ")
    lane = res["lanes"][0]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=_ROOT).stdout.strip()
    return dict(protocol=protocol, muL_over_ell=X, n=int(res["n"]), speed=SPEED, start=start, stage_push=stage_push,
                status=lane["status"], lo=lane["lo"], hi=lane["hi"], stages=len(lane["stages"]),
                steady=[(s["parameter"], s["f_in"]) for s in lane["stages"] if s["status"] == "sliding"],
                wall_s=time.perf_counter() - t, commit=commit, date=time.strftime("%Y-%m-%d"))


def main():
    protocols = sys.argv[1:] or ["settle", "start"]
    path = os.path.join(HERE, "stage_protocols.json")
    done = json.load(open(path)) if os.path.exists(path) else {}
    for p in protocols:
        done[p] = run(p)
        print(json.dumps(done[p]), flush=True)
        with open(path, "w") as fh:  # a finished protocol is never lost
            json.dump(done, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
