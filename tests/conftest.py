import jax

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
jax.config.update("jax_numpy_rank_promotion", "raise")

# One compilation cache for the whole run (both xdist workers, every file): many tests compile
# the same runs (a scene's simulate, a sweep's pool), and each worker would compile them again.
# It also lets `make test` schedule tests one by one (--dist worksteal: 243 s on a clean clone
# against 296 s with whole files per worker, 2026-12-03). The folder starts empty on a clean
# clone (CI) and is not committed.
import os  # noqa: E402

jax.config.update("jax_compilation_cache_dir", os.path.join(os.path.dirname(os.path.dirname(__file__)),
                                                            ".pytest_cache", "jax"))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
