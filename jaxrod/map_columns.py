"""A stability map's columns searched instead of filled: in each column (one load, the grid's
amplitudes ascending) the boundary between the stable and the buckled cells found by bisection
over the grid's own amplitudes, the cells below it labelled stable and those above it buckled
without running them.

This is the map a column search gives *when every column is monotone* (stable below one
amplitude, buckled from it on), as the E3 maps are (`results/paper/e3/`: every column of the
field model's and the 3D rod's maps); a column that is not would be labelled wrongly between the
cells the search ran, so the cells it ran are marked (`ran`) and the full grid stays one option
away (`stability_map(..., fill="grid")`). Each round runs one cell per unresolved column, all
columns of a round side by side as one sweep (`combine="zip"`); a column whose run fails is run
whole. About log₂(amplitudes + 1) runs per column instead of one per cell.

Layer: above `jaxrod.sweeps`, below `jaxrod.stability_map`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .sweeps import SweepResult, SweepSpec, sweep

__all__ = ["search_columns"]


def search_columns(spec: SweepSpec, dF, v0, *, path: str | None = None, progress: bool = True,
                   chunk_size: int | None = None) -> SweepResult:
    """The grid `dF` × `v0` of `spec`'s sweep (as `sweep(spec, {"dF": dF, "amplitude": v0})`
    gives it) with each column's boundary found by bisection (module docstring). `v0` ascending.
    Round r's sweep is written under `path` + `_round<r>` (resumable as any sweep).

    **Returns:** a `SweepResult` of shape (len(dF), len(v0)) whose outputs are the runs' where a
    cell ran and, where it did not, the label its column implies (`buckled`; `result` successful;
    times and amplitudes NaN, `dominant_mode` −1, `stuck` False), with the output `ran`; `meta`
    that of the first round (its step and size, used by every round), with `rounds` and `runs`."""
    dF, v0 = np.asarray(dF, float), np.asarray(v0, float)
    if np.any(np.diff(v0) <= 0):
        raise ValueError(f"v0 = {v0.tolist()!r} is invalid for a column search: expected ascending amplitudes.")
    k, m = len(dF), len(v0)
    lo, hi = np.full(k, -1), np.full(k, m)  # per column: the highest stable cell ran, the lowest buckled one
    whole = np.zeros(k, bool)  # columns run whole after a failed run
    outputs: dict[str, np.ndarray] = {}
    ran = np.zeros((k, m), bool)
    meta, rounds = None, 0
    while True:
        open_ = [i for i in range(k) if hi[i] - lo[i] > 1 and not whole[i]]
        cells = [(i, (lo[i] + hi[i]) // 2) for i in open_]
        if not cells:  # last: every cell not yet run of the columns to be run whole
            cells = [(i, j) for i in np.flatnonzero(whole) for j in range(m) if not ran[i, j]]
            if not cells:
                break
        if progress:
            print(f"  column search, round {rounds + 1}: {len(cells)} run(s)", flush=True)
        where = None if path is None else f"{path}_round{rounds}"
        res = sweep(spec, {"dF": dF[[i for i, _ in cells]], "amplitude": v0[[j for _, j in cells]]}, combine="zip",
                    path=where, progress=progress, chunk_size=chunk_size)
        if meta is None:  # every later round at the first round's size and step (its largest load is the grid's)
            meta = dict(res.meta)
            spec = dataclasses.replace(spec, n=meta["n"], dt=meta["dt"])
            for name, a in res.outputs.items():
                outputs[name] = np.zeros((k, m), a.dtype)
        for q, (i, j) in enumerate(cells):
            for name in outputs:
                outputs[name][i, j] = res.outputs[name][q]
            ran[i, j] = True
            if res.outputs["result"][q] != 0:
                whole[i] = True
            elif res.outputs["buckled"][q]:
                hi[i] = min(hi[i], j)
            else:
                lo[i] = max(lo[i], j)
        rounds += 1
    inferred = ~ran
    cols = np.arange(m)[None, :]
    outputs["buckled"] = np.where(inferred, cols >= hi[:, None], outputs["buckled"])
    for name, fill in (("t_buckle", np.nan), ("max_theta", np.nan), ("final_theta", np.nan), ("t_stop", np.nan),
                       ("dominant_mode", -1), ("stuck", False), ("result", 0)):
        if name in outputs:
            outputs[name] = np.where(inferred, np.asarray(fill).astype(outputs[name].dtype), outputs[name])
    outputs["ran"] = ran
    grid_dF, grid_v0 = np.meshgrid(dF, v0, indexing="ij")
    inputs = {"dF": grid_dF.reshape(-1), "amplitude": grid_v0.reshape(-1), "index": np.arange(k * m)}
    meta.update(shape=[k, m], rounds=rounds, runs=int(ran.sum()), fill="search")
    return SweepResult(inputs, {name: a.reshape(-1) for name, a in outputs.items()}, (k, m), ("dF", "amplitude"), meta)
