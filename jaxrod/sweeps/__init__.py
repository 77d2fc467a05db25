"""Monte Carlo sweeps: continuous batching on every device, chunked, resumable, with progress.

The package: `spec` (what a sweep is), `member` (one member on the engine), `run` (`sweep`),
`result` (`SweepResult`), `store` (the sweep's folder).

`sweep(spec, inputs)` runs one perturbed rod per member of a batch of parameter points and
returns a [`jaxrod.SweepResult`][] of per-member arrays. A chunk's members are dealt to the
local devices in turn (`shard_map` over a one-axis `Mesh`); each device runs its share in
16 lanes with continuous batching ([`jaxrod.batching.run_pool`][]): a lane whose member has
stopped takes the next one inside the compiled loop. Every chunk has the same shape (the last
one is padded with inactive members), so the sweep compiles once. With a `path`, every finished
chunk is written atomically and a re-run skips it.

**Several processes.** Under `jax.distributed` (JAX's multi-controller runtime, started with
`jaxrod.distributed.initialize` or `jax.distributed.initialize()` in every process), the same
`sweep` call in every process splits the work: the missing chunks are dealt to the processes in
turn, each runs its share with continuous batching on its own devices and writes its chunks to
the shared `path`, and every process returns the whole merged result. Results depend only on the
global member index (random keys are `fold_in(key(seed), index)`) and on the chunk layout, which
does not depend on the process count: the merge equals a one-process run with as many devices
bit for bit, and a re-run with any number of processes completes only the missing chunks.
"""

from .member import N_SAVE as N_SAVE
from .result import SweepResult as SweepResult
from .result import wilson_interval as wilson_interval
from .run import resolved as resolved
from .run import sweep as sweep
from .spec import OUTPUTS as OUTPUTS
from .spec import PARAMETERS as PARAMETERS
from .spec import SweepSpec as SweepSpec

__all__ = ["SweepSpec", "SweepResult", "sweep", "resolved", "PARAMETERS", "OUTPUTS", "N_SAVE", "wilson_interval"]
