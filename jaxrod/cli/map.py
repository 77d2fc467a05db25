"""`jaxrod map`: the E3 stability map (the main job)."""

from __future__ import annotations

from ..registry import model_names

import math

from ._common import _fail, _finite_float, _positive_int, _range_spec
from ._checks import _check_map
from ._distributed import _add_distributed_options


def _cmd_map(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from ..stability_map import stability_map

    mus = (0.3, 0.0) if args.mu is None else (args.mu,)
    main = jax.process_index() == 0  # on several processes, process 0 reports
    if main:
        processes = f" x {jax.process_count()} processes" if jax.process_count() > 1 else ""
        print(f"stability map: {args.model} model, mu = {', '.join(f'{m:g}' for m in mus)}, "
              f"{len(args.dF)} x {len(args.v0)} grid, {jax.local_device_count()} device(s){processes} "
              f"({jax.devices()[0].platform})")
    try:
        s = stability_map(mus, args.dF, args.v0, args.model, args.n, 6, args.out,
                          progress=not args.quiet, t1=args.t1, curve_rtol=None if args.no_curve else 1e-3,
                          chunk_size=args.chunk_size, fill=args.fill)
    except ValueError as err:
        _fail(str(err))
    if not main:
        return 0
    steps = ", ".join(f"{g['scheme']} at {g['dt']:.3e} s for dF {g['dF_first']:g}-{g['dF_last']:g} N" for g in s["schemes"])
    print(f"n = {s['n']}, {steps}; wrote {args.out}/map.png, map.csv, map.json")
    if "fill" in s:
        print("  column search: " + ", ".join(f"mu = {k}: {s['fill']['runs'][k]} of {s['fill']['cells'][k]} cells run"
                                              for k in s["fill"]["runs"]))
    for key, m in s["maps"].items():
        line = f"  mu = {key}: {m['buckled']} buckled, {m['stable']} stable"
        if m["failed"]:
            line += f", {m['failed']} failed"
        print(line)
        if m["mu"] > 0:
            if math.isfinite(m["exponent"]):
                print(f"    boundary v0 ~ dF^p with p = {m['exponent']:.3f} +/- {m['exponent_stderr']:.3f} "
                      f"(theory -1/2), from {len(m['boundary_dF'])} columns")
            else:
                print("    no boundary crossing inside the grid: widen --v0 or --dF")
            if "curve_v0" in m:
                found = sum(x is not None for x in m["curve_v0"])
                print(f"    searched boundary at {found} of {len(m['curve_v0'])} loads (rtol {m['curve_rtol']:g}, "
                      f"{sum(m['curve_evaluations'])} runs): p = {m['curve_exponent']:.3f} +/- "
                      f"{m['curve_exponent_stderr']:.3f}")
        largest = m["largest_stable_dF_over_F0cr"]
        print("    largest stable dF/F0cr seen: " + (f"{largest:.2f}" if largest is not None else "none (buckles everywhere)"))
    return 0


def register(sub) -> None:
    """`jaxrod map`: its arguments, checks and command."""
    mp = sub.add_parser("map", help="E3 stability map over (dF, v0): the main job")
    mp.add_argument("--mu", type=_finite_float, default=None,
                    help="friction coefficient (default: 0.3 and, in the same figure, 0)")
    mp.add_argument("--dF", type=_range_spec, default="0.5:64:20", help="LO:HI:N loads above F0_6 [N] (log-spaced), or a list A,B,C")
    mp.add_argument("--v0", type=_range_spec, default="0.001:0.2:24", help="LO:HI:N sine amplitudes [m/s] (log-spaced), or a list A,B,C")
    mp.add_argument("--model", choices=[*model_names(), "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    mp.add_argument("--n", type=_positive_int, default=None, help="nodes / modes (default: by the largest load)")
    mp.add_argument("--t1", type=_finite_float, default=None,
                    help="horizon [s] (default: the model's, 2 s; rod3d 0.4 s)")
    mp.add_argument("--out", default="out/map", help="output folder (default: out/map under the working folder)")
    mp.add_argument("--quiet", action="store_true", help="no progress bar")
    mp.add_argument("--no-curve", dest="no_curve", action="store_true",
                    help="do not search the boundary at every load (drawn over the grid, rtol 1e-3)")
    mp.add_argument("--fill", choices=["grid", "search"], default=None,
                    help="grid: run every cell; search: bisect each column for its boundary and label the rest "
                         "(right where columns are monotone; map.csv's ran column says which cells ran). "
                         "Default: the model's (rod3d search, the others grid)")
    _add_distributed_options(mp)
    mp.set_defaults(func=_cmd_map, check=_check_map, all_cores=True)
