"""E6C with the 3D rod on this CPU: the paper's random position perturbation (lateral forces
±2 N/m on the scene's noise grid for 1 ms, key 6 as `jaxrod reproduce e6`), μ = 0.9: ΔF* of that
realization by label bisection (rtol 1e-2, horizon 0.5 s as E6's field model, bracket a factor 4
around the field model's ΔF*), then 0.5-s runs at 1.05 ΔF* and at the paper's 40 N, and the
largest modes of θ at the stop with their shares of the power of the first 40 modes — the E6C
part of `jaxrod reproduce e6 --model rod3d` (`jaxrod.experiments.e6.rod3d.e6c`), one
`rod3d_random_position_n{n}.csv` per segment count beside this file (commit, date, wall time;
a point already there is not run again).

    python studies/paper/e6/rod3d_random_position.py --n 120 240

The question (issue [paper3d], reason (D)): the paper sees a single mode, m = 21; the field
model's buckled state is broadband (mode 21 with 21 % of the power at 1.05 ΔF*)."""

from __future__ import annotations

import argparse
import os

import jax

jax.config.update("jax_enable_x64", True)

from jaxrod.experiments.e6.rod3d import e6c  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[120])
    for n in ap.parse_args().n:
        print(n, "segments:", e6c(HERE, n=n), flush=True)


if __name__ == "__main__":
    main()
