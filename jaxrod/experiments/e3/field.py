"""E3: the stability map and its boundary exponent."""

from __future__ import annotations


import numpy as np

from .._settings import _settings

__all__ = ['e3']


def e3(out, quick, progress):
    from ...stability_map import stability_map

    s = _settings(quick)
    lo, hi, n = s["map_dF"]
    vlo, vhi, vn = s["map_v0"]
    summ = stability_map((0.3, 0.0), np.geomspace(lo, hi, n), np.geomspace(vlo, vhi, vn), "field",
                         s["n"], 6, out, progress=progress, t1=2.0)
    fric, free = summ["maps"]["0.3"], summ["maps"]["0"]
    return {
        "model": "field", "n": summ["n"], "dt": summ["dt"],
        "boundary_exponent": fric["exponent"], "boundary_exponent_stderr": fric["exponent_stderr"],
        "boundary_exponent_theory": -0.5,
        "largest_stable_dF_over_F0cr": fric["largest_stable_dF_over_F0cr"],
        "frictionless_buckles_for_every_dF_gt_0": free["buckles_for_every_dF_gt_0"],
        "frictionless_stable_points": free["stable"],
    }

