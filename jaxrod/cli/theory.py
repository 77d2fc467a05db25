"""`jaxrod theory`: the analytic loads and stable-zone intercepts."""

from __future__ import annotations

import json
import math

from ._common import _add_rod_options, _finite_float, _json_number, _rod_from_args
from ._checks import _check_theory


def _cmd_theory(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from .. import theory as th

    rod = _rod_from_args(args, args.mu)  # --mu and --mode were checked by cli._checks
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


def register(sub) -> None:
    """`jaxrod theory`: its arguments, checks and command."""
    t = sub.add_parser("theory", help="analytic loads and stable-zone intercepts (docs/physics.md P3-P7)")
    t.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    t.add_argument("--dF", type=_finite_float, default=None, help="load above F0_m [N]")
    t.add_argument("--mode", type=int, default=None, help="mode m (default: the critical mode)")
    t.add_argument("--json", action="store_true", help="print one JSON object")
    _add_rod_options(t)
    t.set_defaults(func=_cmd_theory, check=_check_theory)
