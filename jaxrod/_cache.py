"""JAX's persistent compilation cache, on by default: a compiled jaxrod function is written to
disk once and read back by every later process (a command line call, a notebook kernel, a
pytest worker) instead of being compiled again.

`configure` is called when jaxrod is imported. The folder is `cache_dir()`:

- `JAXROD_CACHE_DIR=PATH`: that folder; `JAXROD_CACHE_DIR=off` (or `0`, `none`, `false`, empty):
  no cache (`jaxrod --no-cache …` sets the same for one command, `jaxrod --cache-dir PATH …`
  the folder);
- otherwise the user's cache folder by the platform's convention — `$XDG_CACHE_HOME/jaxrod`
  or `~/.cache/jaxrod` (Linux and other POSIX), `~/Library/Caches/jaxrod` (macOS),
  `%LOCALAPPDATA%\\jaxrod\\Cache` (Windows) — in a subfolder named by the JAX and jaxlib
  versions, so that a new JAX starts a new folder and the old one can simply be deleted.

A cache the user already set up is kept (`jax_compilation_cache_dir` set before jaxrod is
imported, e.g. by `JAX_COMPILATION_CACHE_DIR`). Entries are keyed by JAX on the compiled
program, the compile options, the XLA flags, the backend and the JAX/jaxlib versions, so an
entry is never used for a different program or another JAX (never stale). JAX (0.10) writes an
entry in place, without a lock unless `jax_compilation_cache_max_size` is set: a process that
shares the folder (pytest workers, the processes of `jax.distributed`, of which only process 0
writes) and reads an entry while another writes it gets a truncated, compressed entry, which
fails to decompress; JAX warns ("Error reading persistent compilation cache entry") and compiles
the program itself — time lost, never a wrong program. JAX never caches a program that calls
back to Python while it runs (`jax.debug.callback`): in jaxrod only a single run with
`RunOptions(progress=True)` (the progress bar of `jaxrod simulate --model rod3d`) does; sweeps,
maps and searches report progress from the host between compiled calls and are cached.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping

__all__ = ["ENV", "OFF", "cache_dir", "configure", "use"]

ENV = "JAXROD_CACHE_DIR"
OFF = ("", "0", "off", "none", "false", "no")
MIN_COMPILE_SECONDS = 0.0
"""Programs that compile faster than this are not written: none (a command compiles dozens of small
programs in 0.02–0.06 s each, which add up to seconds; reading one back costs about a millisecond)."""


def _user_cache_root(environ: Mapping[str, str]) -> str:
    home = os.path.expanduser("~")
    if sys.platform == "darwin":
        return os.path.join(home, "Library", "Caches", "jaxrod")
    if os.name == "nt":
        base = environ.get("LOCALAPPDATA") or os.path.join(home, "AppData", "Local")
        return os.path.join(base, "jaxrod", "Cache")
    base = environ.get("XDG_CACHE_HOME") or os.path.join(home, ".cache")
    return os.path.join(base, "jaxrod")


def cache_dir(environ: Mapping[str, str] | None = None) -> str | None:
    """The folder of jaxrod's compilation cache, or `None` when it is switched off
    (`JAXROD_CACHE_DIR=off`)."""
    import jax
    import jaxlib

    environ = os.environ if environ is None else environ
    value = environ.get(ENV)
    if value is not None:
        if value.strip().lower() in OFF:
            return None
        return os.path.abspath(os.path.expanduser(value))
    return os.path.join(_user_cache_root(environ), f"jax-{jax.__version__}-jaxlib-{jaxlib.__version__}")


def configure(environ: Mapping[str, str] | None = None) -> str | None:
    """Switch JAX's persistent compilation cache on in `cache_dir()` unless it is switched off
    or the user set one up already. Returns the folder in use (`None`: no cache)."""
    import jax

    current = jax.config.jax_compilation_cache_dir
    if current:
        return current
    folder = cache_dir(environ)
    if folder is None:
        return None
    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_SECONDS)
    return folder


def use(folder: str | None) -> None:
    """Move the cache to `folder` (`None`: no cache) from now on, also after jaxrod has already
    compiled something in this process (JAX opens its cache at the first compilation: it is
    reset here)."""
    import jax
    from jax.experimental.compilation_cache import compilation_cache

    jax.config.update("jax_compilation_cache_dir", folder)
    if folder is not None:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_SECONDS)
    compilation_cache.reset_cache()
