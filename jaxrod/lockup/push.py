r"""The lock-up scene with the 3D rod: a rod pushed into a long horizontal channel by a slowly
rising entry force, its far end held against a load cell (docs/physics.md §8, issue [lockup]).

A case is dimensionless (P8): μL/ℓ and r/ℓ, with ℓ = √(EI/(r w)) and F₀ = √(EI w/r).
[`push_rod`][jaxrod.lockup.push.push_rod] makes the rod and channel that realize it from a
material (its d, E, ρ_v, ν and g; default the reference rod's nitinol): EI and the weight per
length w do not depend on r or L, so r = (ρ² EI/w)^{1/3} for ρ = r/ℓ, then ℓ = r/ρ and
L = (μL/ℓ) ℓ/μ. Two materials with the same μL/ℓ and r/ℓ are the same case in these units.

[`push`][jaxrod.lockup.push.push] runs [`jaxrod.rod3d.Rod3D`][]: the far end (node 0) held in
place, its axial support force the load cell's reading; the entry end (node n) guided on the
channel bottom and pushed along the rod by a dead load that rises at a set rate (then, to
unload, falls at it). The rod starts straight on the bottom, unloaded, with a small random
lateral offset (`imperfection`·r, smooth: the first sine modes of the rod with random signs) so
that buckling starts near its onset rather than from rounding. Each save records the entry and
far-end forces, the push, the wall force per length, the stuck fraction of the contacts and
the helical and sinusoidal extents (`extents`).

Layer: beside `jaxrod.scene` (it builds and runs the 3D rod); `jaxrod.lockup`'s closed
forms do not import it.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..integrators import default_for, default_step
from ..integrators.base import RunOptions
from ..params import RodChannel
from ..rod3d import Rod3D, step_limit
from ..simulate import simulate
from .si import case

__all__ = ["push_rod", "push_model", "push", "inject", "inject_lanes", "lane_models", "lane", "locked", "extents", "units", "buckle_wavelength", "SEGMENTS_PER_WAVE"]

SEGMENTS_PER_WAVE = 16
"""Default resolution: segments per buckle wavelength at the sinusoidal onset, 2π√(ℓr) (§3). A
helix at the force f F₀ has the pitch π√(8ℓr/f), so this gives 16√(2/f) segments per turn: 13
at Chen's onset, 5 at 20 F₀, 3 at 50 F₀; pass `n` for a run that pushes hard."""


def _check(name, value, lo, closed, unit=""):
    v = float(value)
    ok = math.isfinite(v) and (v >= lo if closed else v > lo)
    if not ok:
        raise ValueError(f"{name} = {value!r}{unit} is invalid: expected a finite number {'>=' if closed else '>'} {lo:g}.")
    return v


def push_rod(mu_L_over_ell, r_over_ell, mu, material: RodChannel | None = None) -> RodChannel:
    """The rod and channel of the case μL/ℓ = `mu_L_over_ell`, r/ℓ = `r_over_ell` at the friction
    coefficient `mu` (static = dynamic) from `material` (its d, E, ρ_v, ν, g; default
    `RodChannel.reference()`): clearance r = (ρ² EI/w)^{1/3} [m], length L = (μL/ℓ)·ℓ/μ [m].

    **Raises:** `ValueError` naming the argument unless μL/ℓ > 0, 0 < r/ℓ < 0.5 and μ > 0."""
    X = _check("mu_L_over_ell", mu_L_over_ell, 0.0, False)
    rho = _check("r_over_ell", r_over_ell, 0.0, False)
    if rho >= 0.5:
        raise ValueError(f"r_over_ell = {r_over_ell!r} is invalid: expected 0 < r/ell < 0.5 (a slender helix).")
    mu = _check("mu", mu, 0.0, False)
    m = RodChannel.reference() if material is None else material
    EI, w = float(m.EI), float(m.rho * m.g)
    r = (rho**2 * EI / w) ** (1.0 / 3.0)
    ell = r / rho
    return RodChannel(L=X * ell / mu, d=m.d, E=m.E, rho_v=m.rho_v, nu=m.nu, R=r, g=m.g, mu_s=mu, mu_d=mu)


def units(rod: RodChannel) -> tuple[float, float]:
    """(F₀ [N], ℓ [m]) of `rod` (P8; `jaxrod.lockup.si.case`)."""
    c = case(rod)
    return c["F0"], c["ell"]


def buckle_wavelength(rod: RodChannel) -> float:
    """The buckle wavelength at the sinusoidal onset, 2π√(ℓr) [m] (§3)."""
    return 2 * math.pi * math.sqrt(units(rod)[1] * float(rod.R))


def push_model(rod: RodChannel, n: int | None = None, F_in: float = 0.0, rate: float = 0.0, **rod3d) -> Rod3D:
    """The 3D rod of the scene: `n` segments (default `SEGMENTS_PER_WAVE` per buckle wavelength
    at the sinusoidal onset, at least 20), pinned ends, the far end (node 0) held and the entry
    (node n) guided on the channel bottom, free along the rod and pushed by the dead load `F_in`
    [N] rising at `rate` [N/s]; other keywords go to [`jaxrod.rod3d.Rod3D`][]."""
    if n is None:
        n = max(20, math.ceil(SEGMENTS_PER_WAVE * float(rod.L) / buckle_wavelength(rod)))
    return Rod3D(rod, int(n), control="load", end_load=F_in, load_rate=rate, ends="pinned", **rod3d)


def _imperfection(model: Rod3D, amplitude, key, modes: int = 8):
    """A smooth random lateral offset [m] at the nodes: Σ_k c_k sin(kπs/L), k = 1…`modes`, c_k
    uniform in ±1, scaled so that its largest value is `amplitude`."""
    s = np.arange(model.n + 1) / model.n
    c = np.asarray(jax.random.uniform(key, (modes,), minval=-1.0, maxval=1.0))
    y = sum(c[k] * np.sin((k + 1) * np.pi * s) for k in range(modes))
    return amplitude * y / max(np.max(np.abs(y)), 1e-300)


def extents(theta, s, wave):
    """The helical and sinusoidal lengths [m] of the rod at each save: a node is helical where
    the angle θ on the wall (unwrapped along the rod) spans more than π within one buckle
    wavelength `wave` [m] around it (a helix turns once in less than that; a sinusoid of
    amplitude below π/2 spans less), sinusoidal where it spans more than 0.2 rad but not π; a
    section's end next to a straight part is blurred by up to half the window, and a helix's
    last half wavelength (less than π of turn) reads as sinusoidal.
    `theta` (..., n + 1) [rad], `s` (n + 1,) node positions along the rod [m]."""
    th = np.unwrap(np.asarray(theta), axis=-1)
    ds = float(np.mean(np.diff(s)))
    half = max(1, int(round(0.5 * wave / ds)))
    pad = np.pad(th, [(0, 0)] * (th.ndim - 1) + [(half, half)], mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(pad, 2 * half + 1, axis=-1)
    span = windows.max(-1) - windows.min(-1)
    helical = span > np.pi
    sinusoidal = (span > 0.2) & ~helical
    return helical.sum(-1) * ds, sinusoidal.sum(-1) * ds


def _start(rod, n, imperfection, key, dt_fraction, rod3d, dt=None, scheme="leapfrog"):
    """The scene's rod, its straight imperfect start and the step (`dt` [s]; default: the
    implicit scheme's own step, `jaxrod.integrators.default_step`, or `dt_fraction` × the explicit
    limit for the explicit schemes)."""
    model = push_model(rod, n, **rod3d)
    key = jax.random.key(0) if key is None else key
    offset = _imperfection(model, imperfection * float(rod.R), key)
    q, v = model.initial_state(0.0, lateral_offset=jnp.asarray(offset))
    if dt is None:
        dt = default_step(model, q, scheme) if scheme == "implicit" else dt_fraction * float(step_limit(model, q))
    return model.n, q, v, float(dt)


def _phases(rod, phases, q, v, dt, n_save, progress, lanes=False, adjust=None, scheme="leapfrog"):
    """Run `phases` — (model, duration [s]) in turn, each from where the last left the rod — and
    record what the scene reports (each phase's first save dropped after the first). With
    `lanes`, each model is a batch (its leaves with a leading lane axis, `inject_lanes`), and so
    are q and v; every record but `t`, `phase` and `ts` has a leading lane axis; progress is then
    one line per phase. `adjust(model, observables, t)`, if given, makes each phase's model after
    the first from the last phase's model and observables, at the time t [s] it starts."""
    F0, ell = units(rod)
    x0 = np.asarray(q.x[..., 0])
    x0 = x0[0] if lanes else x0  # every lane starts from the same rod
    opts = RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=True, progress=progress and not lanes)
    parts, result, t0, last, obs = [], 0, 0.0, None, None
    ax = 1 if lanes else 0  # the records' time axis
    for k, (model, duration) in enumerate(phases):
        if adjust is not None and k > 0:
            model = adjust(last, obs, t0)
        last = model
        if lanes:
            sol = _run_lanes(model, q, v, dt, duration, n_save, opts, scheme)
            if progress:
                print(f"  {t0 + duration:.4g} s of {sum(d for _, d in phases):.4g} s run", flush=True)
        else:
            sol = simulate(model, default_for(model, dt, scheme), q, v, duration, n_save=n_save, options=opts, throw=False)
        q, v = sol.q_final, sol.v_final
        ts = np.asarray(sol.ts)[0] if lanes else np.asarray(sol.ts)
        obs = {name: np.asarray(a) for name, a in sol.observables.items()}
        sl = (slice(None),) * ax + (slice(0 if k == 0 else 1, None),)
        parts.append(dict(t=t0 + ts[sl[-1]], phase=np.full(len(ts[sl[-1]]), k), ts=ts[sl[-1]],
                          reaction=obs["reaction"][sl], wall_force=obs["normal_force"][sl], theta=obs["theta"][sl],
                          stuck_fraction=obs["stuck_fraction"][sl], u=x0 - np.asarray(sol.q.x[..., 0])[sl]))
        t0 += duration
        result = np.maximum(result, np.asarray(sol.result))
    rec = {name: np.concatenate([p[name] for p in parts], axis=0 if name in ("t", "phase", "ts") else ax)
           for name in parts[0]}
    n = q.x.shape[-2] - 1
    s_nodes = np.arange(n + 1) * (float(rod.L) / n)
    rec["helical"], rec["sinusoidal"] = extents(rec["theta"], s_nodes, buckle_wavelength(rod))
    rec.update(push=rec["u"][..., -1], F0=F0, ell=ell, r=float(rod.R), n=n, dt=dt,
               result=result if lanes else int(result))
    return rec


@eqx.filter_jit
def _run_lanes(models, q, v, dt, duration, n_save, opts, scheme="leapfrog"):
    """One compiled, vmapped run of a batch of models, each lane from its own (q, v)."""
    def one(model, q, v):
        return simulate(model, default_for(model, dt, scheme), q, v, duration, n_save=n_save, options=opts, throw=False)

    return eqx.filter_vmap(one, in_axes=(eqx.if_array(0), 0, 0))(models, q, v)


def _forces(rec, F_in, F_far):
    rec.update(F_in=F_in, F_far=F_far, f_in=F_in / rec["F0"], f_far=F_far / rec["F0"])
    return rec


def push(rod: RodChannel, F_max: float, rate: float, *, unload: bool = True, n: int | None = None,
         n_save: int = 101, imperfection: float = 1e-3, key=None, dt_fraction: float = 0.3,
         progress: bool = False, **rod3d) -> dict:
    """Push the rod, its far end held against the load cell: the entry force rises from 0 to
    `F_max` [N] at `rate` [N/s] (a dead load on the entry, `Rod3D.load_rate`), then, with
    `unload`, falls back to 0 at the same rate. The step is `dt_fraction` × the explicit limit at
    the straight rod (the wall's Hertz contact stiffens as the wall force grows: 0.3 leaves room
    for many w). Other keywords go to every [`jaxrod.rod3d.Rod3D`][] of the run.

    Force and not a set pushing speed against a held far end: the rod is axially stiff (EA/F₀ ≈
    6·10⁵ for the reference material at r/ℓ = 0.02), so a push at mm/s raises the entry force by
    hundreds of F₀ per second before the rod can buckle (the state turns non-finite, the rod
    whipping round the channel); a load raised in steps leaves the friction wherever the step's
    overshoot put it, far from the soft string's μwL that a ramp reaches (docs/physics.md §8). With its far end held the
    rod slides only as far as it is compressed: see `inject` for a rod that slides.

    **Returns:** a dict of NumPy arrays over the saves (`n_save` per phase; the unloading
    phase's first save dropped): `t` [s], `phase` (0 loading, 1 unloading), `F_in` the load [N],
    `push` the entry's displacement into the channel [m], `F_far` the far end's axial support
    force (the load cell) [N], `f_in`, `f_far` in units of F₀, `u` (saves, n + 1) every node's
    displacement along the channel toward the far end [m], `helical`, `sinusoidal` extents [m]
    (`extents`), `wall_force` (saves, n + 1) [N/m], `stuck_fraction`, `theta` (saves, n + 1)
    [rad]; and the scalars `F0`, `ell`, `n`, `dt`, `result` (the worse [`jaxrod.RESULTS`][] code)."""
    F_max, rate = _check("F_max", F_max, 0.0, False, " N"), _check("rate", rate, 0.0, False, " N/s")
    n, q, v, dt = _start(rod, n, imperfection, key, dt_fraction, rod3d)
    loads = [(0.0, rate)] + ([(F_max, -rate)] if unload else [])
    rec = _phases(rod, [(push_model(rod, n, F_in=a, rate=r, **rod3d), F_max / rate) for a, r in loads], q, v, dt, n_save, progress)
    start = np.where(rec["phase"] == 0, 0.0, F_max)
    return _forces(rec, start + np.where(rec["phase"] == 0, rate, -rate) * rec["ts"], rec["reaction"][:, 0])


def inject(rod: RodChannel, F_far: float, speed: float, duration: float, *, unload: bool = False,
           n: int | None = None, n_save: int = 101, imperfection: float = 1e-3, key=None,
           dt_fraction: float = 0.3, progress: bool = False, scheme: str = "implicit", dt: float | None = None,
           **rod3d) -> dict:
    """Inject the rod: the entry (node n) is pushed into the channel at `speed` [m/s] for
    `duration` [s] (then, with `unload`, pulled back as far), while the far end (node 0) slides
    against the dead load `F_far` [N] (`Rod3D.far_load`: a bit pressed on the rock, a catheter tip
    against a vessel). The rod slides toward the far end all along, as the soft-string law
    assumes. `scheme` and `dt` [s]: the integrator (a key of `jaxrod.integrators.SCHEMES`; default
    the implicit leapfrog, the 3D rod's, whose entry force was checked against the explicit
    scheme's: `benchmarks/rod3d_implicit_gates.py`)
    and its step (default: the implicit scheme's own, or `dt_fraction` × the explicit limit for
    `"leapfrog"`/`"verlet"`).
    **Returns:** as `push`, with `F_in` the entry's axial support force [N] and `F_far`
    the far load; `u[:, 0]` is how far the far end has moved."""
    speed = _check("speed", speed, 0.0, False, " m/s")
    F_far = _check("F_far", F_far, 0.0, True, " N")
    n, q, v, dt = _start(rod, n, imperfection, key, dt_fraction, rod3d, dt, scheme)
    model = lambda sp: Rod3D(rod, n, control="displacement", speed=sp, far_load=F_far, ends="pinned", **rod3d)
    phases = [(model(speed), duration)] + ([(model(-speed), duration)] if unload else [])
    rec = _phases(rod, phases, q, v, dt, n_save, progress, scheme=scheme)
    rec["scheme"] = scheme
    return _forces(rec, rec["reaction"][:, 1], np.full(len(rec["t"]), F_far))


def inject_lanes(rod: RodChannel, mus, far_loads, speed: float, duration: float, *, n: int | None = None,
                 n_save: int = 101, chunks: int = 20, cap: float | None = None, imperfection: float = 1e-3,
                 key=None, dt_fraction: float = 0.3, progress: bool = False, scheme: str = "implicit",
                 dt: float | None = None, **rod3d) -> dict:
    """`inject` for many cases as one compiled, vmapped run: lane k is the rod and channel of
    `rod` (its L, r and material) with the friction coefficient `mus[k]` (static = dynamic, so
    μL/ℓ varies across lanes) against the far load `far_loads[k]` [N]; every lane starts from
    the same imperfect straight rod and takes the same steps. The push runs in `chunks` equal
    parts (one program; a progress line after each), `n_save` saves in all. A lane whose entry
    force has passed `cap` [F₀] (default ℓ/r, as `locked`) at the end of a part is locked up:
    its entry is held still from then on (the rod has no contact with itself, so pushing on
    would wind the helix through itself). `scheme`, `dt`: as `inject`.

    **Returns:** as `inject`, with a leading lane axis on every record but `t`, `phase`, `ts`;
    `result` per lane, `mu`, and `held_from` [s] (when each lane's entry was stopped; inf if
    never)."""
    speed = _check("speed", speed, 0.0, False, " m/s")
    mus, far_loads = np.broadcast_arrays(np.asarray(mus, float), np.asarray(far_loads, float))
    if mus.ndim != 1 or mus.size == 0:
        raise ValueError(f"mus = {mus.tolist()!r} is invalid: expected a non-empty 1D array of friction coefficients.")
    for name, a, closed in (("mus", mus, False), ("far_loads", far_loads, True)):
        for i, x in enumerate(a):
            _check(f"{name}[{i}]", float(x), 0.0, closed)
    n, q, v, dt = _start(rod, n, imperfection, key, dt_fraction, rod3d, dt, scheme)
    F0, ell = units(rod)
    cap = ell / float(rod.R) if cap is None else _check("cap", cap, 0.0, False)

    models = lane_models(rod, n, speed, mus, far_loads, **rod3d)
    chunks = max(1, int(chunks))
    held_from = np.full(mus.shape, np.inf)

    def hold_locked(models, obs, t):
        over = np.max(np.asarray(obs["reaction"])[..., 1], axis=-1) / F0 > cap
        held_from[over & ~np.isfinite(held_from)] = t
        return eqx.tree_at(lambda m: m.speed, models, jnp.where(jnp.asarray(over), 0.0, models.speed))

    per = max(2, math.ceil((n_save - 1) / chunks) + 1)
    q, v = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (mus.size,) + a.shape), (q, v))  # one per lane
    rec = _phases(rod, [(models, duration / chunks)] * chunks, q, v, dt, per, progress, lanes=True,
                  adjust=hold_locked, scheme=scheme)
    rec["phase"] = np.zeros_like(rec["phase"])  # one loading phase, run in parts
    rec.update(mu=mus, held_from=held_from, scheme=scheme)
    return _forces(rec, rec["reaction"][..., 1], far_loads[:, None] * np.ones(len(rec["t"])))


def lane_models(rod: RodChannel, n: int, speed: float, mus, far_loads, **rod3d) -> Rod3D:
    """The injection scene's rods as one batch (a leading lane axis on every leaf): lane k is
    `rod` with μ_s = μ_d = `mus[k]`, its entry pushed at `speed` [m/s], its far end against
    `far_loads[k]` [N]; `n` segments, other keywords to [`jaxrod.rod3d.Rod3D`][]."""
    def model(mu, F):
        r = eqx.tree_at(lambda r: (r.mu_s, r.mu_d), rod, (mu, mu))
        return Rod3D(r, n, control="displacement", speed=speed, far_load=F, ends="pinned", **rod3d)

    return eqx.filter_vmap(model)(jnp.asarray(mus), jnp.asarray(far_loads))


def lane(rec: dict, k: int) -> dict:
    """Lane `k` of an `inject_lanes` record, as an `inject` record."""
    shared = ("t", "phase", "ts", "F0", "ell", "r", "n", "dt", "scheme")
    return {name: a if name in shared else a[k] for name, a in rec.items()}


def locked(rec: dict, cap: float | None = None) -> bool | None:
    """The earlier cap heuristic, kept for the committed runs it labelled (`results/lockup/`,
    `results/paper/lockup/`); read runs by [`jaxrod.lockup.verdict`][] instead, which asks for a
    steady state and reports what the rod does not resolve. Whether an `inject` run locked up:
    over the last fifth of the push its far end advanced
    less than half as far as its entry, or its entry force passed `cap` [F₀] (default ℓ/r, half
    of 2EI/r², where the helix angle stops being small and the run leaves the scene's range).
    `None` for a run whose force became non-finite before passing `cap`: a failed run says
    nothing about lock-up."""
    cap = rec["ell"] / rec["r"] if cap is None else cap
    loading = rec["phase"] == 0
    push, far, f_in = rec["push"][loading], rec["u"][loading, 0], rec["f_in"][loading]
    finite = np.isfinite(f_in)
    first_bad = len(f_in) if finite.all() else int(np.argmin(finite))
    if np.any(f_in[:first_bad] > cap):
        return True
    if first_bad < len(f_in) or not np.all(np.isfinite(far)):
        return None
    tail = push >= 0.8 * push[-1]
    advance_in, advance_far = push[tail][-1] - push[tail][0], far[tail][-1] - far[tail][0]
    return not advance_far >= 0.5 * advance_in
