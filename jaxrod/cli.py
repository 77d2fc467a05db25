"""The `jaxrod` command line."""

from __future__ import annotations

import argparse
import json
import math
import sys

__all__ = ["main"]

# Rod options: (option, RodChannel field, help)
_ROD_OPTIONS = [
    ("--L", "L", "rod length [m]"),
    ("--d", "d", "rod diameter [m]"),
    ("--E", "E", "Young's modulus [Pa]"),
    ("--rho-v", "rho_v", "density [kg/m^3]"),
    ("--nu", "nu", "Poisson's ratio"),
    ("--R", "R", "clearance [m]"),
    ("--g", "g", "gravity [m/s^2]"),
]
_FIELD_TO_OPTION = {field: opt for opt, field, _ in _ROD_OPTIONS}
_FIELD_TO_OPTION.update({"mu_s": "--mu", "mu_d": "--mu"})


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, naming the option, non-zero exit
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        sys.exit(2)


def _fail(message: str) -> None:
    sys.stderr.write(f"jaxrod: error: {message}\n")
    sys.exit(2)


def _finite_float(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid number: {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return x


def _add_rod_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("rod and channel (default: the reference rod)")
    for opt, field, help_ in _ROD_OPTIONS:
        g.add_argument(opt, dest=field, type=_finite_float, default=None, help=help_)


def _rod_from_args(args, mu: float):
    from .params import RodChannel

    overrides = {f: getattr(args, f) for _, f, _ in _ROD_OPTIONS if getattr(args, f) is not None}
    try:
        return RodChannel.reference(mu=mu, **overrides)
    except ValueError as err:
        msg = str(err)
        for field, opt in _FIELD_TO_OPTION.items():
            if msg.startswith(f"RodChannel.{field} "):
                msg = f"argument {opt}: " + msg
                break
        _fail(msg)


def _json_number(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _cmd_theory(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from . import theory as th

    if args.mu < 0:
        _fail(f"argument --mu: {args.mu!r} is invalid: a friction coefficient must be >= 0.")
    if args.mode is not None and args.mode < 1:
        _fail(f"argument --mode: {args.mode!r} is invalid: a mode number must be >= 1.")
    rod = _rod_from_args(args, args.mu)
    m = int(th.critical_mode(rod)) if args.mode is None else args.mode
    out = {
        "F0cr_continuous": float(th.critical_load_continuous(rod)),
        "omega0": float(th.critical_wavenumber(rod)),
        "critical_mode": int(th.critical_mode(rod)),
        "mode": m,
        "F0_mode": float(th.frictionless_load(rod, m)),
        "mu": args.mu,
        "dF": args.dF,
        "F": None,
        "k": None,
        "f": None,
        "Adot_cr": None,
        "v_cr": None,
        "A_cr": None,
    }
    if args.dF is not None:
        F = th.frictionless_load(rod, m) + args.dF
        k = th.stiffness(rod, m, F)
        f = th.friction_amplitude(rod)
        Adot_cr = th.velocity_intercept(k, f)
        out.update(
            F=float(F),
            k=float(k),
            f=float(f),
            Adot_cr=_json_number(Adot_cr),
            v_cr=_json_number(Adot_cr * rod.R),
            A_cr=_json_number(th.position_intercept(k, f) if float(k) < 0 else math.inf),
        )
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"continuous frictionless load  F0cr   = {out['F0cr_continuous']:.6g} N")
    print(f"critical wavenumber           omega0 = {out['omega0']:.6g} rad/m")
    print(f"critical mode of the rod      m      = {out['critical_mode']}")
    print(f"frictionless load of mode {m:<3d} F0_m   = {out['F0_mode']:.6g} N")
    if args.dF is not None:
        print(f"at F = F0_m + {args.dF:g} N = {out['F']:.6g} N, mu = {args.mu:g}:")
        print(f"  modal stiffness     k       = {out['k']:.6g} 1/s^2")
        print(f"  friction amplitude  f       = {out['f']:.6g} rad/s^2")
        if out["k"] < 0:
            print(f"  velocity intercept  Adot_cr = {out['Adot_cr']:.6g} rad/s "
                  f"(lateral speed R*Adot_cr = {out['v_cr']:.6g} m/s)")
            print(f"  position intercept  A_cr    = {out['A_cr']:.6g} rad")
        else:
            print("  k >= 0: the mode is stable for any perturbation (no finite intercept)")
    return 0


def _cmd_figure(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    if args.which == "phase":
        from .figures import phase_portraits

        agreement = phase_portraits(args.out)
        print(f"wrote {args.out}/phase.png and {args.out}/phase.csv")
        for case, frac in agreement.items():
            print(f"  {case:40s} simulated = analytic on {100 * frac:5.1f}% of the grid")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="jaxrod", description="Dynamics and stability of a rod in a channel with dry friction.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    t = sub.add_parser("theory", help="analytic loads and stable-zone intercepts (PHYSICS.md P3-P7)")
    t.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    t.add_argument("--dF", type=_finite_float, default=None, help="load above F0_m [N]")
    t.add_argument("--mode", type=int, default=None, help="mode m (default: the critical mode)")
    t.add_argument("--json", action="store_true", help="print one JSON object")
    _add_rod_options(t)
    t.set_defaults(func=_cmd_theory)

    fg = sub.add_parser("figure", help="write a figure")
    fg.add_argument("which", choices=["phase"], help="phase: E2 phase portraits")
    fg.add_argument("--out", default="results", help="output folder (default: results)")
    fg.set_defaults(func=_cmd_figure)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
