"""Vmapped Monte Carlo sweeps: chunked, sharded over devices, resumable, with progress.

`sweep(spec, inputs)` runs one perturbed rod per member of a batch of parameter points and
returns a [`jaxrod.SweepResult`][] of per-member arrays. Inside a chunk the members are vmapped;
each chunk's batch axis is sharded over every local device (`jax.sharding.NamedSharding` over a
one-axis `Mesh`); every chunk has the same shape (the last one is padded), so the sweep compiles
once. With a `path`, every finished chunk is written atomically and a re-run skips it.

**Multi-host use.** Start every process with `jax.distributed.initialize()` and give each one a
disjoint member range (`members=range(start, stop)`, e.g. split by `jax.process_index()`) and
its own `path`; results depend only on the global member index (random keys are
`fold_in(key(seed), index)`), so the parts concatenate into the single-host result
(`SweepResult.concatenate`). Within a process the chunk is sharded over its local devices.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import os
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from ._results import RESULTS
from .integrators import ProjectedVerlet
from .batching import DEFAULT_LANES, DEFAULT_REFILL_EVERY, run_pool
from .integrators.base import RunOptions, save_grid
from .modal import dominant_mode
from .params import RodChannel
from .scene import DEFAULT_SEGMENTS, MODELS, PERTURBATIONS, Scene, default_nodes, make_perturbation
from . import theory

__all__ = ["SweepSpec", "SweepResult", "sweep", "PARAMETERS", "wilson_interval"]

ROD_FIELDS = ("L", "d", "E", "rho_v", "nu", "R", "g", "mu_s", "mu_d")
PARAMETERS = ("dF", "amplitude", "mu", "realization") + ROD_FIELDS
_STIFFNESS_FIELDS = ("L", "d", "E", "rho_v", "R", "g")  # set the step limit
OUTPUTS = ("buckled", "t_buckle", "dominant_mode", "max_theta", "final_theta", "stuck", "t_stop", "result",
           "steps")


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """Everything about a sweep except the swept values (all plain, JSON-serialisable).

    - `model`: "mode", "galerkin", "field" or "rod3d" (the full 3D rod, [`jaxrod.rod3d.Rod3D`][],
      under the dead load F⁰_m* + ΔF with friction at the contact point; `n` segments, default
      60; dt 0.5 of its explicit limit; `threshold` on max|θ| as for the other models).
    - `perturbation`: "sine", "random-velocity", "random-position" or "random-shape"
      (amplitude units as in [`jaxrod.scene.make_perturbation`][]; "random-position", a
      timed force pulse, is not available with "rod3d").
    - `mu`: friction coefficient (μ_s = μ_d) unless swept; `dF` [N], `amplitude` defaults.
    - `mode`: sine / single mode number; `n`: nodes, modes or 3D segments (`None`: the
      default for the largest load of the sweep); `dt` [s] (`None`: 0.4 of the step limit of
      the stiffest member, 0.5 for "rod3d"); `t1` [s] horizon; `threshold` [rad] buckling
      amplitude.
    - `rod`: overrides of the reference rod's fields (e.g. `{"R": 0.01}`).
    """

    model: str = "field"
    perturbation: str = "sine"
    mu: float = 0.3
    dF: float = 5.0
    amplitude: float = 0.01
    mode: int = 6
    n: int | None = None
    dt: float | None = None
    t1: float = 2.0
    threshold: float = 0.5
    duration: float = 1e-3
    rod: Mapping[str, float] = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        if self.model not in MODELS:
            raise ValueError(f"SweepSpec.model = {self.model!r} is invalid: expected one of {MODELS}.")
        if self.model == "rod3d" and self.perturbation == "random-position":
            raise ValueError("SweepSpec.perturbation = 'random-position' is not available with model 'rod3d': "
                             "expected 'sine', 'random-velocity' or 'random-shape'.")
        if self.model == "rod3d" and self.n is not None and not (isinstance(self.n, int) and self.n >= 4):
            raise ValueError(f"SweepSpec.n = {self.n!r} is invalid for model 'rod3d': expected an int >= 4 segments.")
        if self.perturbation not in PERTURBATIONS:
            raise ValueError(
                f"SweepSpec.perturbation = {self.perturbation!r} is invalid: expected one of "
                f"{PERTURBATIONS}."
            )
        if not (isinstance(self.t1, (int, float)) and self.t1 > 0):
            raise ValueError(f"SweepSpec.t1 = {self.t1!r} is invalid: expected > 0 s.")
        bad = set(self.rod) - set(ROD_FIELDS)
        if bad:
            raise ValueError(f"SweepSpec.rod has unknown field(s) {sorted(bad)}; valid: {ROD_FIELDS}.")

    def to_json(self) -> dict:
        d = dataclasses.asdict(self)
        d["rod"] = dict(self.rod)
        return d


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
        return SweepResult(inputs, outputs, tuple(shape), parts[0].names, parts[0].meta)


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
    den = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / den
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / den
    return centre - half, centre + half


# -- building the member function -----------------------------------------------------------------

def _member_rod(spec: SweepSpec, p: Mapping[str, jax.Array]) -> RodChannel:
    base = RodChannel.reference(mu=spec.mu, **spec.rod)
    vals = {f: getattr(base, f) for f in ROD_FIELDS}
    if "mu" in p:
        vals["mu_s"] = vals["mu_d"] = p["mu"]
    for f in ROD_FIELDS:
        if f in p:
            vals[f] = p[f]
    return RodChannel(**vals)


def _valid(rod: RodChannel, p) -> jax.Array:
    pos = [rod.L, rod.d, rod.E, rod.rho_v, rod.R, rod.g]
    ok = jnp.all(jnp.stack([jnp.isfinite(x) & (x > 0) for x in pos]))
    ok &= (rod.nu > -1) & (rod.nu < 0.5)
    ok &= jnp.isfinite(rod.mu_s) & jnp.isfinite(rod.mu_d) & (rod.mu_d >= 0) & (rod.mu_d <= rod.mu_s)
    for k in ("dF", "amplitude"):
        if k in p:
            ok &= jnp.isfinite(p[k])
    if "amplitude" in p:
        ok &= p["amplitude"] >= 0
    return ok


def _member_inputs(spec: SweepSpec, p, index, base_key):
    """A member's validity flag, its rod (the reference rod where invalid, so that an invalid
    member stays finite and cannot disturb the batch; it is flagged afterwards), ΔF, amplitude
    and random key."""
    rod = _member_rod(spec, p)
    ok = _valid(rod, p)
    safe = jax.tree_util.tree_map(
        lambda x, r: jnp.where(ok, x, r), rod, RodChannel.reference(mu=spec.mu, **spec.rod)
    )
    dF = jnp.where(ok, p.get("dF", spec.dF), spec.dF)
    amp = jnp.where(ok, p.get("amplitude", spec.amplitude), spec.amplitude)
    return ok, safe, dF, amp, jax.random.fold_in(base_key, index)


N_SAVE = 201  # the stick test runs at every save, so a stuck member stops within t1/200


def _engine_member(spec: SweepSpec, n: int | None, dt: float, grid_dt: float):
    """A member in three pure parts: `setup(params, index, base_key)` gives its model and its
    [`RunState`][jaxrod.integrators.base.RunState] at t = 0, the fixed-step engine advances it
    (`advance`, `finished`), `outputs(ok, model, run)` summarises it. Every model, 3D included."""
    integrator = ProjectedVerlet(dt)
    opts = RunOptions(buckle_threshold=spec.threshold, save_state=False)
    m, h = save_grid(spec.t1, N_SAVE, dt)

    def setup(p, index, base_key):
        ok, safe, dF, amp, key = _member_inputs(spec, p, index, base_key)
        pert = make_perturbation(spec.perturbation, amp, spec.mode, key, spec.duration)
        scene = Scene(safe, dF, pert, spec.model, n, spec.mode, dt, threshold=spec.threshold,
                      grid_dt=grid_dt)
        model = scene.model()
        q0, v0 = scene.initial_state()
        return ok, model, integrator.start(model, q0, v0, opts)

    def advance(model, run):
        return integrator.advance(model, run, jnp.asarray(h, run.t.dtype), m, N_SAVE, opts)

    def finished(run):
        return run.finished(N_SAVE)

    def outputs(ok, model, run):
        if spec.model == "field":
            dom = dominant_mode(run.q)
        elif spec.model == "rod3d":
            dom = dominant_mode(model.theta(run.q.x)[1:-1])
        elif spec.model == "galerkin":
            dom = jnp.argmax(jnp.abs(run.q)) + 1
        else:
            dom = jnp.asarray(spec.mode)
        code = integrator.result(model, run, jnp.asarray(h, run.t.dtype))
        result = jnp.where(ok & model.check(), code, RESULTS.invalid_input).astype(jnp.int32)
        return {
            "buckled": run.buckled & (result == 0),
            "t_buckle": run.t_buckle,
            "dominant_mode": dom.astype(jnp.int32),
            "max_theta": run.amp_max,
            "final_theta": model.amplitude(run.q),
            "stuck": run.stuck,
            "t_stop": run.stop_time(spec.t1, N_SAVE),
            "result": result,
            "steps": run.steps,
        }

    return setup, advance, finished, outputs


def _make_member(spec: SweepSpec, n: int | None, dt: float, grid_dt: float):
    """The pure per-member function `member(params, index, base_key) -> outputs` (one whole run:
    the "chunk" scheduling, and single runs)."""
    setup, advance, finished, outputs = _engine_member(spec, n, dt, grid_dt)

    m, _ = save_grid(spec.t1, N_SAVE, dt)

    def member(p, index, base_key):
        ok, model, run = setup(p, index, base_key)
        interval = lambda r: jax.lax.fori_loop(0, m, lambda _, r: advance(model, r), r)
        return outputs(ok, model, jax.lax.while_loop(lambda r: ~finished(r), interval, run))

    return member


# -- the sweep -----------------------------------------------------------------------------------

def _expand(inputs: Mapping[str, object], combine: str):
    names = tuple(inputs)
    arrays = []
    for k in names:
        a = np.asarray(inputs[k], dtype=float)
        if a.ndim > 1:
            raise ValueError(f"input {k!r} has shape {a.shape}: expected a scalar or a 1-D array.")
        arrays.append(np.atleast_1d(a))
    if combine == "grid":
        shape = tuple(len(a) for a in arrays)
        mesh = np.meshgrid(*arrays, indexing="ij")
        flat = {k: m.ravel() for k, m in zip(names, mesh)}
    elif combine == "zip":
        lens = {len(a) for a in arrays} - {1}
        if len(lens) > 1:
            raise ValueError(
                "zipped inputs must have equal lengths (or length 1); got "
                + ", ".join(f"{k}: {len(a)}" for k, a in zip(names, arrays))
            )
        n = lens.pop() if lens else 1
        shape = (n,)
        flat = {k: np.broadcast_to(a, (n,)).copy() for k, a in zip(names, arrays)}
    else:
        raise ValueError(f"combine = {combine!r} is invalid: expected 'grid' or 'zip'.")
    return flat, shape, names


def _static_resolution(spec: SweepSpec, flat: dict[str, np.ndarray]):
    """n and dt from the concrete inputs: the largest load sets n, the stiffest valid member dt.
    Depends only on the spec, the distinct stiffness values and the largest ΔF, and is cached
    on them (it evaluates the models eagerly: a few ms, much of a small sweep)."""
    stiff = [f for f in _STIFFNESS_FIELDS if f in flat]
    values = np.unique(np.stack([np.asarray(flat[f], float) for f in stiff], -1), axis=0) if stiff else None
    dF = flat.get("dF", np.array([spec.dF]))
    dF_max = float(np.nanmax(np.where(np.isfinite(dF), dF, -np.inf)))
    key = None if values is None else tuple(map(tuple, values.tolist()))
    return _resolution(json.dumps(spec.to_json(), sort_keys=True), tuple(stiff), key, dF_max)


@functools.lru_cache(maxsize=64)
def _resolution(spec_json: str, stiff: tuple[str, ...], values, dF_max: float):
    import jax.numpy as jnp_

    spec = SweepSpec(**json.loads(spec_json))

    def rod_of(row):
        try:
            return RodChannel.reference(mu=spec.mu, **{**dict(spec.rod), **dict(zip(stiff, row))})
        except ValueError:
            return None

    if values is not None:
        rods = [r for r in map(rod_of, values) if r is not None]
    else:
        rods = [RodChannel.reference(mu=spec.mu, **spec.rod)]
    if not rods:
        raise ValueError("no member of the sweep has valid rod parameters.")
    n = spec.n
    if spec.model == "field" and n is None:
        n = max(default_nodes(r, theory.frictionless_load(r, theory.critical_mode(r)) + dF_max) for r in rods)
    if spec.model == "galerkin" and n is None:
        n = 32
    if spec.model == "rod3d":
        return _rod3d_resolution(spec, rods, dF_max)
    dt = spec.dt
    if dt is None:
        dt = min(Scene(r, jnp_.asarray(dF_max), kind=spec.model, n=n, mode=spec.mode).step() for r in rods)
    grid_dt = min(Scene(r, jnp_.asarray(dF_max), kind="field", n=128).step() for r in rods)
    return n, float(dt), float(grid_dt)


def _rod3d_resolution(spec: SweepSpec, rods, dF_max: float):
    """n (default 60 segments, E1/E6's) and dt: 0.5 of the smallest explicit limit over the
    rods at the largest load (a given `spec.dt` must lie below it)."""
    from .rod3d.model import Rod3D, step_limit

    n = spec.n or DEFAULT_SEGMENTS
    limits = []
    for r in rods:
        F = float(theory.frictionless_load(r, theory.critical_mode(r))) + dF_max
        limits.append(step_limit(Rod3D(r, n, control="load", end_load=F)))
    limit = min(limits)
    if spec.dt is not None and not (0 < spec.dt < limit):
        raise ValueError(f"SweepSpec.dt = {spec.dt!r} s is invalid for model 'rod3d': the explicit step limit "
                         f"is {limit:.4g} s; use 0 < dt < {limit:.4g} s.")
    return n, float(spec.dt or 0.5 * limit), 0.0


def _fingerprint(meta: dict) -> str:
    keep = {k: meta[k] for k in ("spec", "names", "shape", "combine", "seed", "n", "dt", "dtype", "members")}
    keep["inputs"] = {k: np.asarray(v).tolist() for k, v in meta["_inputs"].items()}
    return hashlib.sha256(json.dumps(keep, sort_keys=True, default=str).encode()).hexdigest()


def _meta_file(path):
    return os.path.join(path, "sweep.json")


def _chunk_file(path, c):
    return os.path.join(path, f"chunk_{c:05d}.npz")


def _read_meta(path):
    f = _meta_file(path)
    if not os.path.exists(f):
        return None
    with open(f) as fh:
        return json.load(fh)


def _atomic_write(path: str, write: Callable[[str], None], suffix: str) -> None:
    d = os.path.dirname(path)
    fd, tmp = tempfile.mkstemp(dir=d, prefix=".tmp_", suffix=suffix)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _bytes_per_member(spec: SweepSpec, n: int | None) -> int:
    dof = n or 1
    if spec.model == "rod3d":
        dof = 20 * (n + 1)  # positions, velocities, rotations, forces, caches per node
    # state, velocity, acceleration, trial velocities, stencil temporaries, per-save records
    return 8 * (24 * dof + 64) + 4096


def sweep(
    spec: SweepSpec,
    inputs: Mapping[str, object],
    *,
    combine: str = "grid",
    seed: int = 0,
    path: str | None = None,
    chunk_size: int | None = None,
    memory_mb: float = 256.0,
    members: range | None = None,
    progress: bool = True,
    on_chunk: Callable[[int], None] | None = None,
    scheduling: str = "pool",
    lanes: int = DEFAULT_LANES,
    refill_every: int = DEFAULT_REFILL_EVERY,
) -> SweepResult:
    """Run one rod per member of `inputs` and collect per-member results.

    **Arguments:**

    - `spec`: a [`jaxrod.SweepSpec`][] (model, perturbation kind, horizon, fixed values).
    - `inputs`: swept values by name, each a scalar or 1-D array. Names: `dF` [N],
      `amplitude` (units of the perturbation), `mu` (μ_s = μ_d), `realization` (any labels: a
      random ensemble, each member getting its own key), and any [`jaxrod.RodChannel`][] field.
    - `combine`: `"grid"` (outer product, first name = first axis) or `"zip"` (elementwise,
      length-1 inputs broadcast).
    - `seed`: base seed; member i's key is `fold_in(key(seed), i)` for its global index i, so
      results do not depend on the chunk size or the number of devices.
    - `path`: a folder for the results; finished chunks are written atomically
      (`chunk_XXXXX.npz`, with `sweep.json` holding all metadata) and skipped on a re-run. A
      different sweep at the same path is refused.
    - `chunk_size`: members per chunk (rounded up to a multiple of the device count); default
      from `memory_mb`, at most 1024 (larger chunks wait longer for their slowest member).
    - `members`: a sub-range of global member indices to run (multi-host splitting).
    - `progress`: show a progress bar (members, members/s); `on_chunk(c)`: called after
      chunk c is finished (and written).
    - `scheduling`: `"pool"` (default): continuous batching — each device runs `lanes` members
      side by side and a lane whose member has stopped takes the next pending one every
      `refill_every` steps, inside one compiled loop ([`jaxrod.batching.run_pool`][]);
      `"chunk"`: the whole chunk vmapped at once, running until its slowest member stops
      (kept for comparison). Results are identical either way.

    **Returns:** a [`jaxrod.SweepResult`][].

    **Raises:** `ValueError` for unknown names, bad shapes or a mismatched resume — before
    any member runs. Bad *values* never raise: those members get a result code.
    """
    if not isinstance(spec, SweepSpec):
        raise TypeError(f"spec must be a SweepSpec, got {type(spec).__name__}.")
    unknown = set(inputs) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"unknown sweep parameter(s) {sorted(unknown)}; valid names: {PARAMETERS}.")
    if not inputs:
        raise ValueError("inputs is empty: give at least one swept parameter.")
    if "mu" in inputs and ({"mu_s", "mu_d"} & set(inputs)):
        raise ValueError("give either 'mu' or 'mu_s'/'mu_d', not both.")
    flat, shape, names = _expand(inputs, combine)
    total = int(np.prod(shape))
    members = range(total) if members is None else members
    if members.start < 0 or members.stop > total or members.step != 1:
        raise ValueError(f"members = {members!r} is invalid: expected a contiguous range within [0, {total}).")
    n, dt, grid_dt = _static_resolution(spec, flat)
    n_dev = jax.local_device_count()
    if chunk_size is None:
        chunk_size = int(max(1, min(1024, memory_mb * 2**20 // _bytes_per_member(spec, n))))
    if not (isinstance(chunk_size, int) and chunk_size >= 1):
        raise ValueError(f"chunk_size = {chunk_size!r} is invalid: expected an int >= 1.")
    if scheduling not in ("pool", "chunk"):
        raise ValueError(f"scheduling = {scheduling!r} is invalid: expected 'pool' or 'chunk'.")
    for name, val in (("lanes", lanes), ("refill_every", refill_every)):
        if not (isinstance(val, int) and val >= 1):
            raise ValueError(f"{name} = {val!r} is invalid: expected an int >= 1.")
    index = np.arange(members.start, members.stop)
    chunk_size = math.ceil(min(chunk_size, len(index)) / n_dev) * n_dev
    sel = {k: v[index] for k, v in flat.items()}
    dtype = str(jnp.result_type(float))
    meta = {
        "spec": spec.to_json(),
        "names": list(names),
        "shape": list(shape),
        "full_shape": list(shape),
        "combine": combine,
        "seed": seed,
        "n": n,
        "dt": dt,
        "dtype": dtype,
        "members": [members.start, members.stop],
        "chunk_size": chunk_size,
        "jaxrod": _version(),
        "jax": jax.__version__,
        "devices": [str(d) for d in jax.local_devices()],
        "_inputs": {**{k: v.tolist() for k, v in sel.items()}, "index": index.tolist()},
    }
    if members != range(total):
        meta["shape"] = [len(index)]
    meta["fingerprint"] = _fingerprint(meta)
    if path is not None:
        os.makedirs(path, exist_ok=True)
        old = _read_meta(path)
        if old is not None:
            if old.get("fingerprint") != meta["fingerprint"]:
                raise ValueError(
                    f"{path!r} holds a different sweep (its spec, inputs, seed or resolution "
                    "differ); refusing to mix results. Use another path or delete it."
                )
            chunk_size = old["chunk_size"]
            meta["chunk_size"] = chunk_size
        else:
            _atomic_write(_meta_file(path), lambda f: _dump_json(meta, f), ".json")

    spec_json = json.dumps(spec.to_json(), sort_keys=True)
    if scheduling == "pool":
        run_chunk = _pool_runner(spec_json, n, dt, grid_dt, lanes, refill_every)
    else:
        run_chunk = _chunk_runner(spec_json, n, dt, grid_dt)
    base_key = jax.random.key(seed)
    mesh = jax.sharding.Mesh(np.asarray(jax.local_devices()), ("batch",))
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch"))
    lane_steps = 0

    outputs = {k: np.full(len(index), _FILL[k]) for k in OUTPUTS}
    n_chunks = math.ceil(len(index) / chunk_size)
    bar = _progress(len(index), progress)
    for c in range(n_chunks):
        lo, hi = c * chunk_size, min((c + 1) * chunk_size, len(index))
        f = _chunk_file(path, c) if path is not None else None
        if f is not None and os.path.exists(f):
            with np.load(f) as z:
                for k in OUTPUTS:
                    if k in z:
                        outputs[k][lo:hi] = z[k]
            bar.update(hi - lo, skipped=True)
            continue
        pad = chunk_size - (hi - lo)
        # deal the chunk's members to the devices in turn (member j to device j mod D): the
        # members of one region of a grid take similar times, so contiguous shares would leave
        # one device with most of the work (61 % / 39 % on the default map at μ = 0.3)
        deal = np.arange(chunk_size).reshape(-1, n_dev).T.ravel()
        params = {
            k: jax.device_put(np.pad(v[lo:hi], (0, pad), mode="edge").astype(dtype)[deal], sharding)
            for k, v in sel.items()
        }
        idx = jax.device_put(np.pad(index[lo:hi], (0, pad), mode="edge")[deal], sharding)
        valid = jax.device_put((np.arange(chunk_size) < hi - lo)[deal], sharding)
        out = jax.device_get(run_chunk(params, idx, valid, base_key))
        lane_steps += int(np.sum(out.pop("lane_steps", 0)))
        undeal = np.argsort(deal)
        chunk_out = {k: np.asarray(out[k])[undeal][: hi - lo] for k in OUTPUTS}
        for k in OUTPUTS:
            outputs[k][lo:hi] = chunk_out[k]
        if f is not None:
            _atomic_write(f, lambda t: np.savez(t, **chunk_out), ".npz")
        bar.update(hi - lo)
        if on_chunk is not None:
            on_chunk(c)
    bar.close()
    inputs_out = {**sel, "index": index}
    result = SweepResult(inputs_out, outputs, tuple(meta["shape"]), names, meta)
    # how this call used its lanes (not part of the results, nor of the resume fingerprint)
    member_steps = int(np.sum(np.where(outputs["steps"] > 0, outputs["steps"], 0)))
    result.meta = {**meta, "scheduling": scheduling, "lanes": lanes, "refill_every": refill_every,
                   "lane_steps": lane_steps, "member_steps": member_steps}
    return result


@functools.lru_cache(maxsize=16)
def _chunk_runner(spec_json: str, n, dt, grid_dt):
    """One jitted chunk function per (spec, resolution): repeated sweeps reuse its compilation
    (the seed and all swept values are arguments, not constants)."""
    d = json.loads(spec_json)
    member = _make_member(SweepSpec(**d), n, dt, grid_dt)

    @jax.jit
    def run_chunk(params, idx, valid, base_key):
        return jax.vmap(member, in_axes=(0, 0, None))(params, idx, base_key)

    return run_chunk


@functools.lru_cache(maxsize=16)
def _pool_runner(spec_json: str, n, dt, grid_dt, lanes: int, refill_every: int):
    """One jitted chunk function with continuous batching: every device sets up its share of
    the chunk's members, runs them in `lanes` lanes ([`jaxrod.batching.run_pool`][]) and
    summarises them. Also returns the lane steps computed per device (for the utilisation)."""
    setup, advance, finished, outputs = _engine_member(SweepSpec(**json.loads(spec_json)), n, dt, grid_dt)
    mesh = jax.sharding.Mesh(np.asarray(jax.local_devices()), ("batch",))
    P = jax.sharding.PartitionSpec

    def run_chunk(params, idx, valid, base_key):
        ok, models, runs = jax.vmap(setup, in_axes=(0, 0, None))(params, idx, base_key)
        (models, runs), stats = run_pool(
            lambda mr: (mr[0], advance(*mr)), lambda mr: finished(mr[1]), (models, runs), valid,
            lanes, refill_every,
        )
        out = jax.vmap(outputs)(ok, models, runs)
        return {**out, "lane_steps": stats.lane_steps[None]}

    return jax.jit(jax.shard_map(run_chunk, mesh=mesh, in_specs=(P("batch"), P("batch"), P("batch"), P()),
                                 out_specs=P("batch"), check_vma=False))


def _dump_json(meta, f):
    with open(f, "w") as fh:
        json.dump(meta, fh, indent=1, default=str)


def _version() -> str:
    from ._version import __version__

    return __version__


class _progress:
    """A tqdm bar counting members, with members/s of the members run by this call (silent when
    disabled or tqdm is missing). Advances once per finished chunk."""

    def __init__(self, n_members, enabled):
        self.bar = None
        self.members = 0
        self.t0 = time.perf_counter()
        if enabled:
            try:
                from tqdm.auto import tqdm

                self.bar = tqdm(total=n_members, unit="member", desc="sweep")
            except ImportError:  # pragma: no cover
                self.bar = None

    def update(self, members, skipped=False):
        if not skipped:
            self.members += members
        if self.bar is not None:
            rate = self.members / max(time.perf_counter() - self.t0, 1e-9)
            self.bar.set_postfix_str(f"{rate:.1f} members/s" + (" (resumed)" if skipped else ""))
            self.bar.update(members)

    def close(self):
        if self.bar is not None:
            self.bar.close()
