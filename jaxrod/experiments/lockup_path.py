"""The lock-up curve's path dependence (`jaxrod.experiments.lockup`): the staircase's steady
stage at a point's lower bound reached instead in one step from the straight rod, read by the same
verdict, as `curve.csv` rows of `protocol = single_step`; and the staircases of other stage
protocols (`studies/lockup/stage_protocols.py`: a longer settle per stage, a lower start), as rows
of their protocol with their brackets and crossings (`protocol_rows`).

Each such run is a `jaxrod lockup` command (`results/lockup/path/single_step_muL{X}_far{F}/`,
the command and its commit in `lockup.log`): the rod of the point pushed from straight against the
far load F of the base staircase's lower bound (for the lock-up length: at the lower bound's μ and
no far load). Its row says on which side of that parameter the protocol puts the quantity: a steady
slide at an entry force ≤ f_c is a lower bound (`lo` = F), anything else an upper bound (`hi` =
F), and `single_step_over_staircase` is its entry force against the staircase's at the same
parameter (`stages.csv`), so that the band between the protocols is read where both ran.
"""

from __future__ import annotations

import glob
import json
import math
import os

from .lockup_convergence import FAR, LOCK

__all__ = ["PROTOCOL", "PROTOCOLS", "protocol_rows", "single_step_rows"]

PROTOCOL = "single_step"
BASE_SPEED = 0.01
"""The push speed of the base staircases and of the single-step runs [m/s]."""
PROTOCOLS = {"settle": "staircase_settle_0.3m", "start": "staircase_start_half"}
"""The other staircases' `protocol` in `curve.csv`, by their key in `stage_protocols.json`."""


def _staircase_force(stages, varies, X, n, parameter):
    """The staircase's steady entry force [F₀] at `parameter` (the stage of that far load or μL/ℓ
    at the base speed), or NaN."""
    for s in stages:
        same_point = varies == "mu" or abs(float(s["muL_over_ell"]) - X) < 1e-9
        if (s["varies"] == varies and same_point and int(s["n_segments"]) == n and abs(float(s["push_speed"]) - BASE_SPEED) < 1e-12
                and abs(float(s["parameter"]) - parameter) <= 1e-9 * max(1.0, parameter) and s["status"] == "sliding"):
            return float(s["f_in"])
    return math.nan


def single_step_rows(out, f_c: float, stages: list) -> list:
    """The rows of the single-step runs under `out/path` (module docstring), against the
    staircases' `stages` (the rows of `stages.csv`)."""
    rows = []
    for path in sorted(glob.glob(os.path.join(out, "path", f"{PROTOCOL}_muL*", "lockup.json"))):
        with open(path) as fh:
            d = json.load(fh)
        lock = d["far_load_over_F0"] == 0.0
        X, n = d["mu_L_over_ell"], d["n_segments"]
        parameter = X if lock else d["far_load_over_F0"]
        V = d["verdict"]
        force = V["force"] or [math.nan, math.nan]
        below = V["status"] == "sliding" and force[1] <= f_c
        stair = _staircase_force(stages, "mu" if lock else "far_load", X, n, parameter)
        rows.append(dict(quantity=LOCK if lock else FAR, muL_over_ell=math.nan if lock else X, n_segments=n,
                         push_speed=d["speed"], protocol=PROTOCOL, kind="run",
                         lo=parameter if below else math.nan, hi=math.nan if below else parameter,
                         status=V["status"], entry_force_bound=f_c, L_over_ell=d["L"] / d["ell"],
                         parameter=parameter, push=d["push"], entry_force=force[1],
                         staircase_entry_force=stair, single_step_over_staircase=force[1] / stair,
                         helical_over_ell_end=d["helical_over_ell_end"], source=os.path.relpath(path, out)))
    return rows


def protocol_rows(out, f_c: float, per_wave: int) -> list:
    """The rows of the other stage protocols' staircases in `out/stage_protocols.json` (its
    `<protocol>@L<L/ℓ>` runs, every point of a rod length as a lane; `per_wave` segments per buckle
    wave, the base's), each lane's crossing of `f_c` read from its steady stages."""
    from ..lockup.staircase import crossing

    path = os.path.join(out, "stage_protocols.json")
    if not os.path.exists(path):
        return []
    with open(path) as fh:
        runs = json.load(fh)
    rows = []
    for key, run in sorted(runs.items()):
        if "@L" not in key:  # the single-lane runs at μL/ℓ = 1 that came first: the same as a lane of settle@L2
            continue
        for lane in run["lanes"]:
            lock = lane["point"] == "lock"
            got = crossing([dict(parameter=p, f_in=f, status="sliding") for p, f in lane["steady"]], f_c)
            rows.append(dict(quantity=LOCK if lock else FAR, muL_over_ell=math.nan if lock else float(lane["point"]),
                             n_segments=run["n"], push_speed=run["speed"], protocol=PROTOCOLS[run["protocol"]],
                             kind="run", lo=math.nan if lane["lo"] is None else lane["lo"],
                             hi=math.nan if lane["hi"] is None else lane["hi"], status=lane["status"],
                             crossing=got[0] if got else math.nan, crossing_error=got[1] if got else math.nan,
                             entry_force_bound=f_c, segments_per_wave=per_wave, L_over_ell=run["L_over_ell"],
                             stages=lane["stages"], source=f"stage_protocols.json:{key}"))
    return rows
