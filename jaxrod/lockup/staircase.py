r"""F_far,max and the lock-up length of the 3D rod read by one definition (docs/physics.md §8):
quasi-static staircases of steady injections, bracketed at a bounded entry force.

**The definition.** The soft string's F_far,max is its far-end force as the entry force
f_in → ∞, and its lock-up length where that limit is 0. A discrete rod cannot follow it there:
the helix's pitch π√(8ℓr/f) shrinks as the force grows (16√(2/f) segments per turn at 16
segments per buckle wavelength, 3 at 50 F₀) and its angle atan(√(f r/2ℓ)) stops being small, so
every run past some entry force is **unresolved** (`jaxrod.lockup.verdict`). What a run can
answer is the same question at a bounded entry force f_c [F₀] that the rod resolves:

- **F_far,max(f_c)**: the largest far load the rod pushes in a *steady* slide (`verdict` =
  sliding) with an entry force of at most f_c; the closed forms' counterpart is
  `chain.far_force(f_c F₀, L)`, which tends to their F_far,max as f_c → ∞;
- **μL_lock(f_c)/ℓ**: the μL/ℓ beyond which f_c pushes nothing to the far end (no far load);
  the closed forms' counterpart is `chain.lockup_length(F_in=f_c F₀)`.

**The staircase** ([`staircase`][jaxrod.lockup.staircase.staircase]): each lane is an injection
(`jaxrod.lockup.push.inject`) whose varied parameter — the far load, or μ for the lock-up
length — is raised stage by stage, the rod carried over from one stage to the next (loading
only: it is never lowered, so no stage unloads a helix). Each stage is read by `verdict`:

- sliding with f̄ ≤ f_c: a lower bound; the next stage raises the parameter half of the way
  to the secant's estimate of where f̄ = f_c (on log f̄), by at most 12 % and at least
  0.9 × `rel` of it (`_next`);
- sliding with f̄ > f_c, or locked: an upper bound, and the lane stops (bracketed if the two
  bounds are within `rel`, else `wide`);
- transient: the stage is repeated at the same parameter (at most `repeats` times, then the lane
  stops as transient);
- unresolved or failed: the lane stops with that status.

A stopped lane leaves the batch while the others go on (the batch is compiled again for its new
size).

**The crossing** (`crossing`): inside a bracket, the parameter where the steady entry force
reaches f_c, read linearly between the last steady stage at or below f_c and the first above it,
with an interpolation error: its distance from the quadratic through those two and the steady
stage before them. It resolves the quantity finer than the bracket, whose width is set by the
least step (`_next`): two runs whose brackets differ by one stage can cross f_c at nearly
the same parameter.

Layer: beside `jaxrod.lockup.push`, whose scene it runs.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from ..integrators.base import RunOptions
from .push import _check, _run_lanes, _start, buckle_wavelength, extents, lane_models, units
from .verdict import LOCKED, SLIDING, TRANSIENT, Criterion, verdict

__all__ = ["staircase", "crossing", "BRACKETED", "WIDE", "BELOW_START"]

BRACKETED, WIDE, BELOW_START = "bracketed", "wide", "below start"


def _next(history, p, f_c, rel, growth=0.12):
    """The next value of the varied parameter after the steady stages `history` [(p, f̄)], all
    with f̄ ≤ f_c, the last at `p`: half of the way to where the secant of log f̄ through the last
    two reaches f_c, at most `growth` × p (the entry force rises ever faster as the far load or
    μ nears its bound, so the secant from below overshoots) and at least 0.9 × `rel` × p; only
    that least step once the last steady force is within 5 % of f_c (or within 10 % and did not
    rise), so that the stage that crosses f_c closes a bracket no wider than `rel`."""
    floor = p * (1 + 0.9 * rel) if p > 0 else 0.1
    if len(history) < 2:
        return max(floor, p * (1 + growth))
    (p0, f0), (p1, f1) = history[-2], history[-1]
    slope = (math.log(f1) - math.log(f0)) / (p1 - p0) if p1 > p0 else 0.0
    if f1 >= 0.95 * f_c or (not slope > 0 and f1 >= 0.9 * f_c):  # near the bound only the least step is safe
        return floor
    if not slope > 0:  # the steady force did not rise: noise
        return max(floor, p1 * (1 + growth))
    target = p1 + (math.log(f_c) - math.log(f1)) / slope
    return max(floor, p1 + min(0.5 * (target - p1), growth * p1))


def crossing(stages, f_c: float) -> tuple[float, float] | None:
    """Where the steady entry force of a lane's `stages` (dicts with `parameter`, `status`,
    `f_in` [F₀], as `staircase` returns them) crosses `f_c` [F₀] (module docstring): (the
    linear crossing between the last sliding stage at or below f_c and the first above it, its
    interpolation error). The error is the distance to the crossing of the quadratic through
    those two and the sliding stage before them, or, without one (or where that quadratic does
    not cross f_c between the two), half the distance between the two stages. None without a
    sliding stage on each side of f_c."""
    pts = sorted((float(s["parameter"]), float(s["f_in"])) for s in stages if s["status"] == SLIDING)
    below, above = [p for p in pts if p[1] <= f_c], [p for p in pts if p[1] > f_c]
    if not below or not above:
        return None
    (x0, f0), (x1, f1) = below[-1], above[0]
    linear = x0 + (f_c - f0) * (x1 - x0) / (f1 - f0)
    error = 0.5 * (x1 - x0)
    if len(below) >= 2 and below[-2][0] < x0:
        xs, fs = np.array([below[-2][0], x0, x1]), np.array([below[-2][1], f0, f1])
        roots = np.roots(np.polyfit(xs - x0, fs - f_c, 2)) + x0
        inside = [float(z.real) for z in roots if abs(z.imag) < 1e-12 and x0 <= z.real <= x1]
        if inside:
            error = min(abs(z - linear) for z in inside)
    return linear, error


def _stage_rule(lane: dict, p: float, status: str, f_bar: float, f_c: float, rel: float, repeats: int):
    """What a stage at the parameter `p` read as `status` (the verdict's) with the steady entry
    force `f_bar` [F₀] does to its `lane` (a dict with `lo`, `hi`, `status`, `steady`, `repeats`;
    updated in place), by the module docstring's rules. **Returns:** the next stage's parameter,
    or None where the lane repeats its stage (`status` stays "open") or stops (`status` set)."""
    if status == SLIDING and f_bar <= f_c:
        lane.update(lo=p, repeats=0)
        lane["steady"].append((p, f_bar))
        return _next(lane["steady"], p, f_c, rel)
    if (status == SLIDING and f_bar > f_c) or status == LOCKED:
        lane["hi"] = p
        lane["status"] = BELOW_START if lane["lo"] is None else (BRACKETED if (p - lane["lo"]) <= rel * p else WIDE)
    elif status == TRANSIENT and lane["repeats"] < repeats:
        lane["repeats"] += 1
    else:
        lane["status"] = status
    return None


def staircase(rod, mus, far_loads, speed: float, *, f_c: float = 6.0, vary_mu=False, rel: float = 0.03,
              first_push: float = 0.4, stage_push: float = 0.15, max_stages: int = 12, repeats: int = 2,
              n: int | None = None, saves_per_stage: int = 41, criterion: Criterion = Criterion(),
              imperfection: float = 1e-3, key=None, scheme: str = "implicit", dt: float | None = None,
              progress: bool = False, label: str = "", **rod3d) -> dict:
    """Bracket F_far,max(f_c) (or μL_lock(f_c)/ℓ) of every lane by a staircase of steady
    injections (module docstring). Lane k is `rod` (its L, r and material) with the friction
    coefficient `mus[k]` (static = dynamic) against the far load `far_loads[k]` [F₀]; it raises
    μ if `vary_mu[k]`, else the far load. The entry is pushed at `speed` [m/s], `first_push` [m]
    from the straight rod, then `stage_push` [m] per stage, `saves_per_stage` saves each, at most
    `max_stages` stages; `f_c` [F₀] is the entry force bound, `rel` the bracket's target width
    (relative), `criterion` the verdict's thresholds; with `progress`, a line per stage (after
    `label`). `scheme`, `dt`, `n`, other keywords: as
    `jaxrod.lockup.push.inject`.

    **Returns:** a dict: `lanes`, a list of one dict per lane — `status` (`BRACKETED`, `WIDE`,
    `BELOW_START`, or the verdict status that stopped it: transient, unresolved, failed; or
    `"open"` if the stages ran out), `lo`, `hi` (the bracket of the varied parameter: far load
    [F₀] or μL/ℓ; None where not found), `crossing`, `crossing_error` (`crossing`; None where
    not found), `stages` (per stage: the parameter, the verdict, the
    entry force over the last part [F₀], the worst segments per turn and helix angle [deg], the
    helical and sinusoidal extents at the last save [m], `push.extents`), `profiles` (per
    sliding stage at or below f_c, its last save: `theta` [rad], `wall_force` [N/m] at the nodes,
    `axial_force` [N] per segment, `f_in` [F₀], `mu` and the parameter); and the run's `F0` [N], `ell` [m], `n`, `dt` [s], `l0` [m], `r` [m], `L_over_ell`."""
    speed = _check("speed", speed, 0.0, False, " m/s")
    f_c = _check("f_c", f_c, 0.0, False, " F0")
    rel = _check("rel", rel, 0.0, False)
    mus, far_loads, vary_mu = np.broadcast_arrays(np.asarray(mus, float), np.asarray(far_loads, float),
                                                  np.asarray(vary_mu, bool))
    if mus.ndim != 1 or mus.size == 0:
        raise ValueError(f"mus = {mus.tolist()!r} is invalid: expected a non-empty 1D array of friction coefficients.")
    for name, a, closed in (("mus", mus, False), ("far_loads", far_loads, True)):
        for i, x in enumerate(a):
            _check(f"{name}[{i}]", float(x), 0.0, closed)
    n, q0, v0, dt = _start(rod, n, imperfection, key, 0.3, rod3d, dt, scheme)
    F0, ell = units(rod)
    L, r = float(rod.L), float(rod.R)
    l0 = L / n
    s_nodes, wave = np.arange(n + 1) * l0, buckle_wavelength(rod)

    mu_now, far_now = mus.copy(), far_loads.copy()
    pushing = np.ones(mus.shape, bool)
    lanes = [dict(status="open", lo=None, hi=None, stages=[], profiles=[], steady=[], repeats=0)
             for _ in range(mus.size)]
    opts = RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=True, progress=False)
    q, v = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (mus.size,) + a.shape), (q0, v0))
    x0 = np.asarray(q0.x[:, 0])
    for stage in range(max_stages):
        active = np.flatnonzero(pushing)  # a stopped lane leaves the batch
        models = lane_models(rod, n, speed, mu_now[active], far_now[active] * F0, **rod3d)
        duration = (first_push if stage == 0 else stage_push) / speed
        take = lambda a: a[active]  # noqa: E731
        sol = _run_lanes(models, jax.tree_util.tree_map(take, q), jax.tree_util.tree_map(take, v), dt, duration,
                         saves_per_stage, opts, scheme)
        put = lambda a, b: a.at[active].set(b)  # noqa: E731
        q, v = jax.tree_util.tree_map(put, q, sol.q_final), jax.tree_util.tree_map(put, v, sol.v_final)
        xs = np.zeros((mus.size,) + sol.q.x.shape[1:-1])
        xs[active] = np.asarray(sol.q.x[..., 0])  # (lanes, saves, n + 1)
        obs = {}
        for name in ("reaction", "theta", "normal_force", "axial_force"):  # what the stages read
            a = sol.observables[name]
            obs[name] = np.zeros((mus.size,) + a.shape[1:])
            obs[name][active] = np.asarray(a)
        for k, lane in enumerate(lanes):
            if not pushing[k]:
                continue
            p = float(mu_now[k] * L / ell) if vary_mu[k] else float(far_now[k])
            f_in = obs["reaction"][k, :, 1] / F0
            V = verdict(x0[-1] - xs[k, :, -1], x0[0] - xs[k, :, 0], f_in, obs["theta"][k], l0, r, criterion,
                        contact=obs["normal_force"][k] > 0)
            f_bar = V["force"][1] if V["force"] else math.nan
            hel, sin = extents(obs["theta"][k, -1][None], s_nodes, wave)
            lane["stages"].append(dict(stage=stage, parameter=p, status=V["status"], f_in=f_bar,
                                       segments_per_turn=V["segments_per_turn"], helix_angle=V["helix_angle"],
                                       helical=float(hel[0]), sinusoidal=float(sin[0]), reason=V["reason"]))
            nxt = _stage_rule(lane, p, V["status"], f_bar, f_c, rel, repeats)
            if V["status"] == SLIDING and f_bar <= f_c:
                lane["profiles"].append(dict(parameter=p, f_in=float(f_in[-1]), theta=obs["theta"][k, -1],
                                             wall_force=obs["normal_force"][k, -1],
                                             axial_force=obs["axial_force"][k, -1], mu=float(mu_now[k])))
            if nxt is None:
                pushing[k] = lane["status"] == "open"
            elif vary_mu[k]:
                mu_now[k] = nxt * ell / L
            else:
                far_now[k] = nxt
        if progress:
            done = ", ".join(f"{ln['status']}" for ln in lanes)
            print(f"  {label}stage {stage + 1}: {done}", flush=True)
        if not pushing.any():
            break
    for lane in lanes:
        lane.pop("repeats")
        lane.pop("steady")
        lane["crossing"], lane["crossing_error"] = crossing(lane["stages"], f_c) or (None, None)
    return dict(lanes=lanes, F0=F0, ell=ell, n=n, dt=dt, l0=l0, r=r, L_over_ell=L / ell, f_c=f_c, speed=speed,
                mus=mus, far_loads=far_loads, vary_mu=vary_mu, scheme=scheme,
                X=mus * L / ell)
