"""How jaxrod asks XLA to compile loops on the CPU: each loop as one function.

Since JAX 0.7 the CPU backend runs a compiled program as a sequence of kernels ("thunks"),
one per fusion, each dispatched at a fixed cost. A jaxrod run is a loop over
steps whose body is hundreds of small fused kernels (the 3D rod's step at 60 segments: about
300, plus about 70 per friction sweep), so on small problems the dispatch is most of the time.
XLA compiles a `while` loop whose body touches fewer bytes per iteration than
`xla_cpu_small_while_loop_byte_threshold` (1 kB by default) into one function instead
(`SmallWhileLoopHoistingPass`). Raising that threshold to `SMALL_LOOP_BYTES` makes every
jaxrod loop on arrays of ordinary size one function. What it gains (small problems run
several times faster, large batches are unchanged, compilation takes a little longer) is
measured by `benchmarks/xla_loops.py` (benchmarks/README.md, "XLA's loop option"). The
results are the same up to rounding (the compiler's choice of fused multiply–adds). The
continuous-batching pool does not gain: its lanes' steps are already arithmetic-bound
(benchmarks/README.md, sweeps).

`configure` is called when jaxrod is imported: it adds the option to the environment variable
`XLA_FLAGS` unless the user set `xla_backend_extra_options` there already (their choice is
kept) or set `JAXROD_XLA_DEFAULTS=0`. XLA reads `XLA_FLAGS` when JAX starts its CPU backend,
so it takes effect if jaxrod is imported before the first JAX computation of the process
(`in_effect` tells). Options named `xla_*` are never passed on to LLVM, on any backend.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

__all__ = ["SMALL_LOOP_BYTES", "OPTION", "configure", "in_effect"]

SMALL_LOOP_BYTES = 100_000_000
"""Loops touching fewer bytes per iteration than this (100 MB) become one function."""

OPTION = f"--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold={SMALL_LOOP_BYTES}"


def configure(environ: MutableMapping[str, str] | None = None) -> bool:
    """Add `OPTION` to `environ["XLA_FLAGS"]` (default: `os.environ`), unless
    `JAXROD_XLA_DEFAULTS` is `"0"` or `XLA_FLAGS` already sets `xla_backend_extra_options`.
    Returns whether it was added."""
    environ = os.environ if environ is None else environ
    if environ.get("JAXROD_XLA_DEFAULTS", "1").strip() == "0":
        return False
    flags = environ.get("XLA_FLAGS", "")
    if "xla_backend_extra_options" in flags:
        return False
    environ["XLA_FLAGS"] = f"{flags} {OPTION}".strip()
    return True


def in_effect() -> bool:
    """Whether this process's CPU backend compiles a loop that touches about 0.5 MB per
    iteration as one function (compiles a small probe)."""
    import jax
    import jax.numpy as jnp

    x = jax.device_put(jnp.zeros(60_000, jnp.float32), jax.devices("cpu")[0])  # 240 kB
    loop = jax.jit(lambda y: jax.lax.while_loop(lambda c: c[1] < 2, lambda c: (c[0] + 1.0, c[1] + 1), (y, 0))[0])
    return "xla_cpu_small_call" in loop.lower(x).compile().as_text()
