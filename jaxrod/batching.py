"""Continuous batching: many fixed-step runs in `B` lanes, each lane taking the next pending run
as soon as its own has stopped, inside one compiled loop.

A vmapped batch of runs that each loop until they stop waits for its slowest member: a map
whose runs stop at widely different times keeps its lanes busy a small part of the time
(benchmarks/README.md, sweeps, gives the measured share). Here the lanes advance together `refill_every` steps at a time; after
each round, every lane whose run has finished writes its state back and takes the next
pending run (no host round trip). A run takes exactly the steps of its single run, whatever the
lane it lands in, so results do not depend on `B`, the chunking or the device count.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Int

__all__ = ["PoolStats", "run_pool", "DEFAULT_LANES", "DEFAULT_REFILL_EVERY"]

# Chosen by benchmarks/lane_choice.py on the default E3 map (benchmarks/README.md).
DEFAULT_LANES = 16
DEFAULT_REFILL_EVERY = 16


class PoolStats(eqx.Module):
    """How busy the lanes were: `rounds` (refill rounds), `lane_steps` (steps computed,
    B × rounds × refill_every, busy or not)."""

    rounds: Int[Array, ""]
    lane_steps: Int[Array, ""]


def _take(tree, idx):
    return jax.tree_util.tree_map(lambda x: x[idx], tree)


def _select(mask, new, old):
    return jax.tree_util.tree_map(
        lambda a, b: jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b), new, old
    )


def run_pool(
    advance: Callable[[Any], Any],
    finished: Callable[[Any], Bool[Array, ""]],
    runs: Any,
    valid: Bool[Array, " C"],
    lanes: int = DEFAULT_LANES,
    refill_every: int = DEFAULT_REFILL_EVERY,
) -> tuple[Any, PoolStats]:
    """Advance every valid run of `runs` until it has finished, `lanes` runs at a time.

    **Arguments:**

    - `advance`: one step of one run, `run -> run` (pure; must leave a finished run as it is).
    - `finished`: whether a run is over, `run -> bool`.
    - `runs`: the runs at their start, a pytree whose leaves have a leading axis of length C.
    - `valid`: which of the C runs to advance (the others, e.g. padding, are returned as given).
    - `lanes`: B, the runs advanced side by side (static); `refill_every`: steps between
      refills (static). A lane whose run stops mid-round idles to the round's end.

    **Returns:** `(runs, stats)`: every run at its end, and a [`PoolStats`][].
    """
    n_runs = valid.shape[0]
    # at least two lanes unless one is asked for: XLA compiles a batch of one like an unbatched
    # loop, which rounds some fused operations differently in the last bit (measured), so two keep
    # every run bit-identical across lane counts; `lanes=1` (the 3D rod's) runs each run alone,
    # without a second lane computing an idle copy (half the work), identical across chunkings
    B = 1 if lanes == 1 else max(2, min(lanes, n_runs))
    order = jnp.argsort(~valid, stable=True).astype(jnp.int32)  # valid runs first, in order
    count = jnp.sum(valid, dtype=jnp.int32)
    slot = jnp.arange(B, dtype=jnp.int32)
    member = order[jnp.minimum(slot, n_runs - 1)]  # lanes past the runs hold a copy, inactive
    active = slot < count
    step_lanes = jax.vmap(advance)
    finished_lanes = jax.vmap(finished)

    def cond(c):
        return jnp.any(c[2])

    def body(c):
        runs, lane, active, member, ptr, rounds = c
        lane = jax.lax.fori_loop(0, refill_every, lambda _, x: step_lanes(x), lane)
        done = active & finished_lanes(lane)
        # write finished runs back (out-of-range index: dropped)
        dest = jnp.where(done, member, n_runs)
        runs = jax.tree_util.tree_map(lambda buf, x: buf.at[dest].set(x, mode="drop"), runs, lane)
        # each finished lane takes the next pending run
        n_done = done.astype(jnp.int32)
        nxt = ptr + jnp.cumsum(n_done, dtype=jnp.int32) - 1
        take = done & (nxt < count)
        new = order[jnp.minimum(nxt, n_runs - 1)]
        lane = _select(take, _take(runs, new), lane)
        member = jnp.where(take, new, member)
        active = jnp.where(done, take, active)
        return runs, lane, active, member, ptr + jnp.sum(n_done, dtype=jnp.int32), rounds + 1

    c0 = (runs, _take(runs, member), active, member, jnp.minimum(B, count), jnp.array(0, jnp.int32))
    runs, *_, rounds = jax.lax.while_loop(cond, body, c0)
    return runs, PoolStats(rounds=rounds, lane_steps=rounds * B * refill_every)
