"""`jaxrod simulate`: one rod (single mode, Galerkin, field or the 3D rod)."""

from __future__ import annotations

from ..registry import model_names, perturbation_names

import json
import os

from ._common import _add_rod_options, _fail, _finite_float, _json_number, _positive_int, _rod_from_args
from ._checks import _check_simulate


def _cmd_simulate(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from ..registry import make_perturbation
    from ..scene import Scene

    rod = _rod_from_args(args, args.mu)  # the other values were checked by cli._checks
    if args.model == "rod3d":
        return _simulate_rod3d(args, rod)
    pert = make_perturbation(args.perturbation, args.amplitude, args.mode, jax.random.key(args.seed))
    scene = Scene(rod, args.dF, pert, args.model, args.n, args.mode, args.dt)
    try:
        problem = scene.resolve()  # the model built once
        sol = problem.run(t1=args.t1, n_save=args.n_save, throw=False)
    except ValueError as err:  # a step above the model's stability limit: given, or the default
        msg = str(err)
        if "dt" in msg:
            msg = "argument --dt: " + (msg if args.dt is not None
                                       else msg.rstrip(".") + f" (the default step of --model {args.model}).")
        _fail(msg)
    from .._results import RESULTS

    out = {
        "model": args.model,
        "perturbation": args.perturbation,
        "amplitude": args.amplitude,
        "mu": args.mu,
        "dF": args.dF,
        "F": float(scene.F),
        "n": scene.size(),
        "dt": problem.integrator.dt,
        "t1": args.t1,
        "buckled": bool(sol.buckled),
        "t_buckle": _json_number(sol.t_buckle),
        "dominant_mode": int(scene.recipe.dominant_mode(problem.model, sol.q_final)),
        "max_theta": float(jnp.max(sol.amplitude)),
        "stuck": bool(sol.stuck[-1]),
        "t_stop": float(sol.t_stop),
        "energy_balance_error": float(sol.energy_balance_error()),
        "result": RESULTS.describe(sol.result),
    }
    if args.plot:
        from ..figures.simulation import plot_simulation

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
    """`jaxrod simulate --model rod3d`: the 3D rod with any of the paper's perturbations (sine
    velocity, random velocity, random position, random shape) on its nodes."""
    import numpy as np

    from .. import theory
    from .._results import RESULTS
    from ..integrators.base import save_grid
    from ..modal import dominant_mode
    from ..rod3d import Rod3D, Rod3DRecipe, sine_velocity
    from ..experiments.rod3d import run

    args.control = args.control or "force"  # the defaults (checked by cli._checks: rod3d only)
    args.speed = 1e-3 if args.speed is None else args.speed
    n = Rod3DRecipe.default_segments if args.n is None else args.n  # the 3D scene's one default
    n_save = min(args.n_save, 1001)
    import jax

    from ..integrators import default_for, default_step
    from ..registry import make_perturbation
    from ..scene import Scene

    pert = make_perturbation(args.perturbation, args.amplitude, args.mode, jax.random.key(args.seed))
    F = float(theory.reference_load(rod)) + args.dF if args.control != "displacement" else 0.0
    if args.control == "load":  # a dead load at the free end: the scene of every model
        scene = Scene(rod, args.dF, pert, "rod3d", n, args.mode, args.dt)
        model = scene.model()  # built once: the problem below is resolved on it
        scheme = scene.scheme(model)
    else:  # held ends after a pre-compression, or a pushed end: the 3D rod's own controls
        model = Rod3D(rod, n, control=args.control, speed=args.speed, preload=F if args.control == "force" else 0.0)
        scheme = Rod3DRecipe().scheme_under(pert, model)  # the implicit default under a sine velocity below the wrinkling load
    limit = float(default_for(model, 1.0, scheme).step_limit(model))
    if args.dt is not None and not (0 < args.dt < limit):
        _fail(f"argument --dt: {args.dt!r} s is invalid: the step limit of this rod's scheme is {limit:.4g} s; "
              f"use 0 < dt < {limit:.4g} s.")
    if args.control == "load":
        problem = scene.resolve(model=model)
        dt, q0, v0 = problem.integrator.dt, problem.q0, problem.v0
    else:
        q0, v0 = model.initial_state(F, lateral_velocity=sine_velocity(model, args.amplitude, args.mode))
        dt = default_step(model, q0, scheme) if args.dt is None else args.dt
        if args.perturbation != "sine":
            q0, v0 = pert.initial_state(model, default_for(model, dt, scheme))
    threshold = float(model.buckle_threshold)  # held ends: half the amplitude that relieves ΔF
    try:
        sol = run(model, q0, v0, args.t1, n_save, dt, threshold=threshold, stop_on_buckle=args.control != "displacement", scheme=scheme,
                  stop_when_stuck=args.control != "displacement", save_state=args.export is not None,
                  progress=not args.quiet)
    except ValueError as err:
        _fail(str(err))
    if args.export is not None:
        from ..figures.export3d import animate, write_vtk

        try:
            every = max(1, n_save // 200)  # at most ~200 frames
            write_vtk(sol, model, args.export)
            animate(sol, model, os.path.join(args.export, "rod.gif"), every=every)
        except ImportError as err:
            _fail(f"argument --export: {err}")
    R = np.asarray(sol.observables["reaction"][:, 1])
    end_x = np.asarray(sol.observables["end_x"])
    i = int(np.argmax(R))
    out = {
        "model": "rod3d", "control": args.control, "n_segments": n, "perturbation": args.perturbation,
        "amplitude": args.amplitude, "mu": args.mu, "dF": args.dF if args.control != "displacement" else None,
        "F": F, "speed": args.speed if args.control == "displacement" else None,
        "dt": save_grid(args.t1, n_save, dt)[1], "t1": args.t1, "buckle_threshold": threshold,
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
        print(f"rod3d ({n} segments, {args.control} control), mu = {args.mu:g}, {args.perturbation} "
              f"amplitude {args.amplitude:g}: {'BUCKLED' if out['buckled'] else 'not buckled'}")
        print(f"  max |theta| = {out['max_theta']:.4g} rad, peak reaction {out['peak_reaction']:.4g} N, "
              f"dominant mode {out['dominant_mode']}, energy balance error {out['energy_balance_error']:.2e} J, "
              f"result: {out['result']}")
    return 0 if int(sol.result) == 0 else 1


def register(sub) -> None:
    """`jaxrod simulate`: its arguments, checks and command."""
    sm = sub.add_parser("simulate", help="simulate one perturbed rod")
    sm.add_argument("--model", choices=[*model_names(), "auto"], default="field",
                    help="rod3d: the full 3D rod (jaxrod.rod3d); auto: the cheapest adequate model, "
                         "from the measured table (jaxrod.model_choice)")
    sm.add_argument("--control", choices=["force", "load", "displacement"], default=None,
                    help="rod3d only: ends held after pre-compression (force, the default), dead end load (load), "
                         "or one end pushed at --speed from zero load (displacement)")
    sm.add_argument("--speed", type=_finite_float, default=None,
                    help="rod3d displacement control only: pushing speed [m/s] (default 1e-3)")
    sm.add_argument("--dF", type=_finite_float, default=5.0, help="load above F0_m* [N] (default 5)")
    sm.add_argument("--mu", type=_finite_float, default=0.3, help="friction coefficient (default 0.3)")
    sm.add_argument("--perturbation", choices=list(perturbation_names()),
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
    sm.add_argument("--export", default=None, metavar="DIR",
                    help="rod3d: write a ParaView time series (DIR/rod.pvd, one .vtu per save) and DIR/rod.gif")
    sm.add_argument("--quiet", action="store_true", help="no progress bar (rod3d runs)")
    _add_rod_options(sm)
    sm.set_defaults(func=_cmd_simulate, check=_check_simulate)
