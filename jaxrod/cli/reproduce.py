"""`jaxrod reproduce`: the paper's experiments."""

from __future__ import annotations

from ._common import _fail, _positive_int


def _cmd_reproduce(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from ..reproduce import reproduce

    try:
        res = reproduce(args.which, args.out, quick=args.quick, progress=not args.quiet, model=args.model, n=args.n)
    except ValueError as err:
        _fail(str(err))
    print(f"wrote {args.out}/results.json and figures under {args.out}/<experiment>/")
    for name, r in res.items():
        print(f"  {name}: {r.get('seconds', '?')} s")
    return 0


def register(sub) -> None:
    """`jaxrod reproduce`: its arguments, checks and command."""
    rp = sub.add_parser("reproduce", help="reproduce the paper's experiments E1-E6 (E1 and E6's full-model part with the 3D rod) "
                        "and the post-buckling helix/hysteresis experiment ('all'); lock-up by name")
    rp.add_argument("which", nargs="+", choices=["e1", "e2", "e3", "e4", "e5", "e6", "helix", "lockup", "all"])
    rp.add_argument("--out", default="out/paper", help="output folder (default: out/paper under the working folder; "
                    "the committed reproduction is results/paper)")
    rp.add_argument("--quick", action="store_true", help="coarser, fewer realizations: a few minutes")
    rp.add_argument("--model", choices=["field", "rod3d"], default="field",
                    help="rod3d: E3, E4, E5 and E6C with the 3D rod "
                         "(jaxrod.experiments.eN.rod3d; hours at 500 segments)")
    rp.add_argument("--n", type=_positive_int, default=None, help="segments of the 3D rod (default 500; 60 with --quick)")
    rp.add_argument("--quiet", action="store_true")
    rp.set_defaults(func=_cmd_reproduce, all_cores=True)
