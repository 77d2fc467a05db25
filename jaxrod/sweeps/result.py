"""`SweepResult`: per-member arrays, grids, CSV, ensemble probabilities with Wilson intervals,
loading and joining."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence

import numpy as np

from .._results import RESULTS
from .spec import OUTPUTS
from .store import _chunk_file, _read_meta

__all__ = ['SweepResult', 'wilson_interval']


@dataclasses.dataclass
class SweepResult:
    """Per-member results of a sweep (NumPy arrays of shape (n_members,)).

    - `inputs`: the swept values per member (name → array), plus `index` (global member index).
    - `outputs`: `buckled`, `t_buckle` [s] (inf if not), `dominant_mode`, `max_theta` (largest
      max|θ| reached [rad]), `final_theta` (max|θ| at the end), `stuck` (ended stuck),
      `t_stop` [s], `result` (a [`jaxrod.RESULTS`][] code).
    - `shape`: the grid shape (`combine="grid"`) or `(n_members,)`; `names`: the swept names in
      grid-axis order; `meta`: the full metadata (spec, versions, dtype, seed, dt, n).
    """

    inputs: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    shape: tuple[int, ...]
    names: tuple[str, ...]
    meta: dict

    def __len__(self) -> int:
        return len(self.outputs["result"])

    def grid(self, name: str) -> np.ndarray:
        """An input or output reshaped to the grid."""
        arr = self.inputs[name] if name in self.inputs else self.outputs[name]
        return arr.reshape(self.shape)

    @property
    def ok(self) -> np.ndarray:
        return self.outputs["result"] == RESULTS.successful

    def to_csv(self, path: str) -> None:
        """One row per member: inputs then outputs."""
        cols = {**self.inputs, **self.outputs}
        with open(path, "w") as fh:
            fh.write(",".join(cols) + "\n")
            for i in range(len(self)):
                fh.write(",".join(_fmt(cols[k][i]) for k in cols) + "\n")

    def summary(self) -> str:
        codes, counts = np.unique(self.outputs["result"], return_counts=True)
        parts = [f"{c} {RESULTS.describe(k)}" for k, c in zip(codes, counts)]
        nb = int(np.sum(self.outputs["buckled"] & self.ok))
        return f"{len(self)} members: {nb} buckled, {int(self.ok.sum()) - nb} stable; " + ", ".join(parts)

    def probability(self, over: str = "realization", z: float = 1.96):
        """Buckling probability over the grid axis `over` (a random ensemble), with a Wilson
        confidence interval (`z` = 1.96: 95 %). Failed members are left out of the count.

        **Returns:** a dict of arrays over the remaining axes: the other inputs, `p`, `lo`,
        `hi`, `n` (members counted), `buckled`.
        """
        if over not in self.names or len(self.shape) != len(self.names):
            raise ValueError(f"over = {over!r} is not a grid axis of this sweep (axes: {self.names}).")
        ax = self.names.index(over)
        b = self.grid("buckled") & (self.grid("result") == 0)
        n = (self.grid("result") == 0).sum(axis=ax)
        k = b.sum(axis=ax)
        lo, hi = wilson_interval(k, n, z)
        out = {name: np.take(self.grid(name), 0, axis=ax) for name in self.names if name != over}
        out.update(p=np.where(n > 0, k / np.maximum(n, 1), np.nan), lo=lo, hi=hi, n=n, buckled=k)
        return out

    def to_xarray(self):
        """The result as a labelled `xarray.Dataset` (needs xarray: `pip install 'jaxrod[xarray]'`).

        A grid sweep (`combine="grid"`) has the swept names as dimensions, in grid-axis order,
        with their values as coordinates; every output, and every input that is not an axis
        (`index`), is a variable on those dimensions. A zipped sweep has one `member`
        dimension with the inputs as coordinates. `attrs` hold the sweep's metadata (nested
        values as JSON text)."""
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("SweepResult.to_xarray needs xarray: pip install 'jaxrod[xarray]'") from None
        import json

        if self.names and len(self.shape) == len(self.names):
            dims = tuple(self.names)
            coords = {}
            for ax, name in enumerate(dims):
                at = [0] * len(dims)
                at[ax] = slice(None)
                coords[name] = self.grid(name)[tuple(at)]
            data = {k: (dims, self.grid(k)) for k in self.outputs}
            data.update({k: (dims, self.grid(k)) for k in self.inputs if k not in dims})
        else:
            coords = {k: ("member", v) for k, v in self.inputs.items()}
            data = {k: ("member", v) for k, v in self.outputs.items()}
        attrs = {k: v if isinstance(v, (str, int, float)) else json.dumps(v, default=str)
                 for k, v in self.meta.items() if not k.startswith("_")}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def load(cls, path: str) -> SweepResult:
        """Load a sweep written with `sweep(..., path=path)` (finished chunks only)."""
        meta = _read_meta(path)
        if meta is None:
            raise FileNotFoundError(f"no sweep metadata at {path!r}")
        inputs = {k: np.asarray(v) for k, v in meta.pop("_inputs").items()}
        n = len(inputs["index"])
        outputs = {k: np.full(n, _FILL[k]) for k in OUTPUTS}
        cs = meta["chunk_size"]
        for c in range(math.ceil(n / cs)):
            f = _chunk_file(path, c)
            if os.path.exists(f):
                with np.load(f) as z:
                    for k in OUTPUTS:
                        if k in z:  # "steps" is absent from sweeps written before it existed
                            outputs[k][c * cs : c * cs + len(z["result"])] = z[k]
        return cls(inputs, outputs, tuple(meta["shape"]), tuple(meta["names"]), meta)

    @staticmethod
    def concatenate(parts: Sequence[SweepResult]) -> SweepResult:
        """Join results of disjoint member ranges (e.g. from several hosts), by global index."""
        idx = np.concatenate([p.inputs["index"] for p in parts])
        order = np.argsort(idx)
        inputs = {k: np.concatenate([p.inputs[k] for p in parts])[order] for k in parts[0].inputs}
        outputs = {k: np.concatenate([p.outputs[k] for p in parts])[order] for k in parts[0].outputs}
        shape = parts[0].meta.get("full_shape", (len(idx),))
        # the joined result's own extent, not the first part's
        meta = {**parts[0].meta, **({"shape": list(shape)} if "shape" in parts[0].meta else {}),
                **({"members": [int(idx.min()), int(idx.max()) + 1]} if "members" in parts[0].meta else {})}
        return SweepResult(inputs, outputs, tuple(shape), parts[0].names, meta)


_FILL = {
    "buckled": False, "t_buckle": np.inf, "dominant_mode": 0, "max_theta": np.nan,
    "final_theta": np.nan, "stuck": False, "t_stop": np.nan, "result": -1, "steps": -1,
}


def _fmt(x) -> str:
    if isinstance(x, (bool, np.bool_)):
        return str(int(x))
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return repr(float(x))


def wilson_interval(k, n, z: float = 1.96):
    """Wilson score interval (lo, hi) for a binomial proportion k/n (elementwise)."""
    k, n = np.asarray(k, float), np.asarray(n, float)
    p = np.where(n > 0, k / np.maximum(n, 1), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):  # n = 0 (every member failed): NaN, silently
        den = 1 + z**2 / n
        centre = (p + z**2 / (2 * n)) / den
        half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / den
    return centre - half, centre + half

