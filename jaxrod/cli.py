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


def _positive_int(text: str) -> int:
    try:
        x = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid integer: {text!r}") from None
    if x < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return x


def _cmd_simulate(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from .scene import Scene, make_perturbation

    if args.mu < 0:
        _fail(f"argument --mu: {args.mu!r} is invalid: a friction coefficient must be >= 0.")
    if args.amplitude < 0:
        _fail(f"argument --amplitude: {args.amplitude!r} is invalid: expected >= 0.")
    if args.t1 <= 0:
        _fail(f"argument --t1: {args.t1!r} is invalid: expected > 0 s.")
    if args.dt is not None and args.dt <= 0:
        _fail(f"argument --dt: {args.dt!r} is invalid: expected > 0 s.")
    if args.model == "field" and args.n is not None and args.n < 4:
        _fail(f"argument --n: {args.n!r} is invalid: the field model needs >= 4 nodes.")
    rod = _rod_from_args(args, args.mu)
    if args.model == "rod3d":
        return _simulate_rod3d(args, rod)
    pert = make_perturbation(args.perturbation, args.amplitude, args.mode, jax.random.key(args.seed))
    scene = Scene(rod, args.dF, pert, args.model, args.n, args.mode, args.dt)
    try:
        sol = scene.run(t1=args.t1, n_save=args.n_save, save_state=True, throw=False)
    except ValueError as err:
        _fail(str(err))
    from ._results import RESULTS

    out = {
        "model": args.model,
        "perturbation": args.perturbation,
        "amplitude": args.amplitude,
        "mu": args.mu,
        "dF": args.dF,
        "F": float(scene.F),
        "n": None if args.model == "mode" else (scene.nodes() if args.model == "field" else scene.model().n_modes),
        "dt": scene.step(),
        "t1": args.t1,
        "buckled": bool(sol.buckled),
        "t_buckle": _json_number(sol.t_buckle),
        "dominant_mode": int(scene.dominant_mode(sol.q_final)),
        "max_theta": float(jnp.max(sol.amplitude)),
        "stuck": bool(sol.stuck[-1]),
        "t_stop": float(sol.t_stop),
        "energy_balance_error": float(sol.energy_balance_error()),
        "result": RESULTS.describe(sol.result),
    }
    if args.plot:
        from .figures.simulation import plot_simulation

        plot_simulation(scene, sol, args.plot)
    if args.json:
        print(json.dumps(out))
    else:
        verdict = "BUCKLED" if out["buckled"] else ("stuck (stable)" if out["stuck"] else "not buckled")
        print(f"{args.model} model, F = {out['F']:.4g} N (dF = {args.dF:g} N), mu = {args.mu:g}, "
              f"{args.perturbation} amplitude {args.amplitude:g}: {verdict}")
        if out["buckled"]:
            print(f"  t_buckle = {out['t_buckle']:.4g} s, dominant mode {out['dominant_mode']}")
        else:
            print(f"  stopped at t = {out['t_stop']:.4g} s, dominant mode {out['dominant_mode']}")
        print(f"  max |theta| = {out['max_theta']:.4g} rad, energy balance error "
              f"{out['energy_balance_error']:.2e}, result: {out['result']}")
        if args.plot:
            print(f"  wrote {args.plot}")
    return 0 if int(sol.result) == 0 else 1


def _simulate_rod3d(args, rod) -> int:
    """`jaxrod simulate --model rod3d`: the 3D rod with a sine lateral velocity perturbation."""
    import numpy as np

    from . import theory
    from ._results import RESULTS
    from .integrators.base import save_grid
    from .modal import dominant_mode
    from .rod3d import Rod3D, sine_velocity, step_limit
    from .experiments.rod3d import run

    if args.perturbation != "sine":
        _fail(f"argument --perturbation: {args.perturbation!r} is not available with --model rod3d; use 'sine'.")
    if args.speed < 0:
        _fail(f"argument --speed: {args.speed!r} is invalid: expected >= 0 m/s.")
    n = 60 if args.n is None else args.n
    if n < 4:
        _fail(f"argument --n: {n!r} is invalid: the 3D rod needs >= 4 segments.")
    F = float(theory.frictionless_load(rod, 6)) + args.dF if args.control != "displacement" else 0.0
    model = Rod3D(rod, n, control=args.control, speed=args.speed, end_load=F if args.control == "load" else 0.0)
    q0, v0 = model.initial_state(F, lateral_velocity=sine_velocity(model, args.amplitude, args.mode))
    n_save = min(args.n_save, 1001)
    limit = step_limit(model, q0)
    if args.dt is not None and not (0 < args.dt < limit):
        _fail(f"argument --dt: {args.dt!r} s is invalid: the explicit step limit of this rod is {limit:.4g} s; "
              f"use 0 < dt < {limit:.4g} s.")
    dt = 0.5 * limit if args.dt is None else args.dt
    try:
        sol = run(model, q0, v0, args.t1, n_save, dt, stop_on_buckle=args.control != "displacement",
                  stop_when_stuck=args.control != "displacement")
    except ValueError as err:
        _fail(str(err))
    R = np.asarray(sol.observables["reaction"][:, 1])
    end_x = np.asarray(sol.observables["end_x"])
    i = int(np.argmax(R))
    out = {
        "model": "rod3d", "control": args.control, "n_segments": n, "perturbation": "sine",
        "amplitude": args.amplitude, "mu": args.mu, "dF": args.dF if args.control != "displacement" else None,
        "F": F, "speed": args.speed if args.control == "displacement" else None,
        "dt": save_grid(args.t1, n_save, dt)[1], "t1": args.t1,
        "buckled": bool(sol.buckled), "t_buckle": _json_number(sol.t_buckle),
        "max_theta": float(np.max(np.asarray(sol.amplitude))),
        "dominant_mode": int(dominant_mode(sol.observables["theta"][-1, 1:-1])),
        "peak_reaction": float(R[i]), "end_displacement_at_peak": float(end_x[0] - end_x[i]),
        "twist_over_total_max": float(np.max(np.asarray(sol.energies["twist"] / sum(sol.energies.values())))),
        "energy_balance_error": float(np.max(np.abs(np.asarray(sol.energy_balance)))),
        "result": RESULTS.describe(sol.result),
    }
    if args.json:
        print(json.dumps(out))
    else:
        print(f"rod3d ({n} segments, {args.control} control), mu = {args.mu:g}, sine mode {args.mode} "
              f"amplitude {args.amplitude:g} m/s: {'BUCKLED' if out['buckled'] else 'not buckled'}")
        print(f"  max |theta| = {out['max_theta']:.4g} rad, peak reaction {out['peak_reaction']:.4g} N, "
              f"dominant mode {out['dominant_mode']}, energy balance error {out['energy_balance_error']:.2e} J, "
              f"result: {out['result']}")
    return 0 if int(sol.result) == 0 else 1


def _range_spec(text: str):
    """LO:HI:N -> N log-spaced values from LO to HI (linear if LO <= 0)."""
    import numpy as np

    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(f"{text!r} is not of the form LO:HI:N")
    try:
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not of the form LO:HI:N (numbers)") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or n < 1 or (n > 1 and hi <= lo):
        raise argparse.ArgumentTypeError(f"{text!r}: need finite LO < HI and N >= 1")
    if n == 1:
        return np.array([lo])
    return np.geomspace(lo, hi, n) if lo > 0 else np.linspace(lo, hi, n)


def _cmd_map(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from .stability_map import stability_map

    if args.mu is not None and args.mu < 0:
        _fail(f"argument --mu: {args.mu!r} is invalid: a friction coefficient must be >= 0.")
    if np.any(args.v0 <= 0):
        _fail(f"argument --v0: velocities must be > 0 m/s, got {args.v0.min()!r}.")
    mus = (0.3, 0.0) if args.mu is None else (args.mu,)
    print(f"stability map: {args.model} model, mu = {', '.join(f'{m:g}' for m in mus)}, "
          f"{len(args.dF)} x {len(args.v0)} grid, {jax.local_device_count()} device(s) "
          f"({jax.devices()[0].platform})")
    try:
        s = stability_map(mus, args.dF, args.v0, args.model, args.n, 6, args.out,
                          progress=not args.quiet, t1=args.t1)
    except ValueError as err:
        _fail(str(err))
    print(f"n = {s['n']}, dt = {s['dt']:.3e} s; wrote {args.out}/map.png, map.csv, map.json")
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
        largest = m["largest_stable_dF_over_F0cr"]
        print("    largest stable dF/F0cr seen: " + (f"{largest:.2f}" if largest is not None else "none (buckles everywhere)"))
    return 0


def _write_rows(path, rows):
    from .output import write_csv

    write_csv(path, rows)


def _cmd_boundary(args) -> int:
    import os

    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from . import boundary as bd
    from .boundary import ROOT_RESULTS
    from .stability_map import fit_power_law, theory_boundary

    if args.mu < 0:
        _fail(f"argument --mu: {args.mu!r} is invalid: a friction coefficient must be >= 0.")
    if np.any(args.dF <= 0):
        _fail("argument --dF: loads above F0_6 must be > 0 N for a boundary to exist.")
    rod = _rod_from_args(args, args.mu)
    res, sens = bd.boundary_curve(rod, args.dF, model=args.model, n=args.n, bracket=(1e-5, 2.0), rtol=args.rtol)
    v = np.asarray(res.root)
    ok = np.asarray(res.result) == 0
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

    from . import boundary as bd
    from .boundary import ROOT_RESULTS
    from .stability_map import fit_power_law

    if np.any(args.mu <= 0):
        _fail("argument --mu: friction coefficients must be > 0 (no frictional boundary at mu = 0).")
    if args.amplitude <= 0:
        _fail(f"argument --amplitude: {args.amplitude!r} is invalid: expected > 0.")
    R = args.realizations
    res, _ = bd.critical_load_curve(args.mu, args.amplitude, perturbation=args.perturbation, realizations=R,
                                    seed=args.seed, model=args.model, n=args.n, rtol=args.rtol,
                                    bracket=(1e-3, args.max_dF))
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


def _plot_curve(path, x, y, ok, theory_y, p, se, c, xlabel, ylabel, scale, title):
    import numpy as np

    from .output import subplots

    fig, ax = subplots(figsize=(6.4, 4.6))
    ax.plot(x[ok], scale * y[ok], "o", label="jaxrod (root search)")
    if theory_y is not None:
        ax.plot(x, scale * np.asarray(theory_y), "k--", label="single-mode theory")
    if math.isfinite(p):
        xs = np.geomspace(x[ok].min(), x[ok].max(), 100)
        ax.plot(xs, scale * c * xs**p, "-", label=f"fit: ∝ x^({p:.3f} ± {se:.3f})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _cmd_reproduce(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from .reproduce import reproduce

    which = ["all"] if "all" in args.which else args.which
    try:
        res = reproduce(which, args.out, quick=args.quick, progress=not args.quiet)
    except ValueError as err:
        _fail(str(err))
    print(f"wrote {args.out}/results.json and figures under {args.out}/<experiment>/")
    for name, r in res.items():
        print(f"  {name}: {r.get('seconds', '?')} s")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from ._version import __version__

    p = _Parser(prog="jaxrod", description="Dynamics and stability of a rod in a channel with dry friction.")
    p.add_argument("--version", action="version", version=f"jaxrod {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    t = sub.add_parser("theory", help="analytic loads and stable-zone intercepts (PHYSICS.md P3-P7)")
    t.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    t.add_argument("--dF", type=_finite_float, default=None, help="load above F0_m [N]")
    t.add_argument("--mode", type=int, default=None, help="mode m (default: the critical mode)")
    t.add_argument("--json", action="store_true", help="print one JSON object")
    _add_rod_options(t)
    t.set_defaults(func=_cmd_theory)

    sm = sub.add_parser("simulate", help="simulate one perturbed rod")
    sm.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="rod3d: the full 3D rod (jaxrod.rod3d); auto: the cheapest adequate model, "
                         "from the measured table (jaxrod.model_choice)")
    sm.add_argument("--control", choices=["force", "load", "displacement"], default="force",
                    help="rod3d only: ends held after pre-compression (force), dead end load (load), "
                         "or one end pushed at --speed from zero load (displacement)")
    sm.add_argument("--speed", type=_finite_float, default=1e-3, help="rod3d displacement control: pushing speed [m/s] (default 1e-3)")
    sm.add_argument("--dF", type=_finite_float, default=5.0, help="load above F0_m* [N] (default 5)")
    sm.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    sm.add_argument("--perturbation", choices=["sine", "random-velocity", "random-position", "random-shape"],
                    default="sine")
    sm.add_argument("--amplitude", type=_finite_float, default=0.02,
                    help="m/s (sine, random-velocity); N/m force for 1 ms (random-position); "
                         "m (random-shape); default 0.02")
    sm.add_argument("--mode", type=_positive_int, default=6, help="sine / single mode number (default 6)")
    sm.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sm.add_argument("--n", type=_positive_int, default=None, help="nodes (field; default 128, 384 past 32 unstable modes) or modes (galerkin, 32)")
    sm.add_argument("--dt", type=_finite_float, default=None, help="time step [s] (default: 0.4 of the limit)")
    sm.add_argument("--t1", type=_finite_float, default=2.0, help="horizon [s] (default 2)")
    sm.add_argument("--n-save", dest="n_save", type=_positive_int, default=2001, help="saved times (default 2001)")
    sm.add_argument("--json", action="store_true", help="print one JSON object")
    sm.add_argument("--plot", default=None, help="write theta(s,t) and the modal spectrum to this PNG")
    _add_rod_options(sm)
    sm.set_defaults(func=_cmd_simulate)

    mp = sub.add_parser("map", help="E3 stability map over (dF, v0): the main job")
    mp.add_argument("--mu", type=_finite_float, default=None,
                    help="friction coefficient (default: 0.3 and, in the same figure, 0)")
    mp.add_argument("--dF", type=_range_spec, default="0.5:64:20", help="LO:HI:N loads above F0_6 [N] (log-spaced)")
    mp.add_argument("--v0", type=_range_spec, default="0.001:0.2:24", help="LO:HI:N sine amplitudes [m/s] (log-spaced)")
    mp.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    mp.add_argument("--n", type=_positive_int, default=None, help="nodes / modes (default: by the largest load)")
    mp.add_argument("--t1", type=_finite_float, default=2.0, help="horizon [s] (default 2)")
    mp.add_argument("--out", default="results/map", help="output folder (default results/map)")
    mp.add_argument("--quiet", action="store_true", help="no progress bar")
    mp.set_defaults(func=_cmd_map)

    bd = sub.add_parser("boundary", help="critical sine velocity v0*(dF) by root search")
    bd.add_argument("--mu", type=_finite_float, default=0.3)
    bd.add_argument("--dF", type=_range_spec, default="1:60:6", help="LO:HI:N loads above F0_6 [N]")
    bd.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    bd.add_argument("--n", type=_positive_int, default=None)
    bd.add_argument("--rtol", type=_finite_float, default=1e-6, help="relative tolerance (default 1e-6)")
    bd.add_argument("--out", default=None, help="folder for boundary.csv and boundary.png")
    bd.add_argument("--json", action="store_true")
    _add_rod_options(bd)
    bd.set_defaults(func=_cmd_boundary)

    cl = sub.add_parser("critical-load", help="critical load dF*(mu) by root search")
    cl.add_argument("--mu", type=_range_spec, default="0.05:1:6", help="LO:HI:N friction coefficients")
    cl.add_argument("--perturbation", choices=["sine", "random-velocity", "random-position", "random-shape"],
                    default="sine")
    cl.add_argument("--amplitude", type=_finite_float, default=0.015,
                    help="m/s for velocities, N/m for random-position, m for random-shape")
    cl.add_argument("--realizations", type=_positive_int, default=1)
    cl.add_argument("--seed", type=int, default=0)
    cl.add_argument("--model", choices=["mode", "galerkin", "field", "rod3d", "auto"], default="field",
                    help="auto: the cheapest adequate model, from the measured table (jaxrod.model_choice)")
    cl.add_argument("--n", type=_positive_int, default=None)
    cl.add_argument("--max-dF", dest="max_dF", type=_finite_float, default=100.0, help="bracket top [N]")
    cl.add_argument("--rtol", type=_finite_float, default=1e-6)
    cl.add_argument("--out", default=None)
    cl.add_argument("--json", action="store_true")
    cl.set_defaults(func=_cmd_critical_load)

    rp = sub.add_parser("reproduce", help="reproduce the paper's experiments E1-E6 (E1 and E6's full-model part with the 3D rod) "
                        "and the post-buckling helix/hysteresis experiment")
    rp.add_argument("which", nargs="+", choices=["e1", "e2", "e3", "e4", "e5", "e6", "helix", "all"])
    rp.add_argument("--out", default="results/paper")
    rp.add_argument("--quick", action="store_true", help="coarser, fewer realizations: a few minutes")
    rp.add_argument("--quiet", action="store_true")
    rp.set_defaults(func=_cmd_reproduce)

    fg = sub.add_parser("figure", help="write a figure")
    fg.add_argument("which", choices=["phase"], help="phase: E2 phase portraits")
    fg.add_argument("--out", default="results", help="output folder (default: results)")
    fg.set_defaults(func=_cmd_figure)
    return p


def _use_all_cpu_cores() -> None:
    """On a CPU-only machine, expose one XLA device per core so that sweeps shard their batch
    over every core (set before JAX starts its backend; an explicit XLA_FLAGS wins)."""
    import os

    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        n = os.cpu_count() or 1
        os.environ["XLA_FLAGS"] = (flags + f" --xla_force_host_platform_device_count={n}").strip()


def _resolve_auto_model(args) -> None:
    """`--model auto`: the model and resolution of `jaxrod.model_choice.choose_model` for the
    command's perturbation, its largest load (for critical-load: the bracket top --max-dF) and
    its largest μ; an explicit --n is kept. Says what it chose on stderr."""
    import numpy as np

    from .model_choice import choose_model

    dF = args.max_dF if args.command == "critical-load" else float(np.max(args.dF))
    mu = 0.3 if args.mu is None else float(np.max(args.mu))  # map: μ = 0.3 (and 0) by default
    try:
        model, n = choose_model(getattr(args, "perturbation", "sine"), dF, mu)
    except ValueError as err:
        _fail(str(err))
    args.model = model
    args.n = n if args.n is None else args.n
    sys.stderr.write(f"jaxrod: --model auto chose the {model} model"
                     + (f" with n = {args.n}" if args.n is not None else "") + "\n")


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if getattr(args, "model", None) == "auto":
        _resolve_auto_model(args)
    if args.command in ("map", "boundary", "critical-load", "reproduce"):
        _use_all_cpu_cores()
    return args.func(args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
