"""`jaxrod boundary` and `jaxrod critical-load`: boundary curves by root finding."""

from __future__ import annotations

from ..registry import model_names, perturbation_names

import json
import math

from ._common import _add_rod_options, _fail, _finite_float, _plot_curve, _positive_int, _range_spec, _rod_from_args, _rtol, _write_rows
from ._checks import MIN_DF_BRACKET, _check_boundary, _check_critical_load


def _cmd_boundary(args) -> int:
    import os

    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from .. import boundary as bd
    from ..boundary import ROOT_RESULTS
    from ..stability_map import fit_power_law, theory_boundary

    from ..registry import recipe

    rod = _rod_from_args(args, args.mu)  # --mu, --dF, --n, --t1 and --method were checked by cli._checks
    # the sensitivities come with the departure rate's tangent runs; label bisection (the 3D rod)
    # would need a forward-mode run more per load, which compiles longer than the search: opt-in
    by_labels = (args.method or recipe(args.model).search_method) == "bisection"
    wanted = ("mu", "dF") if args.sensitivities or not by_labels else ()
    try:
        res, sens = bd.boundary_curve(rod, args.dF, model=args.model, n=args.n, bracket=(1e-5, 2.0), rtol=args.rtol,
                                      t1=args.t1, method=args.method, progress=not (args.quiet or args.json),
                                      sensitivities=wanted)
    except ValueError as err:
        _fail(str(err))
    v = np.asarray(res.root)
    ok = np.asarray(res.result) == 0
    nan = np.full(v.shape, math.nan)
    sens = {k: sens.get(k, nan) for k in ("mu", "dF")}
    rows = [dict(dF=float(f), v0_star=float(x) if o else None, evaluations=int(e), result=ROOT_RESULTS.messages[int(r)],
                 dv0_dmu=float(sm), dv0_ddF=float(sf))
            for f, x, e, r, o, sm, sf in zip(args.dF, v, np.asarray(res.evaluations), np.asarray(res.result), ok,
                                              np.asarray(sens["mu"]), np.asarray(sens["dF"]))]
    p, se, c = fit_power_law(args.dF[ok], v[ok]) if ok.sum() >= 2 else (math.nan, math.nan, math.nan)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        _write_rows(os.path.join(args.out, "boundary.csv"), rows)
        _plot_curve(args.out + "/boundary.png", args.dF, v, ok, theory_boundary(rod, args.dF),
                    p, se, c, "ΔF = F − F⁰₆ [N]", "v₀* [mm/s]", 1e3,
                    f"{args.model} model, μ = {args.mu:g}: critical sine mode-6 velocity")
    if args.json:
        print(json.dumps([{k: r[k] for k in ("dF", "v0_star", "evaluations", "result")} for r in rows]))
        return 0
    for r in rows:
        vs = "—" if r["v0_star"] is None else f"{1e3 * r['v0_star']:.5g} mm/s"
        print(f"dF = {r['dF']:8.4g} N  v0* = {vs:>14s}  ({r['evaluations']} evaluations, {r['result']})")
    print(f"fitted v0* ~ dF^p: p = {p:.3f} +/- {se:.3f} (single-mode theory -1/2)")
    if args.out:
        print(f"wrote {args.out}/boundary.csv and boundary.png")
    return 0


def _cmd_critical_load(args) -> int:
    import os

    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from .. import boundary as bd
    from ..boundary import ROOT_RESULTS
    from ..stability_map import fit_power_law

    R = args.realizations  # --mu, --amplitude, --max-dF, --n and --method were checked by cli._checks
    try:
        res, _ = bd.critical_load_curve(args.mu, args.amplitude, perturbation=args.perturbation, realizations=R,
                                        seed=args.seed, model=args.model, n=args.n, rtol=args.rtol, t1=args.t1,
                                        bracket=(MIN_DF_BRACKET, args.max_dF), method=args.method, sensitivities=(),
                                        progress=not args.json)
    except ValueError as err:
        _fail(str(err))
    F = np.asarray(res.root)
    ok = np.asarray(res.result) == 0
    rows = []
    for i, mu in enumerate(args.mu):
        good = F[i][ok[i]]
        row = dict(mu=float(mu), dF_star=float(np.mean(good)) if good.size else None,
                   evaluations=int(np.asarray(res.evaluations)[i].sum()),
                   result=ROOT_RESULTS.messages[int(np.asarray(res.result)[i].max())])
        if R > 1:
            row.update(dF_star_std=float(np.std(good, ddof=1)) if good.size > 1 else None,
                       dF_star_min=float(good.min()) if good.size else None,
                       dF_star_max=float(good.max()) if good.size else None, realizations_ok=int(good.size))
        rows.append(row)
    mean = np.array([r["dF_star"] if r["dF_star"] is not None else np.nan for r in rows])
    fin = np.isfinite(mean)
    p, se, c = fit_power_law(args.mu[fin], mean[fin]) if fin.sum() >= 2 else (math.nan, math.nan, math.nan)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        _write_rows(os.path.join(args.out, "critical_load.csv"), rows)
        _plot_curve(args.out + "/critical_load.png", args.mu, mean, fin, None, p, se, c, "μ", "ΔF* [N]", 1.0,
                    f"{args.model} model, {args.perturbation} perturbation, amplitude {args.amplitude:g}")
    if args.json:
        keys = ["mu", "dF_star", "evaluations", "result"] + (["dF_star_std", "dF_star_min", "dF_star_max"] if R > 1 else [])
        print(json.dumps([{k: r[k] for k in keys} for r in rows]))
        return 0
    for r in rows:
        fs = "—" if r["dF_star"] is None else f"{r['dF_star']:.5g} N"
        extra = f" (std {r['dF_star_std']:.3g} over {r['realizations_ok']})" if R > 1 and r.get("dF_star_std") else ""
        print(f"mu = {r['mu']:6.3g}  dF* = {fs:>12s}{extra}  ({r['evaluations']} evaluations, {r['result']})")
    print(f"fitted dF* ~ mu^p: p = {p:.3f} +/- {se:.3f} (single-mode theory: 2 for velocity, 1 for position)")
    return 0


def register_boundary(sub) -> None:
    """`jaxrod boundary`: its arguments, checks and command."""
    bd = sub.add_parser("boundary", help="critical sine velocity v0*(dF) by root search")
    bd.add_argument("--mu", type=_finite_float, default=0.3)
    bd.add_argument("--dF", type=_range_spec, default="1:60:6", help="LO:HI:N loads above F0_6 [N], or a list A,B,C")
    bd.add_argument("--model", choices=[*model_names(), "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    bd.add_argument("--n", type=_positive_int, default=None)
    bd.add_argument("--rtol", type=_rtol, default=1e-6, help="relative tolerance in (0, 0.5) (default 1e-6)")
    bd.add_argument("--t1", type=_finite_float, default=None,
                    help="horizon of a run [s] (default: the model's, 2 s; rod3d 0.4 s)")
    bd.add_argument("--sensitivities", action="store_true",
                    help="also dv0*/dmu and dv0*/ddF with label bisection (rod3d): one tangent run more per load")
    bd.add_argument("--out", default=None, help="folder for boundary.csv and boundary.png")
    bd.add_argument("--method", choices=["departure", "bisection"], default=None,
                    help="rod models: departure-rate secant (default) or label bisection (default for rod3d)")
    bd.add_argument("--json", action="store_true")
    bd.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_rod_options(bd)
    bd.set_defaults(func=_cmd_boundary, check=_check_boundary, all_cores=True)


def register_critical_load(sub) -> None:
    """`jaxrod critical-load`: its arguments, checks and command."""
    cl = sub.add_parser("critical-load", help="critical load dF*(mu) by root search")
    cl.add_argument("--mu", type=_range_spec, default="0.05:1:6", help="LO:HI:N friction coefficients, or a list A,B,C")
    cl.add_argument("--perturbation", choices=list(perturbation_names()),
                    default="sine")
    cl.add_argument("--amplitude", type=_finite_float, default=0.015,
                    help="m/s for velocities, N/m for random-position, m for random-shape")
    cl.add_argument("--realizations", type=_positive_int, default=1)
    cl.add_argument("--seed", type=int, default=0)
    cl.add_argument("--model", choices=[*model_names(), "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    cl.add_argument("--n", type=_positive_int, default=None)
    cl.add_argument("--max-dF", dest="max_dF", type=_finite_float, default=100.0, help="bracket top [N]")
    cl.add_argument("--rtol", type=_rtol, default=1e-6, help="relative tolerance in (0, 0.5) (default 1e-6)")
    cl.add_argument("--t1", type=_finite_float, default=2.0, help="horizon of a run [s] (default 2; E4's 3D runs 0.5)")
    cl.add_argument("--out", default=None)
    cl.add_argument("--method", choices=["departure", "bisection"], default=None,
                    help="rod models: departure-rate secant (default) or label bisection (default for rod3d)")
    cl.add_argument("--json", action="store_true")
    cl.set_defaults(func=_cmd_critical_load, check=_check_critical_load, all_cores=True)
