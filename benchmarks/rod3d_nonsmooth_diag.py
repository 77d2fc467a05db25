"""Where the 3D rod's implicit step goes wrong, and what the coupled friction solve changes: the
diagnostic runs behind docs/rod3d.md, "The implicit step" (issue [nonsmooth3d]). Each
subcommand prints one JSON line per result; the committed lines are in
`benchmarks/results/rod3d_nonsmooth_diag.jsonl` with the commit whose code ran them.

    python benchmarks/rod3d_nonsmooth_diag.py e4 --scheme local --dt 2e-5 1e-5     # E4 C, mu 0.05 (~3-5 min a step)
    python benchmarks/rod3d_nonsmooth_diag.py e4 --scheme coupled --dt 5e-5        # (~7 min)
    python benchmarks/rod3d_nonsmooth_diag.py e4 --gamma 0 --dt 5e-5 2e-5 1e-5     # without the numerical damping
    python benchmarks/rod3d_nonsmooth_diag.py e4 --adaptive 1e-2 1e-9 --dt 5e-5    # error-controlled steps up to dt
    python benchmarks/rod3d_nonsmooth_diag.py e4-forcing --mu 0.05                 # its forcing phase explicit
    python benchmarks/rod3d_nonsmooth_diag.py e4-warmup --tau 0.02 0.1             # and its first tau s
    python benchmarks/rod3d_nonsmooth_diag.py wrinkle                              # the 61 N rod, seeded (~2 min)
    python benchmarks/rod3d_nonsmooth_diag.py gamma-layer                          # gamma's effect against the step (~1 min)
    python benchmarks/rod3d_nonsmooth_diag.py e4-gates --gamma 0 --dt 2e-5         # E4 B and C, mu 0.05/0.3/1, 3 realizations
    python benchmarks/rod3d_nonsmooth_diag.py adaptive-steps --n 60 500            # the error-controlled step on E4 C
    python benchmarks/rod3d_nonsmooth_diag.py adaptive-damped --n 60 500 --gamma 0.1  # and with gamma, on E3's run
    python benchmarks/rod3d_nonsmooth_diag.py b-ends --scheme coupled               # E4 B's bracket ends, one scheme
    python benchmarks/rod3d_nonsmooth_diag.py b-decay --scheme coupled --dt 1e-5 5e-6  # E4 B's first 0.1 s: energy, stick
    python benchmarks/rod3d_nonsmooth_diag.py spin                                 # a free spinning rod's angular momentum
    python benchmarks/rod3d_nonsmooth_diag.py vstar --scheme coupled --n 60 --dF 5 20
    python benchmarks/rod3d_nonsmooth_diag.py modes --n 500 --dF 40 60            # the straight rod's spectrum

- `e4`: E4 case C (random position ±2 N/m for 1 ms, realization 0) at μ = 0.05, 500 segments, the
  implicit scheme forced on the random perturbation (`implicit_3d`), ΔF* by bisection to 1 %, at
  each step (explicit reference: results/paper/e4/rod3d_n500.csv, 1.3956–1.4000 N);
- `wrinkle`: the rod at F⁰₆ + 60 N, 500 segments, sine 1 µm/s plus node velocities 1e-9 m/s
  (normal, seed 1) along z: the largest vertical displacement over 0.04 s, friction at the
  contact point or at the axis, local pass at 2e-5 and 5e-5 s, coupled at 5e-5 s;
- `vstar`: E3's v₀* at a sine mode-6 velocity (boundary_curve, rtol 3e-3, horizon 0.4 s);
- `modes`: the lowest eigenvalues of M^{-1/2} H M^{-1/2} of the straight loaded rod on the wall,
  and the lowest whose eigenvector moves mostly along z (the wrinkle into the wall).
"""

from __future__ import annotations

import argparse
import json
import time

import jax

jax.config.update("jax_enable_x64", True)
import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import theory  # noqa: E402
from jaxrod.integrators import SCHEMES, ImplicitLeapfrog  # noqa: E402
from jaxrod.rod3d import Rod3D, sine_velocity  # noqa: E402


def _scheme(name, damping=0.1):
    class Chosen(ImplicitLeapfrog):
        coupled: bool = eqx.field(static=True, default=name == "coupled")
        gamma: float = eqx.field(static=True, default=damping)

    return Chosen


def _adaptive(r, a):
    class Adaptive(jr.AdaptiveImplicitLeapfrog):
        rtol: float = r
        atol: float = a

    return Adaptive


def e4(args):
    from jaxrod import perturbations
    from jaxrod.experiments.e4.rod3d import e4_point

    SCHEMES["implicit"] = _scheme(args.scheme, args.gamma) if args.adaptive is None else _adaptive(*args.adaptive)
    for c in (perturbations.RandomForce, perturbations.RandomVelocity):
        c.implicit_3d = True
    for dt in args.dt:
        Rod3D.implicit_step = dt
        t = time.perf_counter()
        row = e4_point("C", 0.05, 0, 500, t1=0.5, width=1.5)
        scheme = args.scheme if args.adaptive is None else f"adaptive rtol {args.adaptive[0]:g} atol {args.adaptive[1]:g}"
        print(json.dumps(dict(what="E4 C mu 0.05 dF* [N]", scheme=scheme, gamma=0.0 if args.adaptive else args.gamma,
                              dt=dt, lo=row["lo"], hi=row["hi"],
                              result=row["result"], runs=row["runs"], wall_s=round(time.perf_counter() - t, 1))), flush=True)


def e4_forcing(args):
    """E4 C with the implicit scheme forced (local pass, 5e-5 s) but its 1-ms forcing phase
    integrated by the explicit leapfrog at half its limit: how much of the error is that phase."""
    from jaxrod import perturbations
    from jaxrod.experiments.e4.rod3d import e4_point
    from jaxrod.rod3d import step_limit

    SCHEMES["implicit"] = _scheme(args.scheme)
    perturbations.RandomForce.implicit_3d = True
    run_phase = perturbations.RandomForce.initial_state

    # half the explicit limit of the reference rod at 500 segments under F⁰₆ + 10 N (the limit
    # barely moves with the load; the searched rod's numbers are traced)
    rod = jr.RodChannel.reference(0.3)
    h_explicit = 0.5 * float(step_limit(Rod3D(rod, 500, control="load", end_load=float(theory.reference_load(rod)) + 10.0)))

    def explicit_phase(self, model, integrator=None):
        if isinstance(integrator, ImplicitLeapfrog):
            integrator = jr.ProjectedLeapfrog(h_explicit)
        return run_phase(self, model, integrator)

    perturbations.RandomForce.initial_state = explicit_phase
    for mu in args.mu:
        t = time.perf_counter()
        row = e4_point("C", mu, 0, 500, t1=0.5, width=1.5)
        print(json.dumps(dict(what=f"E4 C mu {mu:g} dF* [N], forcing phase explicit", scheme=args.scheme, dt=5e-5,
                              lo=row["lo"], hi=row["hi"], result=row["result"], runs=row["runs"],
                              wall_s=round(time.perf_counter() - t, 1))), flush=True)


def e4_warmup(args):
    """E4 C with the implicit scheme forced (local pass, 5e-5 s) after the forcing phase and a
    first stretch of `tau` [s] of free motion both integrated by the explicit leapfrog at half its
    limit: whether small steps at the start alone (what an error-controlled step would take while
    the released segment-scale modes ring) bring ΔF* to the explicit value."""
    from jaxrod import perturbations
    from jaxrod.experiments.e4.rod3d import e4_point
    from jaxrod.rod3d import step_limit

    SCHEMES["implicit"] = _scheme(args.scheme)
    perturbations.RandomForce.implicit_3d = True
    run_phase = perturbations.RandomForce.initial_state
    rod = jr.RodChannel.reference(0.3)
    h_explicit = 0.5 * float(step_limit(Rod3D(rod, 500, control="load", end_load=float(theory.reference_load(rod)) + 10.0)))
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, early_exit=False, save_state=False)
    for tau in args.tau:
        def warm(self, model, integrator=None, tau=tau):
            if not isinstance(integrator, ImplicitLeapfrog):
                return run_phase(self, model, integrator)
            explicit = jr.ProjectedLeapfrog(h_explicit)
            q, v = run_phase(self, model, explicit)
            sol = explicit.integrate(model, q, v, tau, 2, opts, check_step_limit=False)
            return sol.q_final, sol.v_final

        perturbations.RandomForce.initial_state = warm
        t = time.perf_counter()
        row = e4_point("C", args.mu, 0, 500, t1=0.5, width=1.5)
        print(json.dumps(dict(what=f"E4 C mu {args.mu:g} dF* [N], forcing and the first tau explicit", scheme=args.scheme,
                              dt=5e-5, tau=tau, h_explicit=h_explicit, lo=row["lo"], hi=row["hi"], result=row["result"],
                              runs=row["runs"], wall_s=round(time.perf_counter() - t, 1))), flush=True)


def wrinkle(args):
    rod = jr.RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 60.0
    for fa, dt, coupled in (("axis", 2e-5, False), ("surface", 2e-5, False), ("surface", 5e-5, False),
                            ("surface", 5e-5, True)):
        m = Rod3D(rod, 500, control="load", end_load=F, friction_at=fa)
        q0, v0 = m.initial_state(None, lateral_velocity=sine_velocity(m, 1e-6))
        vz = 1e-9 * np.random.default_rng(1).normal(size=501)
        vz[0] = vz[-1] = 0
        v0 = type(v0)(v0.v.at[:, 2].set(jnp.asarray(vz)), v0.w, v0.stuck, v0.force, v0.residual, v0.sweeps)
        sol = jr.simulate(m, ImplicitLeapfrog(dt, coupled=coupled), q0, v0, 0.04, n_save=11,
                          options=jr.RunOptions(buckle_threshold=10.0, stop_on_buckle=False), throw=False)
        dz = np.abs(np.asarray(sol.q.x)[:, :, 2] - np.asarray(q0.x)[None, :, 2]).max(1)
        print(json.dumps(dict(what="max |dz| [m] every 4 ms, F0_6 + 60 N, 500 segments", friction_at=fa, dt=dt,
                              scheme="coupled" if coupled else "local", dz=[float(f"{d:.2e}") for d in dz])), flush=True)


def vstar(args):
    from jaxrod import boundary as bd

    SCHEMES["implicit"] = _scheme(args.scheme, args.gamma)
    Rod3D.implicit_step = args.dt
    rod = jr.RodChannel.reference(0.3)
    for dF in args.dF:
        t = time.perf_counter()
        res, _ = bd.boundary_curve(rod, [dF], model="rod3d", n=args.n, bracket=(1e-5, 2.0), rtol=3e-3, sensitivities=())
        print(json.dumps(dict(what="E3 v0* [mm/s]", scheme=args.scheme, gamma=args.gamma, dt=args.dt, n=args.n, dF=dF,
                              lo=1e3 * float(res.lo[0]), hi=1e3 * float(res.hi[0]), runs=int(res.evaluations[0]),
                              result=int(res.result[0]), wall_s=round(time.perf_counter() - t, 1))), flush=True)


def modes(args):
    from jaxrod.rod3d.hessian import hessian_blocks
    from jaxrod.rod3d.state import held_pattern

    rod = jr.RodChannel.reference(0.3)
    n = args.n
    for dF in args.dF:
        m = Rod3D(rod, n, control="load", end_load=float(theory.reference_load(rod)) + dF)
        q0, _ = m.initial_state()
        D, U = (np.asarray(b) for b in hessian_blocks(m, q0.x, q0.Q))
        H = np.zeros((6 * (n + 1),) * 2)
        for k in range(n + 1):
            H[6 * k:6 * k + 6, 6 * k:6 * k + 6] = D[k]
            if k < n:
                H[6 * k:6 * k + 6, 6 * k + 6:6 * k + 12] = U[k]
                H[6 * k + 6:6 * k + 12, 6 * k:6 * k + 6] = U[k].T
        held_n, held_s = held_pattern(m)
        free = np.concatenate([~held_n, np.concatenate([~held_s, np.zeros((1, 3), bool)])], -1).reshape(-1)
        mass = np.concatenate([np.repeat(np.asarray(m.mass)[:, None], 3, 1),
                               np.concatenate([np.repeat(np.asarray(m.inertia)[None], n, 0), np.ones((1, 3))])], -1)
        s = 1 / np.sqrt(mass.reshape(-1)[free])
        w, V = np.linalg.eigh(s[:, None] * H[np.ix_(free, free)] * s[None, :])
        idx = np.flatnonzero(free)
        z_first = None
        for j in range(len(w)):
            vec = np.zeros(6 * (n + 1))
            vec[idx] = s * V[:, j]
            comp = np.abs(vec.reshape(n + 1, 6)[:, :3]).sum(0)
            if comp[2] > 0.5 * comp.sum():
                z_first = float(w[j])
                break
        print(json.dumps(dict(what="omega^2 [1/s^2] of the straight rod on the wall", n=n, dF=dF, F=float(m.end_load),
                              lowest=float(w[0]), lowest_vertical=z_first,
                              wrinkling_load=float(m.wrinkling_load()))), flush=True)


def e4_gates(args):
    """E4 points under the random perturbations with the implicit scheme forced at `--dt` and
    `--gamma` (`--scheme`: the local friction pass or the coupled solve), each against the explicit point of results/paper/e4/rod3d_n500.csv at
    the same horizon (0.5 s): one line per point, with the explicit bracket and the midpoints'
    relative difference."""
    import csv

    from jaxrod import perturbations
    from jaxrod.experiments.e4.rod3d import e4_point

    ref = {(r["case"], float(r["mu"]), int(r["realization"])): r
           for r in csv.DictReader(open("results/paper/e4/rod3d_n500.csv"))
           if float(r["t1"]) == 0.5 and r["result"] == "0"}
    SCHEMES["implicit"] = _scheme(args.scheme, args.gamma)
    for c in (perturbations.RandomForce, perturbations.RandomVelocity):
        c.implicit_3d = True
    Rod3D.implicit_step = args.dt
    for case in args.cases:
        for mu in args.mu:
            for k in args.realizations:
                r = ref.get((case, mu, k))
                if r is None:
                    continue
                t = time.perf_counter()
                row = e4_point(case, mu, k, 500, t1=0.5)
                mid, ref_mid = 0.5 * (row["lo"] + row["hi"]), 0.5 * (float(r["lo"]) + float(r["hi"]))
                print(json.dumps(dict(what=f"E4 {case} mu {mu:g} realization {k} dF* [N], implicit forced",
                                      scheme=args.scheme, gamma=args.gamma,
                                      dt=args.dt, lo=row["lo"], hi=row["hi"], result=row["result"], runs=row["runs"],
                                      explicit_lo=float(r["lo"]), explicit_hi=float(r["hi"]),
                                      explicit_commit=r["commit"], midpoint_difference=mid / ref_mid - 1,
                                      wall_s=round(time.perf_counter() - t, 1))), flush=True)


def adaptive_steps(args):
    """The steps `AdaptiveImplicitLeapfrog` (γ = 0, largest step 5e-5 s) takes on E4 C's scene
    (μ = 0.05, ΔF = 1.39 N, random position ±2 N/m for 1 ms, realization 0) over `--t1` s, at
    `--n` segments and the tolerances `--rtol`, `--atol`: steps, rejections, smallest and largest
    step, against the explicit limit."""
    from jaxrod import perturbations
    from jaxrod.rod3d import step_limit

    SCHEMES["implicit"] = _adaptive(args.rtol, args.atol)
    for c in (perturbations.RandomForce, perturbations.RandomVelocity):
        c.implicit_3d = True
    Rod3D.implicit_step = 5e-5
    rod = jr.RodChannel.reference(0.05)
    key = jax.random.fold_in(jax.random.key(0), 0)
    for n in args.n:
        scene = jr.Scene(rod, 1.39, perturbation=jr.RandomForce(2.0, key), kind="rod3d", n=n)
        t = time.perf_counter()
        sol = scene.run(t1=args.t1, n_save=11, save_state=False)
        limit = float(step_limit(scene.model()))
        print(json.dumps(dict(what="adaptive steps on E4 C's scene", n=n, t1=args.t1, rtol=args.rtol, atol=args.atol,
                              result=int(sol.result), steps=int(sol.n_steps),
                              **{k: float(v) for k, v in sol.step_stats.items()}, explicit_limit=limit,
                              mean_step_over_limit=args.t1 / int(sol.n_steps) / limit,
                              wall_s=round(time.perf_counter() - t, 1))), flush=True)


def adaptive_damped(args):
    """E3's run (μ = 0.3, ΔF = `--dF`, sine mode 6 at `--v0`, `--t1` s, 11 saves) at each `--n`:
    the explicit leapfrog at half its limit (the reference), the fixed implicit step (γ = 0.1,
    5e-5 s) and `AdaptiveImplicitLeapfrog` with γ = `--gamma` at each `--rtol` (atol 1e-9 m,
    largest step `--dt-max`): each one's largest amplitude difference from the reference over the
    saves, relative to the reference's largest amplitude; steps, rejections, smallest and largest
    step against the explicit limit. Asks whether the controller, with γ taking the stiff modes it
    cannot resolve, steps as far as the fixed step and says what the error is."""
    from jaxrod.rod3d import step_limit

    rod = jr.RodChannel.reference(0.3)
    for n in args.n:
        ref = None
        runs = [("explicit", "leapfrog", None, None)] + [("fixed", None, None, None)]
        runs += [(f"adaptive rtol {r:g}", "adaptive", r, args.dt_max) for r in args.rtol]
        for name, key, rtol, dt in runs:
            if key == "adaptive":
                tol, damping = rtol, args.gamma

                class Adaptive(jr.AdaptiveImplicitLeapfrog):
                    rtol: float = tol
                    gamma: float = eqx.field(static=True, default=damping)

                SCHEMES["adaptive"] = Adaptive
            scene = jr.Scene(rod, args.dF, perturbation=jr.SineVelocity(args.v0, 6.0), kind="rod3d", n=n,
                             scheme_key=key, dt=dt)
            t = time.perf_counter()
            sol = scene.run(t1=args.t1, n_save=11, save_state=False)
            amp = np.asarray(sol.amplitude)
            wall = time.perf_counter() - t
            ref = amp if ref is None else ref
            limit = float(step_limit(scene.model()))
            stats = {k: float(v) for k, v in sol.step_stats.items()} if key == "adaptive" else {}
            print(json.dumps(dict(what="E3 run, adaptive steps with damping", n=n, dF=args.dF, v0=args.v0, t1=args.t1,
                                  scheme=name, gamma=args.gamma if key == "adaptive" else None,
                                  result=int(sol.result), steps=int(sol.n_steps), explicit_limit=limit,
                                  mean_step_over_limit=args.t1 / int(sol.n_steps) / limit, **stats,
                                  amplitude_end=float(amp[-1]),
                                  amplitude_diff=float(np.max(np.abs(amp - ref)) / np.max(np.abs(ref))),
                                  wall_s=round(wall, 1))), flush=True)


def b_ends(args):
    """E4 B (random velocity ±15 mm/s, realization 0) at μ = 0.05, 500 segments, 0.5 s, at the two
    ends of the search's bracket (1.352 and 3.043 N): buckled or not, when and the amplitude every
    50 ms, by the explicit leapfrog (`--scheme explicit`) or the implicit scheme forced (`local` or
    `coupled`, `--gamma`, `--dt`)."""
    from jaxrod import perturbations

    if args.scheme != "explicit":
        SCHEMES["implicit"] = _scheme(args.scheme, args.gamma)
        for c in (perturbations.RandomForce, perturbations.RandomVelocity):
            c.implicit_3d = True
        Rod3D.implicit_step = args.dt
    rod = jr.RodChannel.reference(0.05)
    key = jax.random.fold_in(jax.random.key(0), 0)
    for dF in (1.3523260915353308, 3.042733705954494):
        t = time.perf_counter()
        scene = jr.Scene(rod, dF, perturbation=jr.RandomVelocity(15e-3, key), kind="rod3d", n=500)
        sol = scene.run(t1=0.5, n_save=11, save_state=False)
        print(json.dumps(dict(what="E4 B mu 0.05 r0 at a bracket end, 0.5 s", scheme=args.scheme,
                              integrator=type(scene.integrator()).__name__, gamma=args.gamma, dt=args.dt, dF=dF,
                              buckled=bool(sol.buckled), t_buckle=float(sol.t_buckle), result=int(sol.result),
                              amplitude=[round(float(a), 4) for a in sol.amplitude],
                              wall_s=round(time.perf_counter() - t, 1))), flush=True)


def b_decay(args):
    """E4 B (random velocity ±15 mm/s, realization 0) at μ = 0.05, 500 segments, at the lower end
    of the bracket (1.352 N) for `--t1` s: every 1 ms the kinetic energy, the fraction of nodes
    stuck, the energy friction has dissipated and the amplitude, by the explicit leapfrog or the
    implicit scheme forced at each `--dt` (`--scheme`, `--gamma`). Asks whether the implicit step
    lets the random velocity's segment-scale energy live longer (fewer oscillations per second
    for friction to dissipate it), keeping the rod sliding where the explicit scheme sticks."""
    from jaxrod import perturbations

    rod = jr.RodChannel.reference(0.05)
    key = jax.random.fold_in(jax.random.key(0), 0)
    n_save = int(round(args.t1 / 1e-3)) + 1
    for dt in ([None] if args.scheme == "explicit" else args.dt):
        if dt is not None:
            SCHEMES["implicit"] = _scheme(args.scheme, args.gamma)
            for c in (perturbations.RandomForce, perturbations.RandomVelocity):
                c.implicit_3d = True
            Rod3D.implicit_step = dt
        t = time.perf_counter()
        scene = jr.Scene(rod, 1.3523260915353308, perturbation=jr.RandomVelocity(15e-3, key), kind="rod3d", n=500)
        sol = scene.run(t1=args.t1, n_save=n_save, save_state=False)
        ke = sol.energies["kinetic"]
        print(json.dumps(dict(what="E4 B mu 0.05 r0 at 1.352 N: decay of the random velocity", scheme=args.scheme,
                              integrator=type(scene.integrator()).__name__, gamma=args.gamma, dt=dt,
                              steps=int(sol.n_steps), t=[round(float(x), 4) for x in sol.ts],
                              kinetic=[float(x) for x in ke],
                              stuck_fraction=[round(float(x), 4) for x in sol.observables["stuck_fraction"]],
                              dissipated=[float(x) for x in sol.dissipated],
                              amplitude=[round(float(a), 5) for a in sol.amplitude],
                              result=int(sol.result), wall_s=round(time.perf_counter() - t, 1))), flush=True)


def spin(args):
    """A free 4-segment rod in space spinning (tests/test_rod3d.py's `_spinning_free_rod`), run for
    1000 explicit limits: the largest drift of its angular momentum about the origin relative to
    |L|, by the explicit leapfrog and by the implicit step without γ (local pass) at each
    `--fractions` of the explicit limit."""
    import sys

    sys.path.insert(0, "tests")
    from test_rod3d import _momenta, _spinning_free_rod
    from jaxrod.rod3d import step_limit

    model, q0, v0 = _spinning_free_rod()
    lim = float(step_limit(model))
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)
    for name in ("explicit", "implicit"):
        for f in args.fractions:
            if name == "explicit" and f >= 1:
                continue
            integ = jr.ProjectedLeapfrog(f * lim) if name == "explicit" else ImplicitLeapfrog(f * lim, gamma=0.0)
            sol = jr.simulate(model, integ, q0, v0, 1000 * lim, n_save=11, options=opts)
            _, ang = (np.asarray(a) for a in _momenta(model, sol.q, sol.v))
            print(json.dumps(dict(what="free spinning 4-segment rod: angular momentum drift / |L| over 1000 limits",
                                  scheme=name, step_over_limit=f, limit=lim, t1=1000 * lim, result=int(sol.result),
                                  drift=float(np.abs(ang - ang[0]).max() / np.linalg.norm(ang[0])))), flush=True)


def gamma_layer(args):
    """E3's start on 12 segments (sine mode 6 at 0.02 m/s on the nodes, segments not turning, F⁰₆ + 5 N,
    μ = 0.3) to 0.02 s: the largest lateral node displacement's difference from the explicit
    leapfrog at 0.05 of its limit, for the implicit step with γ = 0, 0.05, 0.1 at 0.05 and 0.2 of
    the explicit limit."""
    from jaxrod.rod3d import step_limit

    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 12, control="load", end_load=theory.reference_load(rod) + 5.0)
    q0, v0 = model.initial_state(None, lateral_velocity=sine_velocity(model, 0.02))
    lim = float(step_limit(model))
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False)

    def run(integ):
        return jax.jit(lambda q, v: jr.simulate(model, integ, q, v, 0.02, n_save=5, options=opts, throw=False))(q0, v0)

    ref = np.asarray(run(jr.ProjectedLeapfrog(0.05 * lim)).q.x[-1, :, 1:])
    for f in (0.05, 0.2):
        for g in (0.0, 0.05, 0.1):
            d = float(np.abs(np.asarray(run(ImplicitLeapfrog(f * lim, gamma=g)).q.x[-1, :, 1:]) - ref).max())
            print(json.dumps(dict(what="12-segment E3 start, 0.02 s: max lateral difference from explicit [m]",
                                  dt=f * lim, gamma=g, difference=d, lateral_scale=float(np.abs(ref).max()))), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("e4")
    p.add_argument("--scheme", choices=["local", "coupled"], default="local")
    p.add_argument("--gamma", type=float, default=0.1)
    p.add_argument("--adaptive", type=float, nargs=2, metavar=("RTOL", "ATOL"),
                   help="the error-controlled scheme (gamma 0) with its largest step --dt")
    p.add_argument("--dt", type=float, nargs="+", default=[5e-5])
    p = sub.add_parser("e4-forcing")
    p.add_argument("--scheme", choices=["local", "coupled"], default="local")
    p.add_argument("--mu", type=float, nargs="+", default=[0.05])
    p = sub.add_parser("e4-warmup")
    p.add_argument("--scheme", choices=["local", "coupled"], default="local")
    p.add_argument("--mu", type=float, default=0.05)
    p.add_argument("--tau", type=float, nargs="+", default=[0.02, 0.1])
    sub.add_parser("wrinkle")
    sub.add_parser("gamma-layer")
    p = sub.add_parser("b-ends")
    p.add_argument("--scheme", choices=["explicit", "local", "coupled"], default="coupled")
    p.add_argument("--gamma", type=float, default=0.0)
    p.add_argument("--dt", type=float, default=1e-5)
    p = sub.add_parser("adaptive-steps")
    p.add_argument("--n", type=int, nargs="+", default=[60, 500])
    p.add_argument("--t1", type=float, default=0.05)
    p.add_argument("--rtol", type=float, default=1e-2)
    p.add_argument("--atol", type=float, default=1e-9)
    p = sub.add_parser("adaptive-damped")
    p.add_argument("--n", type=int, nargs="+", default=[60, 500])
    p.add_argument("--dF", type=float, default=5.0)
    p.add_argument("--v0", type=float, default=0.02)
    p.add_argument("--t1", type=float, default=0.1)
    p.add_argument("--gamma", type=float, default=0.1)
    p.add_argument("--rtol", type=float, nargs="+", default=[1e-1, 1e-2, 1e-3])
    p.add_argument("--dt-max", type=float, default=2e-4)
    p = sub.add_parser("e4-gates")
    p.add_argument("--scheme", choices=["local", "coupled"], default="local")
    p.add_argument("--gamma", type=float, default=0.0)
    p.add_argument("--dt", type=float, default=2e-5)
    p.add_argument("--cases", nargs="+", default=["C", "B"])
    p.add_argument("--mu", type=float, nargs="+", default=[0.05, 0.3, 1.0])
    p.add_argument("--realizations", type=int, nargs="+", default=[0, 1, 2])
    p = sub.add_parser("vstar")
    p.add_argument("--scheme", choices=["local", "coupled"], default="coupled")
    p.add_argument("--gamma", type=float, default=0.1)
    p.add_argument("--dt", type=float, default=5e-5)
    p.add_argument("--n", type=int, default=60)
    p.add_argument("--dF", type=float, nargs="+", default=[5.0, 20.0])
    p = sub.add_parser("b-decay")
    p.add_argument("--scheme", choices=["explicit", "local", "coupled"], default="coupled")
    p.add_argument("--gamma", type=float, default=0.0)
    p.add_argument("--dt", type=float, nargs="+", default=[1e-5, 5e-6])
    p.add_argument("--t1", type=float, default=0.1)
    p = sub.add_parser("spin")
    p.add_argument("--fractions", type=float, nargs="+", default=[0.0625, 0.125, 0.25, 0.5, 1.0, 2.0, 5.0])
    p = sub.add_parser("modes")
    p.add_argument("--n", type=int, default=500)
    p.add_argument("--dF", type=float, nargs="+", default=[40.0, 60.0])
    args = ap.parse_args()
    {"e4": e4, "e4-forcing": e4_forcing, "e4-warmup": e4_warmup, "wrinkle": wrinkle, "vstar": vstar, "modes": modes,
     "gamma-layer": gamma_layer, "e4-gates": e4_gates, "adaptive-steps": adaptive_steps,
     "adaptive-damped": adaptive_damped, "b-ends": b_ends, "b-decay": b_decay, "spin": spin}[args.cmd](args)


if __name__ == "__main__":
    main()
