"""jaxrod asks XLA to compile each loop as one function on the CPU (`jaxrod._xla`): the option is
added to `XLA_FLAGS` on import, a user's own choice is kept, it can be turned off, and a fresh
process that imports jaxrod first really compiles loops that way."""

import os
import subprocess
import sys

import pytest

from jaxrod import _xla


def test_configure_adds_the_option_once():
    env = {"XLA_FLAGS": "--xla_cpu_enable_fast_math=false"}
    assert _xla.configure(env)
    assert env["XLA_FLAGS"] == f"--xla_cpu_enable_fast_math=false {_xla.OPTION}"
    assert not _xla.configure(env)  # already there: the user's (or our) choice stands
    assert env["XLA_FLAGS"].count("xla_backend_extra_options") == 1
    empty = {}
    assert _xla.configure(empty) and empty["XLA_FLAGS"] == _xla.OPTION


def test_configure_keeps_the_users_choice_and_can_be_turned_off():
    own = {"XLA_FLAGS": "--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold=0"}
    assert not _xla.configure(own)
    assert own["XLA_FLAGS"].endswith("=0")
    off = {"JAXROD_XLA_DEFAULTS": "0"}
    assert not _xla.configure(off)
    assert "XLA_FLAGS" not in off


def _probe(**env):
    code = "import jaxrod; from jaxrod import _xla; print(_xla.in_effect())"
    full = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAXROD_XLA_DEFAULTS")}
    out = subprocess.run([sys.executable, "-c", code], env=dict(full, **env), capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout.strip().splitlines()[-1]


@pytest.mark.parametrize("env, expected", [({}, "True"), ({"JAXROD_XLA_DEFAULTS": "0"}, "False")])
def test_a_fresh_process_compiles_loops_as_one_function(env, expected):
    assert _probe(**env) == expected


def test_this_process_compiles_loops_as_its_xla_flags_say():
    """In the test process itself (jaxrod imported before its first computation, as in a
    user's script): the probe finds loops compiled as one function exactly when the option is in
    `XLA_FLAGS`."""
    wanted = f"xla_cpu_small_while_loop_byte_threshold={_xla.SMALL_LOOP_BYTES}" in os.environ.get("XLA_FLAGS", "")
    assert _xla.in_effect() is wanted
