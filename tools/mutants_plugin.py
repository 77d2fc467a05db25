"""A pytest plugin for tools/mutants_heldout.py (loaded with `-p mutants_plugin`, tools/ on PYTHONPATH).

- `JAXROD_MUTANTS_RECORD=PATH`: writes PATH (JSON) at the end of the test run: per failing test
  (in order, the first is the killing one) its node id, the phase (setup, call, teardown, collect), how it failed — "assertion" for an
  AssertionError (a bare assert, pytest.approx, numpy.testing) or pytest's own failure (a
  `pytest.raises` or `pytest.warns` that saw nothing, `pytest.fail`), "exception" for any other
  exception — the exception's type and the first line of its message; and the file jaxrod was
  imported from (the runner checks that it is the mutated copy).
- `JAXROD_MUTANTS_CLEAR=1`: clears JAX's in-memory caches after each test, so that mutmut's
  stats run records every function each test traces, not only the tests that trace it first.
- `JAXROD_MUTANTS_STATS_FAILED=PATH` (during mutmut's stats run): a test that fails on the mutated
  copy with no mutant active is appended to PATH and reported as skipped, so the stats run
  (`pytest -x`) goes on; the held-out runner leaves such tests out.
- During mutmut's stats run (`MUTANT_UNDER_TEST=stats`), the functions a fixture of wider scope
  (module, class, package, the whole run) calls while it is set up are credited to every test that
  requests the fixture, not only to the first (mutmut credits what runs to the test running, and
  a module-scoped fixture runs once, inside the first test's setup).
"""

from __future__ import annotations

import json
import os
import sys

import pytest

_failures: list[dict] = []
_by_fixture: dict[int, set[str]] = {}  # id(FixtureDef) -> functions its setups called (stats run)


def _stats_run() -> bool:
    return os.environ.get("MUTANT_UNDER_TEST") == "stats" and "mutmut" in sys.modules


@pytest.hookimpl(hookwrapper=True)
def pytest_fixture_setup(fixturedef, request):
    if not _stats_run() or fixturedef.scope == "function":
        yield
        return
    from mutmut.state import state

    outer, state()._stats = state()._stats, set()  # what this fixture's setup calls, alone
    try:
        yield
    finally:
        mine = state()._stats
        _by_fixture.setdefault(id(fixturedef), set()).update(mine)
        state()._stats = outer | mine


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item):
    yield
    if _stats_run():
        from mutmut.state import state

        for defs in item._fixtureinfo.name2fixturedefs.values():
            for d in defs:
                state()._stats.update(_by_fixture.get(id(d), ()))


def _how(excinfo) -> tuple[str, str, str]:
    if excinfo is None:
        return "assertion", "XPASS(strict)", ""
    e = excinfo.value
    line = (str(e).strip().splitlines() or [""])[0][:200]
    kind = "assertion" if isinstance(e, (AssertionError, pytest.fail.Exception)) else "exception"
    return kind, type(e).__name__, line


def _record(nodeid: str, when: str, excinfo) -> None:
    how, typ, msg = _how(excinfo)
    _failures.append({"test": nodeid, "when": when, "how": how, "type": typ, "message": msg})


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.failed:
        _record(item.nodeid, call.when, call.excinfo)
        if os.environ.get("MUTANT_UNDER_TEST") == "stats" and os.environ.get("JAXROD_MUTANTS_STATS_FAILED"):
            # a test that fails on the unmutated (trampolined) copy: noted, and reported as skipped
            # so that the stats run (pytest -x) goes on; the held-out runner never runs it
            with open(os.environ["JAXROD_MUTANTS_STATS_FAILED"], "a") as f:
                f.write(item.nodeid + "\n")
            report.outcome = "skipped"
            report.longrepr = (str(item.path), item.location[1] or 0, "failed on the mutated copy")


def pytest_collectreport(report):
    if report.failed:
        text = str(report.longrepr).strip().splitlines()
        _failures.append({"test": report.nodeid, "when": "collect", "how": "exception", "type": "CollectError",
                          "message": (text[-1] if text else "")[:200]})


def pytest_runtest_teardown(item, nextitem):
    if os.environ.get("JAXROD_MUTANTS_CLEAR") == "1" and "jax" in sys.modules:
        sys.modules["jax"].clear_caches()


def pytest_sessionfinish(exitstatus):
    path = os.environ.get("JAXROD_MUTANTS_RECORD")
    if path:
        jaxrod = sys.modules.get("jaxrod")
        with open(path, "w") as f:
            json.dump({"failures": _failures, "exitstatus": int(exitstatus),
                       "jaxrod": getattr(jaxrod, "__file__", None)}, f)
