import os

# The tests compile far more than they run: most of the default suite's time is XLA compiling
# many programs that each run briefly. JAX's switch for that case (XLA's backend optimisation
# level 0, LLVM's expensive passes off) takes about a sixth off the cold suite
# (benchmarks/results/suite_time_variants.txt); the programs run slower, which the tests' short
# runs do not repay. Set in the environment before JAX is imported, so that the processes the
# tests start (the command line, two-process sweeps compared bit for bit with this one) compile
# alike. JAX_DISABLE_MOST_OPTIMIZATIONS=0 in the environment compiles the tests as users' programs
# are compiled (this file is the tests' only).
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
# XLA's CPU "fusion emitters" (its default code generator for fused kernels) cost about 29 ms per
# small program at level 0 (an operation run outside jit compiles one per shape and dtype, and
# the suite compiles thousands); the older emitters 14-18 ms, and the larger programs measured
# compile as fast and run within 7 % (benchmarks/fusion_emitters.py). The cold suite: 217 and
# 223 s against 304 s (benchmarks/results/suite_time_variants.txt). Appended to XLA_FLAGS unless
# set there.
# XLA aborts a process whose XLA_FLAGS names a flag it does not know (older or later versions
# may not have this one): a child process tries it first, once (the xdist workers and the
# processes the tests start inherit the outcome).
_EMITTERS = "--xla_cpu_use_fusion_emitters=false"


def _xla_accepts(flag: str) -> bool:
    import subprocess
    import sys

    env = dict(os.environ, XLA_FLAGS=f"{os.environ.get('XLA_FLAGS', '')} {flag}".strip(), JAX_PLATFORMS="cpu")
    probe = "import jax.numpy as jnp; jnp.zeros(1).block_until_ready()"
    return subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True).returncode == 0


if "xla_cpu_use_fusion_emitters" not in os.environ.get("XLA_FLAGS", "") and "JAXROD_TESTS_XLA_DEFAULT" not in os.environ:
    if _xla_accepts(_EMITTERS):
        os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {_EMITTERS}".strip()
    else:
        os.environ["JAXROD_TESTS_XLA_DEFAULT"] = "1"  # XLA's default emitters, without asking again

# JAX reads the variable as it is imported (nothing imports JAX before this file)
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
jax.config.update("jax_numpy_rank_promotion", "raise")

# One compilation cache for the whole run (both xdist workers, every file): many tests compile
# the same runs (a scene's simulate, a sweep's pool), and each worker would compile them again.
# It also lets `make test` schedule tests one by one (--dist worksteal: 243 s on a clean clone
# against 296 s with whole files per worker, 2026-12-03). The folder starts empty on a clean
# clone (CI) and is not committed.
jax.config.update("jax_compilation_cache_dir", os.path.join(os.path.dirname(os.path.dirname(__file__)),
                                                            ".pytest_cache", "jax"))
# Every program is written, however fast it compiled (threshold 0 s, as jaxrod's own default): at
# XLA's level 0 most of the tests' programs compile in under 0.2 s (a cold suite leaves 3630 files
# in the cache at 0 s, 216 at 0.2 s), and each worker compiled those again
# (benchmarks/results/suite_time_variants.txt, J and K: 319 s against 348 and 395 s).
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
