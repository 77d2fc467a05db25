"""The lock-up curve's path band: the staircase for F_far,max(6 F₀) (and for the lock-up length
μL_lock(6 F₀)/ℓ) run again with other stage protocols, at every point of the curve, in the base
setting of `jaxrod reproduce lockup` (r/ℓ = 0.02, 16 segments per buckle wave, 10 mm/s; one
staircase per rod length, its points as lanes, as the command runs them: L = 2ℓ for μL/ℓ = 0.5, 1,
1.5, 2; L = 4ℓ for μL/ℓ = 3 and the lock-up lane) —

- `settle`: each stage pushed 0.3 m instead of 0.15 m (a longer settle at each far load);
- `start`: the staircase started at half the base's first far load (or, for the lock-up lane, half
  its first μ), so that it climbs through other loads; 24 stages at most instead of 16;

beside the base staircase's bracket (`results/lockup/curve.csv`). Writes stage_protocols.json in
results/lockup/ (the folder of this study under results/), with the commit that ran it; the keys
`settle` and `start` hold the single-lane runs at μL/ℓ = 1 (53ca218), `settle@L2` … `start@L4` the
lanes of every point.

    python studies/lockup/stage_protocols.py [settle|start ...] [--L 2|4]   # 10-25 min a run, one core
"""

import argparse
import json
import math
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/

from jaxrod.experiments.lockup import DAMPING, R_OVER_ELL, SETTINGS, _closed  # noqa: E402
from jaxrod.lockup.push import buckle_wavelength, push_rod  # noqa: E402
from jaxrod.lockup.staircase import staircase  # noqa: E402

GROUPS = {2.0: ((0.5, 1.0, 1.5, 2.0), False), 4.0: ((3.0,), True)}  # L/ℓ: (far-load lanes' μL/ℓ, a lock-up lane)
PER_WAVE, SPEED = 16, 10e-3


def run(protocol: str, Lx: float) -> dict:
    """One staircase of `protocol` over the points on L = `Lx` ℓ, lanes as `jaxrod reproduce lockup`'s
    base job (`jaxrod.experiments.lockup._job`) with the protocol's change."""
    S = SETTINGS[False]
    Xs, lock = GROUPS[Lx]
    rod = push_rod(Lx, R_OVER_ELL, 1.0)
    n = max(8, math.ceil(PER_WAVE * float(rod.L) / buckle_wavelength(rod)))
    locks = [0.8 * min(v["lock_at_fc"] for v in _closed(rod, 1.0, S["f_c"]).values())] if lock else []
    starts = [max(0.7 * min(v["far_at_fc"] for v in _closed(rod, X, S["f_c"]).values()), 0.1) for X in Xs]
    stage_push, max_stages = S["stage_push"], S["max_stages"]
    if protocol == "settle":
        stage_push = 0.3
    elif protocol == "start":
        starts = [0.5 * s for s in starts]
        locks = [0.5 * x for x in locks]
        max_stages = 24
    else:
        raise ValueError(f"protocol = {protocol!r} is invalid: expected 'settle' or 'start'.")
    mus = [X / Lx for X in (*Xs, *locks)]
    vary = [False] * len(Xs) + [True] * len(locks)
    t = time.perf_counter()
    res = staircase(rod, mus, starts + [0.0] * len(locks), SPEED, f_c=S["f_c"], vary_mu=vary, n=n,
                    first_push=S["first_push"], stage_push=stage_push, max_stages=max_stages,
                    saves_per_stage=S["saves_per_stage"], damping=DAMPING, progress=True, label=f"{protocol}@L{Lx:g}: ")
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=_ROOT).stdout.strip()
    lanes = [dict(point="lock" if vary[k] else mus[k] * Lx, start=(locks[0] * 1.0 if vary[k] else starts[k]),
                  status=lane["status"], lo=lane["lo"], hi=lane["hi"], stages=len(lane["stages"]),
                  steady=[(s["parameter"], s["f_in"]) for s in lane["stages"] if s["status"] == "sliding"])
             for k, lane in enumerate(res["lanes"])]
    return dict(protocol=protocol, L_over_ell=Lx, n=int(res["n"]), speed=SPEED, stage_push=stage_push,
                max_stages=max_stages, lanes=lanes, wall_s=time.perf_counter() - t, commit=commit,
                date=time.strftime("%Y-%m-%d"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("protocols", nargs="*", default=["settle", "start"])
    ap.add_argument("--L", type=float, action="append", help="rod lengths L/ℓ to run (default: 2 and 4)")
    a = ap.parse_args()
    path = os.path.join(HERE, "stage_protocols.json")
    for Lx in a.L or sorted(GROUPS):
        for p in a.protocols:
            done = json.load(open(path)) if os.path.exists(path) else {}
            done[f"{p}@L{Lx:g}"] = run(p, Lx)
            print(json.dumps(done[f"{p}@L{Lx:g}"])[:400], flush=True)
            with open(path, "w") as fh:  # a finished run is never lost
                json.dump(done, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
