"""`jaxrod figure phase`: the E2 phase portraits."""

from __future__ import annotations


def _cmd_figure(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    if args.which == "phase":
        from ..figures import phase_portraits

        agreement = phase_portraits(args.out)
        print(f"wrote {args.out}/phase.png and {args.out}/phase.csv")
        for case, frac in agreement.items():
            print(f"  {case:40s} simulated = analytic on {100 * frac:5.1f}% of the grid")
    return 0


def register(sub) -> None:
    """`jaxrod figure`: its arguments, checks and command."""
    fg = sub.add_parser("figure", help="write a figure")
    fg.add_argument("which", choices=["phase"], help="phase: E2 phase portraits")
    fg.add_argument("--out", default="out/figures", help="output folder (default: out/figures under the working folder)")
    fg.set_defaults(func=_cmd_figure)
