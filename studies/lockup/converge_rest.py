"""The lock-up curve's convergence at the μL/ℓ that `jaxrod reproduce lockup` checks only at its
base (0.5, 1.5 and 3), and μL/ℓ = 3 again at the base with more stages (its bracket stayed open
after 12): the same staircases (`jaxrod.experiments.lockup`) with up to 16 stages, each job's
JSON under results/lockup/converge_rest/jobs/ and the tables beside it.

    python studies/lockup/converge_rest.py   # about 35 min on the 2-core CPU, two jobs at a time
"""

import json
import multiprocessing as mp
import os
import time
from concurrent.futures import ProcessPoolExecutor

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
OUT = os.path.join(HERE, "converge_rest")

if __name__ == "__main__":
    import jax

    jax.config.update("jax_enable_x64", True)
    from jaxrod.experiments.lockup import SETTINGS, _job, _write

    S = dict(SETTINGS[False], max_stages=16)
    jobs = [((4.0, (3.0,), None), (32, 10e-3)), ((4.0, (3.0,), None), (16, 5e-3)), ((2.0, (0.5, 1.5), None), (16, 5e-3)),
            ((2.0, (0.5, 1.5), None), (32, 10e-3)), ((4.0, (3.0,), None), (16, 10e-3))]
    os.makedirs(os.path.join(OUT, "jobs"), exist_ok=True)
    args = [(g, run, S, os.path.join(OUT, "jobs", f"L{g[0]:g}_X{'-'.join(f'{x:g}' for x in g[1])}_w{run[0]}_v{1e3 * run[1]:g}.json"),
             True) for g, run in jobs]
    t = time.time()
    with ProcessPoolExecutor(2, mp_context=mp.get_context("spawn")) as pool:
        for path in pool.map(_job, [a for a in args if not os.path.exists(a[3])]):
            print(f"  {os.path.basename(path)} done after {time.time() - t:.0f} s", flush=True)
    results = [json.load(open(a[3])) for a in args]
    _write(OUT, S, results, time.time() - t)
    print(f"wrote {OUT} in {time.time() - t:.0f} s")
