"""Statistics over realizations, some of which may have failed (NaN)."""

from __future__ import annotations

import numpy as np

__all__ = ["finite_mean_std"]


def finite_mean_std(F, ddof: int = 1):
    """Mean and standard deviation (`ddof` as numpy's) of the finite entries along the last axis
    (the realizations whose run or search succeeded): NaN where there are none (the mean) or no
    more than `ddof` (the deviation). `np.nanmean` and `np.nanstd` without their empty-slice
    warnings."""
    F = np.asarray(F, float)
    ok = np.isfinite(F)
    count = ok.sum(axis=-1)
    mean = np.where(count > 0, np.where(ok, F, 0.0).sum(axis=-1) / np.maximum(count, 1), np.nan)
    sq = np.where(ok, (F - mean[..., None]) ** 2, 0.0).sum(axis=-1)
    return mean, np.where(count > ddof, np.sqrt(sq / np.maximum(count - ddof, 1)), np.nan)
