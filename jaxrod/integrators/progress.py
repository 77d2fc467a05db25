"""A progress bar for one compiled run: the time loop reports each finished save interval to
the host (`jax.debug.callback`), which advances a tqdm bar (`RunOptions(progress=True)`; for
single runs: under `vmap` every member would report)."""

from __future__ import annotations

__all__ = ["compiling", "tick"]

_BAR = {}
_SEEN = set()


def compiling(what: str, key) -> None:
    """Host side, before a run's first compiled call: say on stderr that `what` is being compiled
    (once per `key` and process), so that a terminal is never silent for the seconds that
    tracing and compilation take (a fraction of a second when the persistent compilation
    cache has the program)."""
    if key in _SEEN:
        return
    _SEEN.add(key)
    import sys

    print(f"compiling {what} (seconds the first time; cached after)…", file=sys.stderr, flush=True)



def tick(done, total, stopped) -> None:
    """Host side: `done` of `total` save intervals finished; the bar closes at the end or when
    the run stops early (buckled, stuck or non-finite)."""
    done, total, stopped = int(done), int(total), bool(stopped)
    bar = _BAR.get("bar")
    if bar is None and done > 1:  # the later saves of a run that stopped (its bar is closed)
        return
    if bar is None or done <= bar.n:  # a new run
        if bar is not None:
            bar.close()
        from tqdm.auto import tqdm

        bar = _BAR["bar"] = tqdm(total=total, unit="save", desc="run", leave=False)
    bar.update(done - bar.n)
    if done >= total or stopped:
        bar.close()
        _BAR.pop("bar", None)
