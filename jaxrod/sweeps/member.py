"""One sweep member: its rod, load, perturbation and validity from the swept values, its run on
the fixed-step engine, its outputs; and the static resolution (n, dt) of a sweep."""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping

import jax
import jax.numpy as jnp
import numpy as np

from .. import theory
from .._results import RESULTS
from ..integrators import default_for
from ..integrators.base import RunOptions, save_grid
from ..params import RodChannel
from ..registry import make_perturbation, name_of, recipe
from ..scene import Scene
from .spec import ROD_FIELDS, SweepSpec, _STIFFNESS_FIELDS

__all__ = ['N_SAVE']


def _member_rod(spec: SweepSpec, p: Mapping[str, jax.Array]) -> RodChannel:
    base = RodChannel.reference(mu=spec.mu, **spec.rod)
    vals = {f: getattr(base, f) for f in ROD_FIELDS}
    if "mu" in p:
        vals["mu_s"] = vals["mu_d"] = p["mu"]
    for f in ROD_FIELDS:
        if f in p:
            vals[f] = p[f]
    return RodChannel(**vals)


def _valid(rod: RodChannel, p) -> jax.Array:
    """A member's rod by `RodChannel.valid`, and its load and amplitude finite (the amplitude ≥ 0)."""
    ok = rod.valid()
    for k in ("dF", "amplitude"):
        if k in p:
            ok &= jnp.isfinite(p[k])
    if "amplitude" in p:
        ok &= p["amplitude"] >= 0
    return ok


def _member_inputs(spec: SweepSpec, p, index, base_key):
    """A member's validity flag, its rod (the reference rod where invalid, so that an invalid
    member stays finite and cannot disturb the batch; it is flagged afterwards), ΔF, amplitude
    and random key."""
    rod = _member_rod(spec, p)
    ok = _valid(rod, p)
    safe = jax.tree_util.tree_map(
        lambda x, r: jnp.where(ok, x, r), rod, RodChannel.reference(mu=spec.mu, **spec.rod)
    )
    dF = jnp.where(ok, p.get("dF", spec.dF), spec.dF)
    amp = jnp.where(ok, p.get("amplitude", spec.amplitude), spec.amplitude)
    return ok, safe, dF, amp, jax.random.fold_in(base_key, index)


N_SAVE = 201  # the stick test runs at every save, so a stuck member stops within t1/200


def _engine_member(spec: SweepSpec, n: int | None, dt: float, grid_dt: float, scheme: str | None):
    """A member in three pure parts: `setup(params, index, base_key)` gives its model and its
    [`RunState`][jaxrod.integrators.base.RunState] at t = 0, the fixed-step engine advances it
    (`advance`, `finished`), `outputs(ok, model, run)` summarises it. Every model, 3D included;
    every member runs `scheme` (the sweep's, `_static_resolution`)."""

    def integrator(model):  # the scene's scheme, as `Scene.integrator`
        return default_for(model, dt, scheme)

    opts = RunOptions(buckle_threshold=spec.threshold, save_state=False)
    m, h = save_grid(spec.t1, N_SAVE, dt)
    # a step the sweep chose itself is the smallest default step over its rods at its largest load
    # (`_resolution`), within every member's limit, so the members' own check is skipped; a given
    # `spec.dt` is checked member by member.
    check_limit = spec.dt is not None

    def setup(p, index, base_key):
        ok, safe, dF, amp, key = _member_inputs(spec, p, index, base_key)
        pert = make_perturbation(spec.perturbation, amp, spec.mode, key, spec.duration)
        scene = Scene(safe, dF, pert, spec.model, n, spec.mode, dt, threshold=spec.threshold,
                      grid_dt=grid_dt)
        problem = scene.resolve()  # the member's model, built once, and its initial state
        model = problem.model
        return ok, model, integrator(model).start(model, problem.q0, problem.v0, opts)

    def advance(model, run):
        return integrator(model).advance(model, run, jnp.asarray(h, run.t.dtype), m, N_SAVE, opts)

    def finished(run):
        return run.finished(N_SAVE)

    def outputs(ok, model, run):
        dom = recipe(spec.model).dominant_mode(model, run.q)
        code = integrator(model).result(model, run, jnp.asarray(h, run.t.dtype), check_limit)
        result = jnp.where(ok & model.check(), code, RESULTS.invalid_input).astype(jnp.int32)
        return {
            "buckled": run.buckled & (result == 0),
            "t_buckle": run.t_buckle,
            "dominant_mode": dom.astype(jnp.int32),
            "max_theta": run.amp_max,
            "final_theta": model.amplitude(run.q),
            "stuck": run.stuck,
            "t_stop": run.stop_time(spec.t1, N_SAVE),
            "result": result,
            "steps": run.steps,
        }

    return setup, advance, finished, outputs


def _make_member(spec: SweepSpec, n: int | None, dt: float, grid_dt: float, scheme: str | None):
    """The pure per-member function `member(params, index, base_key) -> outputs` (one whole run:
    the "chunk" scheduling, and single runs)."""
    setup, advance, finished, outputs = _engine_member(spec, n, dt, grid_dt, scheme)

    m, _ = save_grid(spec.t1, N_SAVE, dt)

    def member(p, index, base_key):
        ok, model, run = setup(p, index, base_key)
        interval = lambda r: jax.lax.fori_loop(0, m, lambda _, r: advance(model, r), r)
        return outputs(ok, model, jax.lax.while_loop(lambda r: ~finished(r), interval, run))

    return member


def _static_resolution(spec: SweepSpec, flat: dict[str, np.ndarray]):
    """n, dt, the field grid's step and the scheme from the concrete inputs: the largest load sets n
    and the scheme (the 3D rod's explicit leapfrog past the wall's wrinkling load, `Scene.scheme`),
    the stiffest valid member dt, in that scheme; every member runs that scheme at that step.
    Depends only on the spec, the distinct stiffness values and the largest ΔF, and is cached
    on them (it evaluates the models eagerly: a few ms, much of a small sweep)."""
    stiff = [f for f in _STIFFNESS_FIELDS if f in flat]
    values = np.unique(np.stack([np.asarray(flat[f], float) for f in stiff], -1), axis=0) if stiff else None
    dF = flat.get("dF", np.array([spec.dF]))
    dF_max = float(np.nanmax(np.where(np.isfinite(dF), dF, -np.inf)))
    key = None if values is None else tuple(map(tuple, values.tolist()))
    return _resolution(json.dumps(spec.to_json(), sort_keys=True), spec.model, tuple(stiff), key, dF_max)


def spec_of(spec_json: str, model) -> SweepSpec:
    """The spec of `spec_json` (`SweepSpec.to_json`, the cached functions' key) with its `model`
    (a name, or a recipe, which the JSON holds by name only)."""
    return SweepSpec(**{**json.loads(spec_json), "model": model})


@functools.lru_cache(maxsize=64)
def _resolution(spec_json: str, model, stiff: tuple[str, ...], values, dF_max: float):
    import jax.numpy as jnp_

    spec = spec_of(spec_json, model)

    errors = []

    def rod_of(row):
        try:
            return RodChannel.reference(mu=spec.mu, **{**dict(spec.rod), **dict(zip(stiff, row))})
        except ValueError as e:
            errors.append(str(e))
            return None

    if values is not None:
        rods = [r for r in map(rod_of, values) if r is not None]
    else:
        rods = [RodChannel.reference(mu=spec.mu, **spec.rod)]
    if not rods:
        raise ValueError(f"no member of the sweep has valid rod parameters (the first: {errors[0]})")
    cls = recipe(spec.model)
    pert = _perturbation(spec)
    n = spec.n
    if n is None:  # the largest default size over the rods at the largest load
        sizes = [cls.default_size(r, theory.reference_load(r) + dF_max, pert) for r in rods]
        n = None if None in sizes else max(sizes)
    scenes = [Scene(r, jnp_.asarray(dF_max), pert, kind=spec.model, n=n, mode=spec.mode) for r in rods]
    if spec.dt is not None:
        _check_given_step(spec, scenes)
    steps = [s.step() for s in scenes]
    scheme = scenes[int(np.argmin(steps))].scheme() or cls.model_class.scheme  # the stiffest member's at the largest load
    dt = spec.dt or min(steps)
    grid_dt = min(Scene(r, jnp_.asarray(dF_max), kind="field", n=128).step() for r in rods)
    return n, float(dt), float(grid_dt), scheme


def _check_given_step(spec: SweepSpec, scenes) -> None:
    """A given `spec.dt` must lie below the step limit of the members' scheme at the sweep's largest
    load (members at smaller loads are checked again by the engine)."""
    models = [s.model() for s in scenes]
    limit = min(float(default_for(m, 1.0, s.scheme()).step_limit(m)) for m, s in zip(models, scenes))
    if not (0 < spec.dt < limit):
        raise ValueError(f"SweepSpec.dt = {spec.dt!r} s is invalid for model {name_of(spec.model)!r}: the scheme's step limit "
                         f"is {limit:.4g} s; use 0 < dt < {limit:.4g} s.")


def _perturbation(spec: SweepSpec):
    return make_perturbation(spec.perturbation, 1.0, spec.mode, None, spec.duration)



