"""A stability map's columns searched instead of filled: in each column (one load, the grid's
amplitudes ascending) the boundary between the stable and the buckled cells found by bisection
over the grid's own amplitudes, the cells below it labelled stable and those above it buckled
without running them.

This is the map a column search gives *when every column is monotone* (stable below one
amplitude, buckled from it on), as the E3 maps are (`results/paper/e3/`: every column of the
field model's and the 3D rod's maps); a column that is not would be labelled wrongly between the
cells the search ran, so the cells it ran are marked (`ran`) and the full grid stays one option
away (`stability_map(..., fill="grid")`). Each round runs one cell per unresolved column (two in
a guessed column's first round), all columns of a round side by side as one sweep
(`combine="zip"`); a column whose run fails is run whole. About log₂(amplitudes + 1) runs per column instead of one per cell; from a guess of each
column's boundary (a cheaper model's map: `jaxrod.stability_map` guides the 3D rod's by the field
model's), about two.

Layer: above `jaxrod.sweeps`, below `jaxrod.stability_map`.
"""

from __future__ import annotations

import numpy as np

from .sweeps import SweepResult, SweepSpec, resolved, sweep

__all__ = ["search_columns"]


def search_columns(spec: SweepSpec, dF, v0, *, guess=None, fixed: dict | None = None, path: str | None = None,
                   progress: bool = True, chunk_size: int | None = None) -> SweepResult:
    """The grid `dF` × `v0` of `spec`'s sweep (as `sweep(spec, {"dF": dF, "amplitude": v0})`
    gives it) with each column's boundary found by bisection (module docstring). `v0` ascending.
    Round r's sweep is written under `path` + `_round<r>` (resumable as any sweep). Every round
    runs at the whole grid's size and step (`jaxrod.sweeps.resolved`) in chunks of `chunk_size`
    (default: the number of loads, twice that with a `guess`), so that all rounds share one
    compiled program.

    `fixed`: sweep inputs given to every run (e.g. `{"mu": 0.05}`): searches that differ only in
    them share one spec, and so one compiled program.

    `guess`: per column the index of its predicted first buckled cell (0 to len(v0), len(v0):
    none buckles; e.g. a cheaper model's map). The column's first round runs the two cells either
    side of the predicted boundary side by side (one where it says the whole column buckles, or
    none of it does), the next rounds one cell outward at steps 1, 2, 4, … until a stable and a
    buckled cell bracket the boundary, then bisection between them: one round and two runs a
    column where the guess is right.

    **Returns:** a `SweepResult` of shape (len(dF), len(v0)) whose outputs are the runs' where a
    cell ran and, where it did not, the label its column implies (`buckled`; `result` successful;
    times and amplitudes NaN, `dominant_mode` −1, `stuck` False), with the output `ran`; `meta`
    that of the first round (its step and size, used by every round), with `rounds` and `runs`."""
    dF, v0 = np.asarray(dF, float), np.asarray(v0, float)
    if np.any(np.diff(v0) <= 0):
        raise ValueError(f"v0 = {v0.tolist()!r} is invalid for a column search: expected ascending amplitudes.")
    k, m = len(dF), len(v0)
    lo, hi = np.full(k, -1), np.full(k, m)  # per column: the highest stable cell ran, the lowest buckled one
    if guess is not None:
        guess = np.asarray(guess, int)
        if guess.shape != (k,) or np.any((guess < 0) | (guess > m)):
            raise ValueError(f"guess = {guess.tolist()!r} is invalid: expected one index in [0, {m}] per load.")
    reach = np.ones((k, 2), int)  # the next outward step below / above the predicted boundary
    whole = np.zeros(k, bool)  # columns run whole after a failed run
    outputs: dict[str, np.ndarray] = {}
    ran = np.zeros((k, m), bool)
    meta, rounds = None, 0
    fixed = dict(fixed or {})
    spec = resolved(spec, {"dF": dF, "amplitude": v0, **fixed})
    chunk_size = (k if guess is None else 2 * k) if chunk_size is None else chunk_size
    while True:
        open_ = [i for i in range(k) if hi[i] - lo[i] > 1 and not whole[i]]
        per = [[(i, j) for j in _next_cells(lo[i], hi[i], m, None if guess is None else guess[i], reach[i])] for i in open_]
        # each column's first cells, then its second: a sweep deals its members to the devices in
        # turn, and a pair's lower cell (stable, run to the horizon) is the longer run
        cells = [c[r] for r in range(2) for c in per if r < len(c)]
        if not cells:  # last: every cell not yet run of the columns to be run whole
            cells = [(i, j) for i in np.flatnonzero(whole) for j in range(m) if not ran[i, j]]
            if not cells:
                break
        if progress:
            print(f"  column search, round {rounds + 1}: {len(cells)} run(s)", flush=True)
        where = None if path is None else f"{path}_round{rounds}"
        res = sweep(spec, {"dF": dF[[i for i, _ in cells]], "amplitude": v0[[j for _, j in cells]], **fixed},
                    combine="zip", path=where, progress=progress, chunk_size=chunk_size)
        if meta is None:
            meta = dict(res.meta)
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


def _next_cells(lo: int, hi: int, m: int, guess: int | None, reach) -> list[int]:
    """The next cells of a column whose highest stable run is `lo` (−1: none) and lowest buckled run
    `hi` (`m`: none): bisection without a guess or once both are known; else first the two
    cells either side of the guessed boundary (the guessed first buckled cell and the one below
    it, where they exist), then one cell outward from the side known, by `reach` (below, above),
    which doubles each time it is used."""
    if guess is None or (lo >= 0 and hi < m):
        return [(lo + hi) // 2]
    if lo < 0 and hi == m:
        return [j for j in (guess - 1, guess) if 0 <= j < m]
    if hi == m:  # stable so far: up
        j = min(lo + reach[1], m - 1)
        reach[1] *= 2
        return [j]
    j = max(hi - reach[0], 0)  # buckled so far: down
    reach[0] *= 2
    return [j]
