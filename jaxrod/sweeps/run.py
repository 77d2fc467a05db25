"""`sweep`: chunks, continuous batching on every device, resume and progress."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import os
import time
import warnings
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np

from ..batching import DEFAULT_LANES, DEFAULT_REFILL_EVERY, run_pool
from ..distributed import broadcast, gather, share
from ..registry import recipe
from .member import _engine_member, _make_member, _static_resolution, spec_of
from .result import SweepResult, _FILL
from .spec import OUTPUTS, PARAMETERS, SweepSpec
from .store import _atomic_write, _chunk_file, _dump_json, _fingerprint, _meta_file, _read_meta

__all__ = ['sweep', 'resolved']

# Lanes per device when `sweep` is not told: the 3D rod's arrays of n segments already fill the
# vector units, and a batch of them only adds memory traffic and friction sweeps run for the
# slowest lane — 64 rods on 2 devices cost 17 / 74 µs per rod-step at 60 / 500 segments in 1
# lane per device against 19 / 116 in 16 (benchmarks/README.md, "3D rod: batched rods"; the one-lane
# figures measured with an idle copy beside each run, which the pool no longer steps).


def resolved(spec: SweepSpec, inputs: Mapping[str, object], combine: str = "grid") -> SweepSpec:
    """`spec` with the size `n` and step `dt` that `sweep(spec, inputs, combine)` runs its members
    at (the largest load's size and the stiffest member's step) filled in: sweeps of parts of
    `inputs` under it run at that resolution and share one compiled program."""
    flat, _, _ = _expand(inputs, combine)
    n, dt, _, _ = _static_resolution(spec, flat)
    return dataclasses.replace(spec, n=n, dt=dt)


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


def _bytes_per_member(spec: SweepSpec, n: int | None) -> int:
    return recipe(spec.model).bytes_per_member(n)


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
    lanes: int | None = None,
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
      (`chunk_XXXXX.npz`, with `sweep.json` holding all metadata) and skipped on a re-run, with
      any number of processes or devices (the chunk layout is the first run's). A different
      sweep at the same path is refused.
    - `chunk_size`: members per chunk (rounded up to a multiple of the device count); default
      from `memory_mb`, at most 1024 (larger chunks wait longer for their slowest member). The
      unit of work dealt to the processes of a distributed run. A chunk is cut to the members
      there are, except a given `chunk_size` under `"pool"`: the chunk is padded to it, within
      `memory_mb` (the pool never runs the padding), so sweeps of up to that many members share
      one compiled program.
    - `members`: a sub-range of global member indices to run.
    - `progress`: show a progress bar (members, members/s); `on_chunk(c)`: called after
      chunk c is finished (and written).
    - `scheduling`: `"pool"` (default): continuous batching — each device runs `lanes` members
      side by side and a lane whose member has stopped takes the next pending one every
      `refill_every` steps, inside one compiled loop ([`jaxrod.batching.run_pool`][]);
      `lanes` defaults to 16 for the reduced models and 1 for `"rod3d"` (the model's `sweep_lanes`);
      `"chunk"`: the whole chunk vmapped at once, running until its slowest member stops
      (kept for comparison). Results are identical either way, bit for bit with two lanes or
      more; one lane runs each member alone (no idle lane beside it), which XLA rounds in the
      last bit like an unbatched run: its labels and counts are the same, its numbers to
      rounding, and any chunking of a one-lane sweep gives the same bits.

    **Several processes.** Under `jax.distributed` every process makes the same call (same
    arguments; a shared `path` to keep the chunks); process 0 writes `sweep.json` and its view
    of the finished chunks is everyone's; the missing chunks are dealt to the processes in turn
    (`jaxrod.distributed.share`); each process writes its own chunks and, at the end, all of
    them exchange their new outputs (`jaxrod.distributed.gather`, which waits for every
    process), so every process returns the whole result. A member's outputs depend on its global
    index and, in the last bit of some of them, on the width of its device's share of the chunk
    (XLA compiles other widths differently): the chunk layout is the first run's whatever the
    process count, and with as many devices per process as a one-process run has, the merged
    result equals that run's bit for bit (to rounding across device counts). The default
    layout makes one chunk of up to 1024 members: pass a smaller `chunk_size` to split a
    smaller sweep. Every process needs the same number of local devices; `on_chunk` is called
    in the process that ran the chunk, and only process 0 shows progress.

    **Returns:** a [`jaxrod.SweepResult`][] (`meta["processes"]`: the process count;
    `meta["member_steps"]`: the steps the members took; `meta["lane_steps"]`: under `"pool"`,
    the lane steps computed by this call, busy or not — under `"chunk"` they are not counted
    and it is 0).

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
    n, dt, grid_dt, scheme = _static_resolution(spec, flat)
    n_dev = jax.local_device_count()
    n_proc = jax.process_count()
    given = chunk_size is not None
    budget = int(max(1, min(1024, memory_mb * 2**20 // _bytes_per_member(spec, n))))  # members in memory_mb
    if chunk_size is None:
        chunk_size = budget
    if not (isinstance(chunk_size, int) and chunk_size >= 1):
        raise ValueError(f"chunk_size = {chunk_size!r} is invalid: expected an int >= 1.")
    if scheduling not in ("pool", "chunk"):
        raise ValueError(f"scheduling = {scheduling!r} is invalid: expected 'pool' or 'chunk'.")
    # a chunk is as long as the members unless a pool's chunk size was given: padding is free
    # there (a pool never runs it), and sweeps of fewer members then reuse one compiled program
    keep = given and scheduling == "pool"
    if lanes is None:
        lanes = recipe(spec.model).sweep_lanes or DEFAULT_LANES
    for name, val in (("lanes", lanes), ("refill_every", refill_every)):
        if not (isinstance(val, int) and val >= 1):
            raise ValueError(f"{name} = {val!r} is invalid: expected an int >= 1.")
    index = np.arange(members.start, members.stop)
    target = min(chunk_size, len(index))
    if keep:  # padded up to the given size, within the memory budget
        target = max(target, min(chunk_size, budget))
    chunk_size = math.ceil(target / n_dev) * n_dev
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
        "scheme": scheme,
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
        old = _read_meta(path)  # every process checks it, so that all of them refuse alike
        if old is not None:
            if old.get("fingerprint") != meta["fingerprint"]:
                raise ValueError(
                    f"{path!r} holds a different sweep (its spec, inputs, seed or resolution "
                    "differ); refusing to mix results. Use another path or delete it."
                )
            chunk_size = old["chunk_size"]
        elif jax.process_index() == 0:
            _atomic_write(_meta_file(path), lambda f: _dump_json(meta, f), ".json")
    # the plan: the chunk layout (sweep.json's) and the chunks already in the folder, as process 0
    # sees them; the same for all processes, whose own views of the folder could differ a moment
    plan = np.zeros(0, np.int64)
    if jax.process_index() == 0:
        on_disk = [path is not None and os.path.exists(_chunk_file(path, c))
                   for c in range(math.ceil(len(index) / chunk_size))]
        plan = np.array([chunk_size, *on_disk], np.int64)
    if n_proc > 1:
        plan = broadcast(plan)
    chunk_size, done = int(plan[0]), plan[1:].astype(bool)
    meta["chunk_size"] = chunk_size

    spec_json = json.dumps(spec.to_json(), sort_keys=True)
    if scheduling == "pool":
        run_chunk = _pool_runner(spec_json, spec.model, n, dt, grid_dt, scheme, lanes, refill_every)
    else:
        run_chunk = _chunk_runner(spec_json, spec.model, n, dt, grid_dt, scheme)
    base_key = jax.random.key(seed)
    mesh = jax.sharding.Mesh(np.asarray(jax.local_devices()), ("batch",))
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch"))
    lane_steps = 0

    outputs = {k: np.full(len(index), _FILL[k]) for k in OUTPUTS}
    n_chunks = len(done)
    bounds = [(c * chunk_size, min((c + 1) * chunk_size, len(index))) for c in range(n_chunks)]
    mine = share(np.flatnonzero(~done))
    if n_proc > n_chunks and jax.process_index() == 0:
        warnings.warn(f"the sweep has {n_chunks} chunk(s) of {chunk_size} members for {n_proc} processes: some "
                      "have nothing to do; a smaller chunk_size splits it further.", stacklevel=2)
    show = progress and jax.process_index() == 0
    ours = done.copy()
    ours[mine] = True
    bar = _progress(sum(hi - lo for c, (lo, hi) in enumerate(bounds) if ours[c]), show)
    for c in np.flatnonzero(done):
        lo, hi = bounds[c]
        with np.load(_chunk_file(path, c)) as z:
            for k in OUTPUTS:
                if k in z:
                    outputs[k][lo:hi] = z[k]
        bar.update(hi - lo, skipped=True)
    # a chunk runs padded to a multiple of the device count (its stored size need not be one:
    # a resumed sweep may have other devices than the run that started it)
    width = math.ceil(chunk_size / n_dev) * n_dev
    # deal the chunk's members to the devices in turn (member j to device j mod D): the
    # members of one region of a grid take similar times, so contiguous shares would leave
    # one device with most of the work (61 % / 39 % on the default map at μ = 0.3)
    deal = np.arange(width).reshape(-1, n_dev).T.ravel()
    undeal = np.argsort(deal)
    for c in mine:
        c = int(c)
        lo, hi = bounds[c]
        pad = width - (hi - lo)
        params = {
            k: jax.device_put(np.pad(v[lo:hi], (0, pad), mode="edge").astype(dtype)[deal], sharding)
            for k, v in sel.items()
        }
        idx = jax.device_put(np.pad(index[lo:hi], (0, pad), mode="edge")[deal], sharding)
        valid = jax.device_put((np.arange(width) < hi - lo)[deal], sharding)
        out = jax.device_get(run_chunk(params, idx, valid, base_key))
        lane_steps += int(np.sum(out.pop("lane_steps", 0)))
        chunk_out = {k: np.asarray(out[k])[undeal][: hi - lo] for k in OUTPUTS}
        for k in OUTPUTS:
            outputs[k][lo:hi] = chunk_out[k]
        if path is not None:
            _atomic_write(_chunk_file(path, c), lambda t: np.savez(t, **chunk_out), ".npz")
        bar.update(hi - lo)
        if on_chunk is not None:
            on_chunk(c)
    if n_proc > 1:  # the other processes' chunks, by position (every process returns the whole sweep)
        at = np.concatenate([np.arange(*bounds[c]) for c in mine] + [np.zeros(0, int)])
        parts = gather({"at": at, "lane_steps": np.array([lane_steps]), **{k: outputs[k][at] for k in OUTPUTS}})
        for part in parts:
            for k in OUTPUTS:
                outputs[k][part["at"]] = part[k]
        lane_steps = int(sum(int(part["lane_steps"][0]) for part in parts))
    bar.close()
    inputs_out = {**sel, "index": index}
    result = SweepResult(inputs_out, outputs, tuple(meta["shape"]), names, meta)
    # how this call used its lanes (not part of the results, nor of the resume fingerprint)
    member_steps = int(np.sum(np.where(outputs["steps"] > 0, outputs["steps"], 0)))
    result.meta = {**meta, "scheduling": scheduling, "lanes": lanes, "refill_every": refill_every,
                   "lane_steps": lane_steps, "member_steps": member_steps, "processes": n_proc}
    return result


@functools.lru_cache(maxsize=16)
def _chunk_runner(spec_json: str, model, n, dt, grid_dt, scheme):
    """One jitted chunk function per (spec, resolution): repeated sweeps reuse its compilation
    (the seed and all swept values are arguments, not constants)."""
    member = _make_member(spec_of(spec_json, model), n, dt, grid_dt, scheme)

    @jax.jit
    def run_chunk(params, idx, valid, base_key):
        return jax.vmap(member, in_axes=(0, 0, None))(params, idx, base_key)

    return run_chunk


@functools.lru_cache(maxsize=16)
def _pool_runner(spec_json: str, model, n, dt, grid_dt, scheme, lanes: int, refill_every: int):
    """One jitted chunk function with continuous batching: every device sets up its share of
    the chunk's members, runs them in `lanes` lanes ([`jaxrod.batching.run_pool`][]) and
    summarises them. Also returns the lane steps computed per device (for the utilisation)."""
    setup, advance, finished, outputs = _engine_member(spec_of(spec_json, model), n, dt, grid_dt, scheme)
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


def _version() -> str:
    from .._version import __version__

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

