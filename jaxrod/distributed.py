"""The processes of a `jax.distributed` run (JAX's multi-controller runtime): starting it, each
process's share of the work, and host arrays sent between the processes.

Every process of such a run executes the same program on its own devices (one process per host,
or per accelerator); they meet only where they call the same collective, in the same order.
Here those are `jaxrod.distributed.gather` and `jaxrod.distributed.broadcast`, built on
`jax.experimental.multihost_utils` (on CPU through JAX's default gloo collectives). In a single
process — no runtime, or a runtime of one process — every function here is a local no-op.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["broadcast", "gather", "initialize", "share"]


def initialize(
    coordinator_address: str | None = None,
    num_processes: int | None = None,
    process_id: int | None = None,
    *,
    timeout: int = 300,
) -> None:
    """Join this process to a `jax.distributed` run, before any JAX computation.

    Settings left `None` are detected from the cluster's environment by
    `jax.distributed.initialize` (SLURM, Open MPI, Kubernetes, or `JAX_COORDINATOR_ADDRESS`
    for the address); outside a cluster all three are needed.

    **Arguments:**

    - `coordinator_address`: `"HOST:PORT"` of process 0, which serves the runtime there.
    - `num_processes`: the number of processes, ≥ 1.
    - `process_id`: this process's index, 0 ≤ `process_id` < `num_processes`.
    - `timeout`: seconds to wait for all processes to connect.

    **Raises:** `ValueError` naming the argument for a malformed or missing setting.
    """
    import jax

    if coordinator_address is not None:
        host, _, port = str(coordinator_address).rpartition(":")
        if not host or not port.isdigit() or not 1 <= int(port) <= 65535:
            raise ValueError(f"coordinator_address = {coordinator_address!r} is invalid: expected HOST:PORT "
                             "with a port in 1..65535.")
    if num_processes is not None and not (isinstance(num_processes, int) and num_processes >= 1):
        raise ValueError(f"num_processes = {num_processes!r} is invalid: expected an int >= 1.")
    if process_id is not None:
        top = "num_processes" if num_processes is None else f"num_processes = {num_processes}"
        if not (isinstance(process_id, int) and process_id >= 0) or (
                num_processes is not None and process_id >= num_processes):
            raise ValueError(f"process_id = {process_id!r} is invalid: expected an int with 0 <= process_id < {top}.")
    try:
        jax.distributed.initialize(coordinator_address, num_processes, process_id,
                                   initialization_timeout=timeout)
    except ValueError as err:
        # what the cluster detection left undefined, by the name of the argument
        msg = str(err)
        for name, clue in (("coordinator_address", "coordinator_address"), ("num_processes", "Number of processes"),
                           ("process_id", "process id")):
            if clue in msg:
                raise ValueError(f"{name} is missing: no SLURM, Open MPI or Kubernetes cluster detected to "
                                 "supply it; give coordinator_address, num_processes and process_id.") from None
        raise


def share(items: Sequence) -> Sequence:
    """This process's share of `items`: every `jax.process_count()`-th item from the
    `jax.process_index()`-th (neighbours go to different processes, so that work that costs
    alike where it lies close together is spread evenly). All of `items` in a single process."""
    import jax

    return items[jax.process_index()::jax.process_count()]


def gather(arrays: Mapping[str, np.ndarray]) -> list[dict[str, np.ndarray]]:
    """Every process's `arrays`, in process order: a collective, called by all processes with
    the same names and dtypes in the same order (the lengths may differ). Bit-exact whatever
    the dtype and the x64 setting (the arrays travel as bytes).

    **Arguments:** `arrays`: name → 1-D NumPy array.

    **Returns:** a list of `jax.process_count()` dicts name → array.
    """
    import jax

    names = list(arrays)
    local = [np.ascontiguousarray(np.asarray(arrays[k])).reshape(-1) for k in names]
    if jax.process_count() == 1:
        return [dict(zip(names, local))]
    from jax.experimental import multihost_utils

    sizes = multihost_utils.process_allgather(np.array([a.nbytes for a in local], np.int32).reshape(-1))
    sizes = np.asarray(sizes).reshape(jax.process_count(), len(names))
    width = int(sizes.sum(axis=1).max())
    blob = np.concatenate([a.view(np.uint8) for a in local] + [np.zeros(0, np.uint8)])
    blobs = np.asarray(multihost_utils.process_allgather(np.pad(blob, (0, width - blob.size)))) if width else None
    out = []
    for p in range(jax.process_count()):
        part, at = {}, 0
        for k, a, nb in zip(names, local, sizes[p]):
            raw = blobs[p, at:at + nb] if width else np.zeros(0, np.uint8)
            part[k] = raw.copy().view(a.dtype)
            at += int(nb)
        out.append(part)
    return out


def broadcast(array: np.ndarray) -> np.ndarray:
    """Process 0's 1-D `array` in every process (a collective, like `jaxrod.distributed.gather`;
    the other processes' arrays are ignored and may be empty): one view of a shared resource,
    e.g. which result files exist, where the processes' own views could differ by a moment."""
    return gather({"x": array})[0]["x"]
