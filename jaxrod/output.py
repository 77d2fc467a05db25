"""Host-side output shared by the experiments, the map, the figures and the CLI: figures that do
not touch pyplot's global state, and CSV files of plain numbers.

Figures are `matplotlib.figure.Figure` objects: creating one never switches the user's backend
(a notebook keeps its inline backend) and never registers it with pyplot, so nothing has to be
closed; `fig.savefig` writes it, and a notebook shows it by returning it.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["subplots", "write_csv", "plain"]


def subplots(nrows: int = 1, ncols: int = 1, *, figsize=None, **kwargs):
    """`(Figure, axes)` as `pyplot.subplots`, without pyplot."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def plain(x):
    """A value as a plain Python number for CSV and JSON: bools and integers as ints, floats as
    floats (`inf`, `nan` included), anything else unchanged."""
    if isinstance(x, (bool, np.bool_)):
        return int(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x)
    if isinstance(x, np.ndarray) and x.ndim == 0:
        return plain(x.item())
    return x


def write_csv(path: str, rows: Sequence[Mapping[str, object]]) -> None:
    """One header line (the keys of the first row), then one line per row; numbers are written
    as plain numbers (`inf` and `nan` spelled so), never as Python reprs. Nothing is written for
    no rows."""
    if not rows:
        return
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for row in rows:
            w.writerow({k: _cell(v) for k, v in row.items()})


def _cell(x):
    x = plain(x)
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x
