"""E3 with the full model: the 3D rod's stable-zone boundary v₀*(ΔF) and its fitted exponent
(issue [rod3d]), by `jaxrod.experiments.e3.rod3d.boundary_3d`.

Every finished 3D run is appended to `rod3d_runs.csv` beside this file and replayed from it, so
the loads can be split between processes (each load's search depends only on its load) and a
last call with every load writes the summary from the recorded runs without running them again:

    python studies/paper/e3/rod3d_boundary.py --n 120 --dF 0.5 1 2 5 &
    python studies/paper/e3/rod3d_boundary.py --n 120 --dF 10 20 40 60 &
    wait; python studies/paper/e3/rod3d_boundary.py --n 120 --dF 0.5 1 2 5 10 20 40 60

Writes `rod3d_boundary_n{n}.json` (`_axis` added with `--friction-at axis`, `_implicit` with the
default `--scheme implicit`, `_leapfrog` with `--scheme leapfrog`: the files without either hold
the runs of projected Verlet, the 3D rod's scheme until an earlier revision) (points, both
exponents, settings), `.csv` (one row per load, plain numbers) and `.png`.
"""

from __future__ import annotations

import argparse
import os

import jax

jax.config.update("jax_enable_x64", True)

from jaxrod.experiments.e3.rod3d import boundary_3d  # noqa: E402
from jaxrod.experiments.e3.rod3d import write_boundary  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dF", type=float, nargs="+", required=True, help="loads above F⁰₆ [N]")
    ap.add_argument("--n", type=int, default=120, help="segments of the 3D rod")
    ap.add_argument("--rtol", type=float, default=0.01, help="relative bracket width of each v₀*")
    ap.add_argument("--t1", type=float, default=0.4, help="horizon of a run [s]")
    ap.add_argument("--friction-at", default="surface", choices=("surface", "axis"),
                    help="friction at the contact point (default) or at the centre line (no rolling)")
    ap.add_argument("--sink", type=float, default=1e-3,
                    help="the wall's compliance: the rod sinks sink·R into it under its weight")
    ap.add_argument("--scheme", default="implicit", choices=("implicit", "leapfrog", "verlet"),
                    help="the integrator: the implicit leapfrog (the 3D rod's default), projected leapfrog or "
                         "projected Verlet")
    ap.add_argument("--dir", default=HERE, help="folder of the runs file and the outputs")
    args = ap.parse_args()
    res = boundary_3d(args.dF, n=args.n, rtol=args.rtol, t1=args.t1,
                      friction_at=args.friction_at, sink=args.sink, scheme=args.scheme, runs_csv=os.path.join(args.dir, "rod3d_runs.csv"))
    stem = os.path.join(args.dir, f"rod3d_boundary_n{args.n}" + ("" if args.friction_at == "surface" else "_axis")
                        + ("" if args.sink == 1e-3 else f"_sink{args.sink:g}")
                        + {"leapfrog": "_leapfrog", "implicit": "_implicit"}.get(args.scheme, ""))
    write_boundary(res, stem)
    print(f"3D rod ({args.n} segments): v0* ∝ ΔF^({res['exponent_rod3d']:.3f} ± {res['exponent_rod3d_stderr']:.3f}); "
          f"field model: ΔF^({res['exponent_field']:.3f} ± {res['exponent_field_stderr']:.3f}); theory −0.5")
    print("wrote", stem + ".json/.csv/.png")


if __name__ == "__main__":
    main()
