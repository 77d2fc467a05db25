"""The persistent compilation cache that jaxrod switches on (jaxrod/_cache.py): where it lives,
how it is switched off or moved, and that a second process compiles nothing of jaxrod's (JAX's
own cache-miss log, in fresh processes)."""

import os
import subprocess
import sys

import jax
import jaxlib

from jaxrod import _cache

PROGRAM = "jaxrod theory --json"  # 21 small programs (jaxrod simulate: the same, and seconds more)


def test_cache_folder_follows_the_platform_and_the_environment(tmp_path):
    versions = f"jax-{jax.__version__}-jaxlib-{jaxlib.__version__}"
    if sys.platform.startswith("linux"):
        env = {"XDG_CACHE_HOME": str(tmp_path)}
        assert _cache.cache_dir(env) == os.path.join(str(tmp_path), "jaxrod", versions)
    assert _cache.cache_dir({_cache.ENV: str(tmp_path / "c")}) == str(tmp_path / "c")
    for off in ("off", "0", "", "None", "false"):
        assert _cache.cache_dir({_cache.ENV: off}) is None


def test_cache_root_on_each_platform(monkeypatch):
    """macOS: ~/Library/Caches/jaxrod; Windows: %LOCALAPPDATA%\\jaxrod\\Cache (or its default under
    the home folder); elsewhere $XDG_CACHE_HOME/jaxrod (or ~/.cache/jaxrod)."""
    home = os.path.expanduser("~")
    roots = {}
    for platform, name in (("darwin", "posix"), ("win32", "nt"), ("linux", "posix")):
        monkeypatch.setattr(_cache.sys, "platform", platform)
        monkeypatch.setattr(_cache.os, "name", name)
        roots[platform] = (_cache._user_cache_root({"LOCALAPPDATA": "/L", "XDG_CACHE_HOME": "/X"}),
                           _cache._user_cache_root({}))
        monkeypatch.undo()
    assert roots["darwin"] == (os.path.join(home, "Library", "Caches", "jaxrod"),) * 2
    assert roots["win32"] == (os.path.join("/L", "jaxrod", "Cache"),
                              os.path.join(home, "AppData", "Local", "jaxrod", "Cache"))
    assert roots["linux"] == (os.path.join("/X", "jaxrod"), os.path.join(home, ".cache", "jaxrod"))


def _run(args, env_extra, cwd):
    env = {k: v for k, v in os.environ.items() if not k.startswith(("JAX_", "JAXROD_"))}
    env.update({"JAX_EXPLAIN_CACHE_MISSES": "1", "JAX_LOG_COMPILES": "1", **env_extra})
    exe = os.path.join(os.path.dirname(sys.executable), "jaxrod")
    res = subprocess.run([exe, *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stderr


def test_a_second_process_compiles_nothing_and_off_means_off(tmp_path):
    folder = tmp_path / "cache"
    args = PROGRAM.split()[1:]
    first = _run(args, {_cache.ENV: str(folder)}, tmp_path)
    assert "PERSISTENT COMPILATION CACHE MISS" in first and len(os.listdir(folder)) >= 10
    second = _run(args, {_cache.ENV: str(folder)}, tmp_path)
    assert "Persistent compilation cache hit" in second
    assert "PERSISTENT COMPILATION CACHE MISS" not in second, [
        line for line in second.splitlines() if "MISS" in line][:5]
    # switched off by the command line's --no-cache ($JAXROD_CACHE_DIR=off: cache_dir() is None,
    # above)
    off = _run(["--no-cache", *args], {_cache.ENV: str(folder)}, tmp_path)
    assert "cache hit" not in off


def test_the_command_line_moves_or_switches_off_the_cache(tmp_path):
    """`--cache-dir` and `--no-cache` set JAX's cache folder (and reset the cache JAX opened); a
    folder given writes every program, however fast it compiled (`_cache.MIN_COMPILE_SECONDS`)."""
    from jaxrod.cli import _set_cache, build_parser

    before = jax.config.jax_compilation_cache_dir
    threshold = jax.config.jax_persistent_cache_min_compile_time_secs  # the tests' own (conftest.py)
    try:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
        _set_cache(build_parser().parse_args(["--cache-dir", str(tmp_path / "c"), "theory"]))
        assert jax.config.jax_compilation_cache_dir == str(tmp_path / "c")
        assert jax.config.jax_persistent_cache_min_compile_time_secs == _cache.MIN_COMPILE_SECONDS  # every program
        _set_cache(build_parser().parse_args(["--no-cache", "theory"]))
        assert jax.config.jax_compilation_cache_dir is None
    finally:
        _cache.use(before)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", threshold)


def test_configure_keeps_a_cache_the_user_set_and_otherwise_writes_every_program(tmp_path):
    """`configure` (run as jaxrod is imported): a cache folder already set is kept as it is; none
    set, `JAXROD_CACHE_DIR` names the folder (every program written, however fast it compiled)
    or switches the cache off."""
    key, min_key = "jax_compilation_cache_dir", "jax_persistent_cache_min_compile_time_secs"
    before = (jax.config.jax_compilation_cache_dir, jax.config.jax_persistent_cache_min_compile_time_secs)
    try:
        jax.config.update(min_key, 0.5)
        assert _cache.configure({_cache.ENV: str(tmp_path / "x")}) == before[0]
        assert jax.config.jax_compilation_cache_dir == before[0]
        assert jax.config.jax_persistent_cache_min_compile_time_secs == 0.5
        jax.config.update(key, None)
        assert _cache.configure({_cache.ENV: "off"}) is None and jax.config.jax_compilation_cache_dir is None
        assert jax.config.jax_persistent_cache_min_compile_time_secs == 0.5
        assert _cache.configure({_cache.ENV: str(tmp_path / "x")}) == str(tmp_path / "x")
        assert jax.config.jax_compilation_cache_dir == str(tmp_path / "x")
        assert jax.config.jax_persistent_cache_min_compile_time_secs == 0.0
    finally:
        jax.config.update(key, before[0])
        jax.config.update(min_key, before[1])
