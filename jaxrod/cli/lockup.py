"""`jaxrod lockup`: one rod injected into a long channel against a far-end load (the 3D rod)."""

from __future__ import annotations

import json
import math
import os
from ._checks import _check_lockup
from ._common import _finite_float, _positive_int


def _cmd_lockup(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    import numpy as np

    from .._results import RESULTS
    from ..lockup import chain
    from ..lockup.closed_forms import HELICAL_LAWS, HELICAL_ONSETS
    from ..lockup.push import inject, push_rod, units
    from ..lockup.si import case, tubing
    from ..lockup.verdict import turn_resolution, verdict
    from ..output import write_csv

    # the values were checked by cli._checks (before any work); the rods are built here, in float64
    rod = tubing(**args.tubing) if args.tubing is not None else push_rod(args.mu_L, args.r_over_ell, args.mu)
    F0, ell = units(rod)
    c = case(rod)
    args.mu_L, args.r_over_ell = c["mu_L_over_ell"], c["r_over_ell"]
    if args.far_force is not None:
        args.far_load = args.far_force / F0
    w = float(rod.rho * rod.g)
    duration = args.push / args.speed
    if not args.quiet:
        print(f"lock-up: muL/ell = {args.mu_L:g}, r/ell = {args.r_over_ell:g}, mu = {args.mu:g} (L = {float(rod.L):.3g} m, "
              f"r = {1e3 * float(rod.R):.3g} mm, F0 = {F0:.4g} N, ell = {ell:.4g} m); far load {args.far_load:g} F0, "
              f"pushed {args.push:g} m at {1e3 * args.speed:g} mm/s")
    r = inject(rod, args.far_load * F0, args.speed, duration, unload=args.unload, n=args.n, n_save=args.n_save,
               damping=args.damping, progress=not args.quiet, scheme=args.scheme)
    l0 = float(rod.L) / int(r["n"])
    on_wall = r["wall_force"] > 0
    per_turn, angle = turn_resolution(r["theta"], l0, float(rod.R), on_wall)
    rows = [dict(t=r["t"][k], push=r["push"][k], far_displacement=r["u"][k, 0], F_in=r["F_in"][k], f_in=r["f_in"][k],
                 F_far=r["F_far"][k], f_far=r["f_far"][k], helical_over_ell=r["helical"][k] / ell,
                 sinusoidal_over_ell=r["sinusoidal"][k] / ell, stuck_fraction=r["stuck_fraction"][k],
                 max_wall_force_over_w=float(np.max(r["wall_force"][k])) / w, segments_per_turn=per_turn[k],
                 helix_angle_deg=angle[k]) for k in range(len(r["t"]))]
    loading = r["phase"] == 0
    told = verdict(r["push"][loading], r["u"][loading, 0], r["f_in"][loading], r["theta"][loading], l0, float(rod.R),
                   contact=on_wall[loading])
    tail = loading & (r["push"] >= 0.8 * float(np.max(r["push"][loading])))  # the last fifth of the push
    geometry = (float(rod.L), float(rod.EI), w, float(rod.R), args.mu)
    soft = {f"{onset} / {law}": float(chain.entry_force(args.far_load * F0, *geometry, helical_onset=onset,
                                                         helical_law=law)) / F0
            for onset in HELICAL_ONSETS for law in HELICAL_LAWS}
    summary = {
        "mu_L_over_ell": args.mu_L, "r_over_ell": args.r_over_ell, "mu": args.mu, "far_load_over_F0": args.far_load,
        "speed": args.speed, "push": args.push, "damping": args.damping, "unload": args.unload,
        "L": float(rod.L), "r": float(rod.R), "F0": F0, "ell": ell, "n_segments": int(r["n"]), "scheme": args.scheme, "dt": r["dt"],
        "entry_force_over_F0_last_fifth": [float(np.min(r["f_in"][tail])), float(np.max(r["f_in"][tail]))],
        "helical_over_ell_end": float(r["helical"][loading][-1] / ell),
        "sinusoidal_over_ell_end": float(r["sinusoidal"][loading][-1] / ell),
        "drag_over_F0": args.damping * float(rod.rho) * float(rod.L) * args.speed / F0,
        "soft_string_entry_force_over_F0": soft,
        "si": _in_si(rod, r, tail, loading, args.far_load * F0, F0, ell, soft),
        "verdict": {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in told.items()},
        "result": RESULTS.describe(r["result"]),
    }
    if args.unload:
        summary["unloading"] = _unloading(r, ell)
    os.makedirs(args.out, exist_ok=True)
    write_csv(os.path.join(args.out, "lockup.csv"), rows)
    with open(os.path.join(args.out, "lockup.json"), "w") as fh:
        json.dump(summary, fh, indent=1)
    _plot(r, summary, os.path.join(args.out, "lockup.png"))
    if args.json:
        print(json.dumps(summary))
    elif not args.quiet:
        lo, hi = summary["entry_force_over_F0_last_fifth"]
        print(f"  entry force over the last fifth of the push: {lo:.3f}-{hi:.3f} F0 (drag of the damping "
              f"{summary['drag_over_F0']:.3f} F0); helical {summary['helical_over_ell_end']:.2f} ell, "
              f"sinusoidal {summary['sinusoidal_over_ell_end']:.2f} ell")
        print("  soft string (onset / helical law): " + ", ".join(
            f"{k} {v:.3f}" if math.isfinite(v) else f"{k} locked up" for k, v in soft.items()))
        if args.unload:
            u = summary["unloading"]
            print(f"  pulled back: entry force over the last fifth {u['entry_force_over_F0_last_fifth'][0]:.3f}-"
                  f"{u['entry_force_over_F0_last_fifth'][1]:.3f} F0; at the end helical {u['helical_over_ell_end']:.2f} ell, "
                  f"sinusoidal {u['sinusoidal_over_ell_end']:.2f} ell, far end moved {1e3 * u['far_end_moved_m']:.1f} mm")
        si = summary["si"]
        print(f"  in SI: F0 = {F0:.4g} N, ell = {ell:.4g} m, far load {si['far_force_N']:.4g} N, entry force over the "
              f"last fifth {si['entry_force_N_last_fifth'][0]:.4g}-{si['entry_force_N_last_fifth'][1]:.4g} N, helical "
              f"{si['helical_m_end']:.3g} m; soft-string lock-up length {si['soft_string_lockup_length_m']:.4g} m")
        print(f"  verdict (jaxrod.lockup.verdict): {told['status']}: {told['reason']}")
        print(f"  result: {summary['result']}; wrote {args.out}/lockup.csv, lockup.json, lockup.png")
    return 0 if r["result"] == 0 else 1


TUBING_OPTIONS = (("--E", "Pa", "Young's modulus"), ("--od", "m", "outer diameter"),
                  ("--id", "m", "inner diameter (default 0: a solid rod)"), ("--density", "kg/m^3", "density"),
                  ("--weight", "N/m", "(buoyed) weight per length, with or instead of --density"),
                  ("--clearance", "m", "radial clearance: channel radius minus outer radius"),
                  ("--length", "m", "length"), ("--nu", "-", "Poisson's ratio (default 0.3)"))


def _in_si(rod, r, tail, loading, F_far, F0, ell, soft) -> dict:
    """The run's forces and lengths in N and m: F0, ell, the far load, the entry force over the last
    fifth, the helical extent at the end of the push, the soft string's entry forces and its lock-up
    length (default laws, unbounded push)."""
    import numpy as np

    from ..lockup import chain

    F_in = np.asarray(r["F_in"])[tail]
    EI, w = float(rod.EI), float(rod.rho * rod.g)
    return {"F0_N": F0, "ell_m": ell, "L_m": float(rod.L), "clearance_m": float(rod.R), "EI_Nm2": EI, "w_N_per_m": w,
            "far_force_N": F_far, "entry_force_N_last_fifth": [float(F_in.min()), float(F_in.max())],
            "helical_m_end": float(r["helical"][loading][-1]),
            "soft_string_entry_force_N": {k: v * F0 for k, v in soft.items()},
            "soft_string_lockup_length_m": float(chain.lockup_length(EI, w, float(rod.R), float(rod.mu_d)))}


def _unloading(r, ell) -> dict:
    """What the pull-back shows: the entry force over its last fifth (the rod sliding back out
    against friction and the far load), and what is left at its end — the extents, the largest
    wall force, how far the far end ended up from where it started (> 0: toward the far end)."""
    import numpy as np

    back = r["phase"] == 1
    top = float(np.max(r["push"]))
    tail = back & (r["push"] <= 0.2 * top)
    last = np.flatnonzero(back)[-1]
    return {"entry_force_over_F0_last_fifth": [float(np.min(r["f_in"][tail])), float(np.max(r["f_in"][tail]))],
            "entry_force_over_F0_end": float(r["f_in"][last]),
            "helical_over_ell_end": float(r["helical"][last] / ell),
            "sinusoidal_over_ell_end": float(r["sinusoidal"][last] / ell),
            "far_end_moved_m": float(r["u"][last, 0] - r["u"][0, 0]),
            "push_end_m": float(r["push"][last])}


def _plot(r, summary, path):
    from ..output import subplots

    fig, axes = subplots(1, 2, figsize=(11, 4))
    ell = summary["ell"]
    ax = axes[0]
    ax.plot(1e3 * r["push"], r["f_in"], label="entry force (3D rod)")
    ax.axhline(summary["far_load_over_F0"], color="k", lw=0.8, ls=":", label="far load")
    colors = ("tab:red", "tab:orange", "tab:green", "tab:purple")
    for (name, f), color in zip(summary["soft_string_entry_force_over_F0"].items(), colors):
        if f < 1e300:
            ax.axhline(f, lw=0.8, ls="--", label=f"soft string: {name}", color=color)
    ax.set_xlabel("push [mm]")
    ax.set_ylabel("force / F0")
    ax.legend(fontsize=7)
    ax = axes[1]
    ax.plot(1e3 * r["push"], r["helical"] / ell, label="helical")
    ax.plot(1e3 * r["push"], r["sinusoidal"] / ell, label="sinusoidal")
    ax.set_xlabel("push [mm]")
    ax.set_ylabel("extent / ell")
    ax.legend()
    fig.suptitle(f"muL/ell = {summary['mu_L_over_ell']:g}, r/ell = {summary['r_over_ell']:g}, mu = {summary['mu']:g}, "
                 f"far load {summary['far_load_over_F0']:g} F0, {1e3 * summary['speed']:g} mm/s")
    fig.savefig(path, dpi=110)


def register(sub) -> None:
    """`jaxrod lockup`: its arguments, checks and command."""
    lk = sub.add_parser("lockup", help="one rod injected into a long channel against a far-end load (the 3D rod; "
                        "docs/physics.md section 8)")
    lk.add_argument("--mu-L", dest="mu_L", type=_finite_float, default=None,
                    help="muL/ell of the case, on the reference rod's material (default 1)")
    lk.add_argument("--r-over-ell", type=_finite_float, default=None, help="clearance r/ell (default 0.02)")
    lk.add_argument("--mu", type=_finite_float, default=0.5, help="friction coefficient (default 0.5)")
    lk.add_argument("--far-load", type=_finite_float, default=None, help="far-end load in units of F0 (default 2.5)")
    lk.add_argument("--far-force", type=_finite_float, default=None, help="far-end load [N] (instead of --far-load)")
    si = lk.add_argument_group("a tubing in SI units (instead of --mu-L and --r-over-ell; jaxrod.lockup.si)")
    for flag, unit, what in TUBING_OPTIONS:
        si.add_argument(flag, type=_finite_float, default=None, help=f"{what} [{unit}]")
    lk.add_argument("--speed", type=_finite_float, default=5e-3, help="injection speed [m/s] (default 5e-3)")
    lk.add_argument("--push", type=_finite_float, default=0.3, help="how far the entry is pushed [m] (default 0.3)")
    lk.add_argument("--damping", type=_finite_float, default=20.0,
                    help="mass-proportional damping [1/s] that takes out the start's axial wave (default 20)")
    lk.add_argument("--unload", action="store_true", help="then pull the entry back as far")
    lk.add_argument("--n", type=_positive_int, default=None, help="segments (default: 16 per buckle wavelength)")
    lk.add_argument("--scheme", choices=["implicit", "leapfrog"], default="implicit",
                    help="time stepping: the implicit leapfrog at its own step (default) or the explicit one "
                         "at 0.3 of its limit")
    lk.add_argument("--n-save", type=_positive_int, default=201, help="saves per phase (default 201)")
    lk.add_argument("--out", default="out/lockup", help="output folder (default: out/lockup under the working folder)")
    lk.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    lk.add_argument("--quiet", action="store_true")
    lk.set_defaults(func=_cmd_lockup, check=_check_lockup)
