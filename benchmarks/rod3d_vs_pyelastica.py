"""The 3D Cosserat rod (`jaxrod.rod3d`) against PyElastica: speed and agreement, side by side.

The same rod, in free space, in both codes: the reference rod (nitinol, d = 1.5 mm, E = 77 GPa,
rho_v = 6450 kg/m^3, nu = 0.33) cut to L = 0.3 m, no channel, no contact, no friction, no
gravity, pinned at both ends (end nodes held, rotations free), straight and at rest except for
the lateral velocity v(s) = a sin(pi s / L) along y (the first bending mode). Same number of
segments n, same time step, same Verlet family (jaxrod: velocity Verlet, with its kick / drift
/ kick on positions and rotations; PyElastica: `PositionVerlet`), float64 in both.

Constants are made identical: PyElastica's shear coefficient (27/28 by default) is set to
jaxrod's kappa = 6(1 + nu)/(7 + 6 nu), and both use G = E / (2(1 + nu)). Rotary inertia:
jaxrod by default scales the transverse rotary inertia by alpha (`Rod3D.rotary_scale`,
alpha = 21.4 at n = 50 and 5.3 at n = 100 on this rod) so that the rotation-shear vibration
no longer sets the step; PyElastica's is unscaled. So:

1. **Speed** (alpha = jaxrod's default in both: PyElastica's transverse mass second moment of
   inertia is multiplied by the same alpha before `finalize()`), dt = 0.5 x
   `jaxrod.rod3d.step_limit`. That PyElastica's *unmodified* rod is unstable at this dt is
   checked and reported (`pyelastica_unscaled_stable`).
   - single rod: jaxrod = one compiled `_run` call (jaxrod.simulate) of `--steps` steps, timed with
     `jax.block_until_ready` after a warm-up call (compile time = first call - steady call);
     PyElastica = its integration loop (`PositionVerlet.step` in a Python loop, as
     `elastica.integrate` does without the progress bar) over the same steps. Min over
     `--repeats`. Target: jaxrod >= 1x PyElastica.
   - diagnostic: the same `_run` with `Rod3D.friction_step` replaced by the identity (a
     subclass defined here, not a jaxrod API). With no channel nothing is ever in contact, so
     the pass has nothing to do and the final state is checked to be identical; the ratio
     shows what that idle pass costs. Measured for the batch too.
   - the three single-rod runs are interleaved repeat by repeat (the machine is shared and
     noisy), and PyElastica runs again between the batch calls; PyElastica's steps/s is the
     best over all its runs, the one both ratios use.
   - batch: `jax.vmap` of `_run` over 64 amplitudes a in [0.5, 2] x `A0`, `--batch-steps` steps;
     per-rod throughput (rod-steps/s) against PyElastica's single-rod steps/s. Target >= 10x.
     And the same 64 rods as `jaxrod.sweep` runs 3D rods (`batch_lanes`): one XLA device per
     core (set here before JAX starts, as `jaxrod map` does), each running its share one rod at
     a time (`jax.pmap` of `lax.map` of `_run`).
2. **Agreement**: the midpoint lateral displacement y(L/2, t) after the same simulated time.
   (a) alpha = 1 in both (unmodified PyElastica, jaxrod with `rotary_scale=1.0`), dt = 0.5 x
   jaxrod's (much smaller) step limit at alpha = 1, horizon at least a quarter of the
   Euler-Bernoulli first period, covered in chunks of `--steps` / 10 steps (one `_run` call
   each), y compared after every chunk. The Euler-Bernoulli value (a / w1) sin(w1 t),
   w1 = (pi/L)^2 sqrt(EI / rho A), is reported as an independent (linear) reference. Three
   amplitudes: `A0` = 1 mm/s (7 um, linear: checks the linearised discrete system), `A_MID` =
   0.1 m/s (0.7 mm: the pinned rod stretches, its tension, reported as
   `max_tension_over_euler_load`, reaches about 0.7 Euler load and stiffens it) and `A_LARGE` =
   2 m/s (linear amplitude 14 mm = L/21: the tension reaches tens of Euler loads and sets the
   motion). The nonlinear cases are where the two codes' formulations may differ (PyElastica
   divides its couples by the cubed Voronoi dilatation and its stresses by the dilatation;
   jaxrod's forces are the gradient of an energy in the reference lengths). The main measure is the
   largest difference over the trajectory divided by the largest |y| (the final value may sit
   near a zero crossing). (b) alpha = jaxrod's default in both: the final midpoint
   displacement of the single-rod timing runs (a = `A0`).

    python benchmarks/rod3d_vs_pyelastica.py [--quick]

Needs the optional extra `pyelastica` (`pip install -e '.[pyelastica]'`); without it the script
says so and exits 0.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import math
import os
import platform
import sys
import time

import numpy as np

try:
    import elastica as ea
except ImportError as err:  # optional dependency: CI does not install it
    print(
        "rod3d_vs_pyelastica: PyElastica is not importable "
        f"({err}); install it with `pip install -e '.[pyelastica]'`. Nothing to benchmark."
    )
    sys.exit(0)

# one XLA device per core, as `jaxrod map` sets it (the `lanes` batch below runs one rod per device
# at a time); single-rod runs use the first device either way
from _common import with_devices, write_csv  # noqa: E402

os.environ["XLA_FLAGS"] = with_devices(os.environ.get("XLA_FLAGS", ""))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.rod3d import Rod3D, step_limit  # noqa: E402


L = 0.3  # m
A0 = 1e-3  # m/s: lateral velocity amplitude (midpoint displacement ~ A0 / w1 = 7 um)
A_MID = 0.1  # m/s: 0.7 mm, nonlinear (the pinned rod stretches: tension ~0.7 Euler load)
A_LARGE = 2.0  # m/s: linear amplitude 14 mm = L/21; stretching dominates (nonlinear)
BATCH = 64


@eqx.filter_jit
def _run(model, state, dt: float, steps: int):
    """`steps` steps of jaxrod's one engine (`jaxrod.simulate` with the 3D rod's default scheme,
    projected leapfrog, which without contact is velocity Verlet; no channel, so no buckling or
    stick stop), one compiled call. Returns ((q, v) at the end, steps taken, observables at the
    two saves)."""
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=False)
    sol = jr.simulate(model, jr.integrators.default_for(model, dt), *state, steps * dt, n_save=2, options=opts,
                      throw=False)
    return (sol.q_final, sol.v_final), sol.n_steps, sol.observables


# -- the two rods ---------------------------------------------------------------------------------

def jaxrod_model(n: int, rotary_scale=None) -> Rod3D:
    rod = jr.RodChannel.reference(0.0, L=L)
    return Rod3D(rod, n, channel=False, gravity=False, ends="pinned", rotary_scale=rotary_scale)


def mode_one(n: int) -> np.ndarray:
    return np.sin(np.pi * np.linspace(0.0, 1.0, n + 1))


class _Simulator(ea.BaseSystemCollection, ea.Constraints):
    pass


def pyelastica_rod(model: Rod3D, amplitude: float, alpha: float):
    """PyElastica's straight rod with jaxrod's constants: same E, G, rho, d, kappa; the
    transverse rotary inertia times `alpha` (1: PyElastica as shipped). Directors d1 = y,
    d2 = z, d3 = x, as `Rod3D.initial_state`."""
    rod, n = model.rod, model.n
    E, G, d, rho_v = (float(rod.E), float(rod.G), float(rod.d), float(rod.rho_v))
    area = math.pi * d**2 / 4
    r = ea.CosseratRod.straight_rod(
        n, np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), L, d / 2, rho_v,
        youngs_modulus=E, shear_modulus=G,
    )
    kGA = float(model.shear_coefficient) * G * area
    r.shear_matrix[0, 0, :] = kGA
    r.shear_matrix[1, 1, :] = kGA
    for k in (0, 1):
        r.mass_second_moment_of_inertia[k, k, :] *= alpha
        r.inv_mass_second_moment_of_inertia[k, k, :] /= alpha
    r.velocity_collection[1, :] = amplitude * mode_one(n)
    sim = _Simulator()
    sim.append(r)
    sim.constrain(r).using(ea.FixedConstraint, constrained_position_idx=(0, -1))
    sim.finalize()
    # finalize() copies the rod into PyElastica's memory block: check the edits survived
    assert np.allclose(r.shear_matrix[0, 0, :], kGA)
    J, J_inv = r.mass_second_moment_of_inertia, r.inv_mass_second_moment_of_inertia
    assert np.allclose(J_inv[0, 0, :] * J[0, 0, :], 1.0)
    return sim, r


def pyelastica_steps(sim, stepper, t: float, dt: float, steps: int) -> float:
    """PyElastica's integration loop (`elastica.integrate` without tqdm and print)."""
    t = np.float64(t)
    dt = np.float64(dt)
    for _ in range(steps):
        t = stepper.step(sim, t, dt)
    return t


# -- measurements -------------------------------------------------------------------------------

class _NoFrictionPass(Rod3D):
    """Diagnostic only: `Rod3D` without the friction pass. Without a channel no node is ever
    in contact (N = 0), so `friction_step` returns its input and this is the same run; it
    measures what that pass costs when it has nothing to do."""

    def friction_step(self, friction, table, Q, v, w, stuck, force, h):
        return v, w, stuck, force, jnp.zeros((), v.dtype), jnp.zeros((), v.dtype)


def best_of(fn, repeats: int):
    best, out = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def pyelastica_stable(model: Rod3D, dt: float, steps: int, alpha: float) -> bool:
    """Finite and bounded (|y| < 100 x the mode-one amplitude a / w1) after `steps` steps."""
    sim, r = pyelastica_rod(model, A0, alpha)
    with np.errstate(all="ignore"):
        pyelastica_steps(sim, ea.PositionVerlet(), 0.0, dt, steps)
        y = np.abs(r.position_collection[1])
    bound = 100 * A0 / euler_bernoulli_w1(model)
    return bool(np.all(np.isfinite(r.position_collection)) and np.max(y) < bound)


def euler_bernoulli_w1(model: Rod3D) -> float:
    return (math.pi / L) ** 2 * math.sqrt(float(model.rod.EI) / float(model.rod.rho))


def speed(n: int, steps: int, batch_steps: int, repeats: int) -> list[dict]:
    model = jaxrod_model(n)
    alpha = float(model.rotary_scale)
    s0 = model.initial_state(0.0, lateral_velocity=A0 * mode_one(n))
    dt = 0.5 * step_limit(model, s0[0])
    mid = n // 2

    def time_jaxrod():
        return best_of(lambda: jax.block_until_ready(_run(model, s0, dt, steps)), 1)

    bare = _NoFrictionPass(model.rod, n, channel=False, gravity=False, ends="pinned")

    def time_bare():
        return best_of(lambda: jax.block_until_ready(_run(bare, s0, dt, steps)), 1)

    def time_pyelastica():
        sim, r = pyelastica_rod(model, A0, alpha)  # from the same initial state each time
        return best_of(lambda: pyelastica_steps(sim, stepper, 0.0, dt, steps), 1)[0], r

    # warm-ups: jaxrod compiles; PyElastica's first steps compile numba kernels or load them
    # from its cache
    t0 = time.perf_counter()
    jax.block_until_ready(_run(model, s0, dt, steps))
    first = time.perf_counter() - t0
    jax.block_until_ready(_run(bare, s0, dt, steps))
    stepper = ea.PositionVerlet()
    t0 = time.perf_counter()
    sim, _ = pyelastica_rod(model, A0, alpha)
    pyelastica_steps(sim, stepper, 0.0, dt, 10)
    warm = time.perf_counter() - t0

    # side by side: the three single-rod runs interleaved, min over repeats of each
    t_jr = t_bare = t_pe = math.inf
    for _ in range(repeats):
        t, c = time_jaxrod()
        t_jr = min(t_jr, t)
        t, c_bare = time_bare()
        t_bare = min(t_bare, t)
        t, r = time_pyelastica()
        t_pe = min(t_pe, t)
    assert int(c[1]) == steps, "jaxrod froze the run early"
    assert np.array_equal(c_bare[0][0].x, c[0][0].x), "without the friction pass the run differs"
    y_jr = float(c[0][0].x[mid, 1])
    y_pe = float(r.position_collection[1, mid])
    unscaled_ok = pyelastica_stable(model, dt, min(steps, 2000), 1.0)

    # jaxrod, a batch of 64 amplitudes, interleaved with more PyElastica single-rod runs
    amps = A0 * np.linspace(0.5, 2.0, BATCH)
    states = jax.vmap(lambda a: model.initial_state(0.0, lateral_velocity=a * mode_one(n)))(jnp.asarray(amps))
    run_batch = eqx.filter_jit(jax.vmap(lambda m, s: _run(m, s, dt, batch_steps), (None, 0)))
    t0 = time.perf_counter()
    jax.block_until_ready(run_batch(model, states))
    first_b = time.perf_counter() - t0
    jax.block_until_ready(run_batch(bare, states))
    t_b = t_bb = math.inf
    for _ in range(max(1, repeats - 1)):
        t, cb = best_of(lambda: jax.block_until_ready(run_batch(model, states)), 1)
        t_b = min(t_b, t)
        t_bb = min(t_bb, best_of(lambda: jax.block_until_ready(run_batch(bare, states)), 1)[0])
        t_pe = min(t_pe, time_pyelastica()[0])
    # the same batch as jaxrod.sweep runs 3D rods: one lane per device (the rods of a device's share
    # one after another, `lax.map`), the devices in parallel
    D = jax.local_device_count()
    per = -(-BATCH // D)
    lanes_states = jax.tree_util.tree_map(
        lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], per * D - BATCH, 0)]).reshape((D, per) + a.shape[1:]), states)
    run_lanes = jax.pmap(lambda s: jax.lax.map(lambda x: _run(model, x, dt, batch_steps), s))
    jax.block_until_ready(run_lanes(lanes_states))
    t_l = math.inf
    for _ in range(max(1, repeats - 1)):
        t, cl = best_of(lambda: jax.block_until_ready(run_lanes(lanes_states)), 1)
        t_l = min(t_l, t)
    xl = np.asarray(cl[0][0].x).reshape((per * D,) + cl[0][0].x.shape[2:])[:BATCH]
    yb = np.asarray(cb[0][0].x[:, mid, 1])
    assert np.all(np.isfinite(np.asarray(cb[0][0].x))) and np.all(np.asarray(cb[1]) == batch_steps)
    # small amplitudes: y_mid / a is the same for every member (a check that vmap ran them all)
    linear_dev = float(np.max(np.abs(yb / amps / (yb[0] / amps[0]) - 1)))

    sps_jr, sps_pe = steps / t_jr, steps / t_pe
    rps_b = BATCH * batch_steps / t_b
    common = dict(n_segments=n, rotary_scale=round(alpha, 3), dt_s=dt)
    w1 = euler_bernoulli_w1(model)
    return [
        dict(test="steps_per_s_single", **common, steps=steps, batch=1, jaxrod=sps_jr, pyelastica=sps_pe,
             ratio=sps_jr / sps_pe, jaxrod_compile_s=first - t_jr, pyelastica_warmup_s=warm,
             note=f"pyelastica_unscaled_stable={unscaled_ok}"),
        dict(test="steps_per_s_single_no_friction_pass", **common, steps=steps, batch=1,
             jaxrod=steps / t_bare, pyelastica=sps_pe, ratio=steps / t_bare / sps_pe,
             note="diagnostic: the same _run with Rod3D.friction_step (idle here) skipped"),
        dict(test="rod_steps_per_s_batch", **common, steps=batch_steps, batch=BATCH, jaxrod=rps_b,
             pyelastica=sps_pe, ratio=rps_b / sps_pe, jaxrod_compile_s=first_b - t_b,
             note=f"pyelastica single rod; y/a spread over the batch {linear_dev:.1e}"),
        dict(test="rod_steps_per_s_batch_lanes", **common, steps=batch_steps, batch=BATCH,
             jaxrod=BATCH * batch_steps / t_l, pyelastica=sps_pe, ratio=BATCH * batch_steps / t_l / sps_pe,
             note=(f"{D} devices, one rod per device at a time (as jaxrod.sweep runs rod3d); largest difference "
                   f"from the vmapped batch {float(np.max(np.abs(xl - np.asarray(cb[0][0].x)))):.1e} m")),
        dict(test="rod_steps_per_s_batch_no_friction_pass", **common, steps=batch_steps, batch=BATCH,
             jaxrod=BATCH * batch_steps / t_bb, pyelastica=sps_pe, ratio=BATCH * batch_steps / t_bb / sps_pe,
             note="diagnostic: the batch with Rod3D.friction_step (idle here) skipped"),
        dict(test="agreement_y_mid_m", **common, steps=steps, batch=1, jaxrod=y_jr, pyelastica=y_pe,
             ratio=abs(y_jr - y_pe) / abs(y_pe), t_s=steps * dt,
             euler_bernoulli=A0 / w1 * math.sin(w1 * steps * dt),
             amplitude_m_per_s=A0, note="both alpha-scaled; ratio = |jaxrod - pyelastica| / |pyelastica|"),
    ]


def agreement(n: int, periods: float, steps: int, amplitude: float = A0) -> list[dict]:
    """alpha = 1 in both, over at least `periods` Euler-Bernoulli first periods, in chunks of
    `steps` steps (one `_run` call each; rotary_scale and the amplitude are dynamic, so one
    compilation serves every amplitude and both alphas), y compared after every chunk."""
    model = jaxrod_model(n, rotary_scale=1.0)
    s = model.initial_state(0.0, lateral_velocity=amplitude * mode_one(n))
    dt = 0.5 * step_limit(model, s[0])
    w1 = euler_bernoulli_w1(model)
    chunks = max(1, math.ceil(periods * 2 * math.pi / w1 / (steps * dt)))
    mid = n // 2
    y_jr = [float(s[0].x[mid, 1])]
    tension = 0.0
    t0 = time.perf_counter()
    for _ in range(chunks):
        s, _, obs = jax.block_until_ready(_run(model, s, dt, steps))
        y_jr.append(float(s[0].x[mid, 1]))
        tension = max(tension, float(-jnp.min(obs["axial_force"][-1])))
    t_jr = time.perf_counter() - t0
    y_jr = np.asarray(y_jr)

    sim, r = pyelastica_rod(model, amplitude, 1.0)
    stepper = ea.PositionVerlet()
    y_pe = [float(r.position_collection[1, mid])]
    t, t0 = 0.0, time.perf_counter()
    for _ in range(chunks):
        t = pyelastica_steps(sim, stepper, t, dt, steps)
        y_pe.append(float(r.position_collection[1, mid]))
    t_pe = time.perf_counter() - t0
    y_pe = np.asarray(y_pe)
    ts = np.arange(chunks + 1) * steps * dt
    y_eb = amplitude / w1 * np.sin(w1 * ts)
    peak = np.max(np.abs(y_pe))
    return [
        dict(test="agreement_y_mid_m", n_segments=n, rotary_scale=1.0, dt_s=dt, steps=steps * chunks, batch=1,
             jaxrod=y_jr[-1], pyelastica=y_pe[-1], ratio=abs(y_jr[-1] - y_pe[-1]) / abs(y_pe[-1]),
             t_s=ts[-1], euler_bernoulli=y_eb[-1],
             traj_rel_diff=float(np.max(np.abs(y_jr - y_pe)) / peak),
             jaxrod_vs_eb=abs(y_jr[-1] / y_eb[-1] - 1), pyelastica_vs_eb=abs(y_pe[-1] / y_eb[-1] - 1),
             amplitude_m_per_s=amplitude,
             max_tension_over_euler_load=tension / (math.pi**2 * float(model.rod.EI) / L**2),
             note=f"alpha=1 in both, a = {amplitude} m/s; {chunks + 1} saves; "
             f"wall: jaxrod {t_jr:.1f} s, pyelastica {t_pe:.1f} s"),
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="n = 50 only, fewer steps (about a minute)")
    ap.add_argument("--n", type=int, nargs="*", default=None, help="segments (default 50 100)")
    ap.add_argument("--steps", type=int, default=None, help="single-rod timed steps (default 20000)")
    ap.add_argument("--batch-steps", type=int, default=None, help="steps of the batch run (default 1000)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--periods", type=float, default=None, help="agreement horizon in first periods (0.25)")
    ap.add_argument("--out", default=None, help="CSV (default benchmarks/results/rod3d_vs_pyelastica.csv, "
                    "with _n<sizes> added for other sizes than 50 100, so that a --n 500 run keeps the default's)")
    a = ap.parse_args()
    ns = a.n or ([50] if a.quick else [50, 100])
    if a.out is None:
        tag = "" if ns == [50, 100] else "_n" + "_".join(map(str, ns))
        a.out = f"benchmarks/results/rod3d_vs_pyelastica{tag}.csv"
    steps = a.steps or (4000 if a.quick else 20000)
    batch_steps = a.batch_steps or (200 if a.quick else 1000)
    periods = a.periods or (0.1 if a.quick else 0.25)

    t_start = time.perf_counter()
    print(
        f"device {jax.devices()[0].device_kind} ({jax.default_backend()}), {os.cpu_count()} CPUs, "
        f"{platform.processor() or platform.machine()}; JAX {jax.__version__}, "
        f"PyElastica {importlib.metadata.version('pyelastica')}, "
        f"numba {importlib.metadata.version('numba')}; "
        f"float64; batch {BATCH}; L = {L} m, pinned ends, v_y = {A0} sin(pi s/L) m/s"
    )
    rows = []
    for n in ns:
        rows += speed(n, steps, batch_steps, a.repeats)
        for amp in (A0, A_MID, A_LARGE):
            rows += agreement(n, periods, max(1, steps // 10), amp)
    wall = time.perf_counter() - t_start

    print(f"\n{'test':38s} {'n':>4s} {'alpha':>6s} {'dt [s]':>9s} {'steps':>6s} {'batch':>5s} "
          f"{'jaxrod':>10s} {'PyElastica':>10s} {'ratio/diff':>10s}")
    for r in rows:
        print(f"{r['test']:38s} {r['n_segments']:4d} {r['rotary_scale']:6.2f} {r['dt_s']:9.3g} "
              f"{r['steps']:6d} {r['batch']:5d} {r['jaxrod']:10.4g} {r['pyelastica']:10.4g} "
              f"{r['ratio']:10.3g}  {r.get('note', '')}")
    for r in rows:
        if r["test"] == "steps_per_s_single":
            print(f"n = {r['n_segments']}: jaxrod compile {r['jaxrod_compile_s']:.1f} s, "
                  f"PyElastica build + first steps {r['pyelastica_warmup_s']:.1f} s")
        if "euler_bernoulli" in r:
            print(f"n = {r['n_segments']}, alpha = {r['rotary_scale']}, a = {r['amplitude_m_per_s']} m/s: "
                  f"y_mid at t = {r['t_s'] * 1e3:.2f} ms: "
                  f"jaxrod {r['jaxrod']:.6e}, PyElastica {r['pyelastica']:.6e}, Euler-Bernoulli "
                  f"{r['euler_bernoulli']:.6e} m; |jaxrod - PyElastica|/|PyElastica| = {r['ratio']:.2e}"
                  + (f", trajectory max diff / peak = {r['traj_rel_diff']:.2e}" if "traj_rel_diff" in r else ""))
    print(f"\nwall time {wall:.0f} s")

    write_csv(a.out, rows, verbose=True)


if __name__ == "__main__":
    main()
