"""The resolution of each reproduction setting: full, `quick` and the test suite's `tiny`."""

from __future__ import annotations


import numpy as np



def _settings(quick) -> dict:
    if quick == "tiny":  # for the test suite: structure, not accuracy
        return dict(n=24, mus=np.array([0.1, 0.4, 1.0]), realizations=2, map_dF=(0.5, 64.0, 4),
                    map_v0=(1e-3, 0.2, 5), t1=0.3, max_dF=300.0)
    if quick:
        return dict(n=48, mus=np.geomspace(0.05, 1.0, 4), realizations=3, map_dF=(0.5, 64.0, 8),
                    map_v0=(1e-3, 0.2, 10), t1=0.3, max_dF=300.0)
    return dict(n=None, mus=np.geomspace(0.05, 1.0, 8), realizations=8, map_dF=(0.5, 64.0, 20),
                map_v0=(1e-3, 0.2, 24), t1=0.5, max_dF=300.0)

