"""The lock-up curve's speed convergence where v/2 against v/4 failed: μL/ℓ = 1.5 (L = 2ℓ,
μ = 0.75, r/ℓ = 0.02, 16 segments per buckle wave) at an eighth of the base push speed
(1.25 mm/s), one lane, the staircase of `jaxrod reproduce lockup` otherwise unchanged, beside its
10, 5 and 2.5 mm/s brackets in `results/lockup/curve.csv`. Writes slower_push.json in
results/lockup/ with the commit that ran it.

    python studies/lockup/slower_push.py [muL_over_ell]   # about 30 min on one core
"""

import json
import math
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

L_OVER_ELL, PER_WAVE, SPEED = 2.0, 16, 1.25e-3


def run(X: float) -> dict:
    S = SETTINGS[False]
    rod = push_rod(L_OVER_ELL, R_OVER_ELL, 1.0)
    n = max(8, math.ceil(PER_WAVE * float(rod.L) / buckle_wavelength(rod)))
    start = max(0.7 * min(v["far_at_fc"] for v in _closed(rod, X, S["f_c"]).values()), 0.1)
    t = time.perf_counter()
    res = staircase(rod, [X / L_OVER_ELL], [start], SPEED, f_c=S["f_c"], n=n, first_push=S["first_push"],
                    stage_push=S["stage_push"], max_stages=S["max_stages"], saves_per_stage=S["saves_per_stage"],
                    damping=DAMPING, progress=True, label=f"muL {X:g}, v/8: ")
    lane = res["lanes"][0]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=_ROOT).stdout.strip()
    return dict(muL_over_ell=X, n=int(res["n"]), speed=SPEED, start=start, status=lane["status"], lo=lane["lo"],
                hi=lane["hi"], stages=len(lane["stages"]),
                steady=[(s["parameter"], s["f_in"]) for s in lane["stages"] if s["status"] == "sliding"],
                wall_s=time.perf_counter() - t, commit=commit, date=time.strftime("%Y-%m-%d"))


def main():
    X = float(sys.argv[1]) if len(sys.argv) > 1 else 1.5
    path = os.path.join(HERE, "slower_push.json")
    done = json.load(open(path)) if os.path.exists(path) else {}
    done[f"{X:g}"] = run(X)
    print(json.dumps(done[f"{X:g}"]), flush=True)
    with open(path, "w") as fh:
        json.dump(done, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
