"""Curves of the boundary searches: v₀*(ΔF) along loads and ΔF*(μ) over friction coefficients and
realizations, each point a search of `jaxrod.boundary.search`. The reduced rod models go along
the loads in order, each search started from its neighbours' roots (`continuation`); label
bisection on the other rod models (the 3D rod) starts at the field model's boundary, a load per
device; otherwise all points are searched at once (vmapped).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import theory
from ..models.field import FieldRecipe
from ..registry import make_perturbation, recipe
from ..scene import Scene
from .indicators import departure_sensitivities
from .roots import expanding_bisection
from .search import (_label, _method_of, _named, _params_of, _resolution, _rod_of, _scene, critical_load,
                     critical_velocity)

__all__ = ["boundary_curve", "critical_load_curve"]


@eqx.filter_jit
def _velocity_search(rod, dF, lo, hi, start, **static):
    """One compiled `critical_velocity` per set of static settings, reused by every curve (the
    rod and the numbers are traced)."""
    return critical_velocity(rod, dF, bracket=(lo, hi), start=start, **static)


def _predict(xs, roots, refs, x):
    """A root at `x` from earlier roots: the ratio root/ref (ref a theory curve of the same
    shape) extrapolated linearly in log x from the last two, or kept from the last one."""

    if not roots:
        return refs(x)
    r = [np.log(a / refs(b)) for a, b in zip(roots[-2:], xs[-2:])]
    if len(r) == 1 or xs[-1] == xs[-2]:
        return refs(x) * np.exp(r[-1])
    slope = (r[1] - r[0]) / (np.log(xs[-1]) - np.log(xs[-2]))
    return refs(x) * np.exp(r[1] + slope * (np.log(x) - np.log(xs[-1])))


def _along_curve(search, xs, refs, bracket, margin, progress):
    """Searches along `xs` in order (host loop, one compiled search): each started at
    (1 + `margin`)·prediction inside a bracket of a factor 4 around it (clipped to `bracket`),
    and searched again in the full `bracket` if that one holds no root."""

    from .roots import ROOT_RESULTS

    order = np.argsort(xs)
    out = [None] * len(xs)
    done_x, done_r = [], []
    bar = _progress(len(xs), progress)
    for i in order:
        pred = float(_predict(done_x, done_r, refs, float(xs[i])))
        lo, hi = max(bracket[0], pred / 4), min(bracket[1], pred * 4)
        start = min(max(pred * (1 + margin), lo), hi)
        res, sens = search(xs[i], lo, hi, start)
        if int(res.result) == ROOT_RESULTS.invalid_bracket and (lo, hi) != tuple(bracket):
            first = int(res.evaluations)
            res, sens = search(xs[i], bracket[0], bracket[1], bracket[1])
            res = eqx.tree_at(lambda r: r.evaluations, res, res.evaluations + first)
        if int(res.result) == ROOT_RESULTS.converged:
            done_x.append(float(xs[i]))
            done_r.append(float(res.root))
        out[i] = (res, sens)
        bar.update(1)
    bar.close()
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *out)


def _progress(total, show):
    if show:
        from tqdm.auto import tqdm
    else:  # a disabled bar: plain tqdm (tqdm.auto warns in a notebook without ipywidgets)
        from tqdm import tqdm

    return tqdm(total=total, disable=not show, unit="point", desc="boundary", leave=False)


def boundary_curve(rod, dFs, *, model="field", n=None, dt=None, mode=6, bracket=(1e-4, 1.0), rtol=1e-6,
                   max_iter=60, t1=None, method=None, continuation=True, margin=0.02, width=0.04, progress=False,
                   sensitivities=("mu", "dF")):
    """v₀*(ΔF) for an array of loads.

    With `continuation` (reduced models, `method="departure"`), the loads are searched in
    increasing order, each from a prediction: the single-mode boundary (P6) times the ratio of
    the last two roots to it, extrapolated in log ΔF; the first run at (1 + `margin`) times
    the prediction. Each load gets the scene's default resolution for it unless `n`/`dt` are
    given (one compiled search per resolution).

    With `continuation` and label bisection on a model other than the field model (the 3D rod's
    default), each load is predicted by the field model's boundary (its departure search, to
    1e-4) and bisected from a bracket of ±`width` around it, moved and widened while its ends
    agree ([`jaxrod.boundary.expanding_bisection`][], inside `bracket`): the 3D rod's v₀* lies
    near the field model's (docs/rod3d.md), so a narrow bracket takes a few runs where a bisection
    over `bracket` takes a dozen. One compiled search serves every load (the resolution of the
    largest); the loads run on the local devices at once, one per device. Otherwise all loads are searched at once, one vmapped,
    jitted search over the whole `bracket` at the resolution of the largest load.

    `t1`: the horizon of a run [s] (a run that neither sticks nor buckles by then is stable);
    default the model's `search_horizon` (2 s; the 3D rod 0.4 s, docs/rod3d.md).

    **Returns:** `(RootResult, sensitivities)` with a leading batch axis.
    """

    dFs = np.asarray(dFs, float)
    if t1 is None:
        t1 = recipe(model).search_horizon
    kw = dict(model=model, mode=mode, rtol=rtol, max_iter=max_iter, t1=t1, method=method,
              sensitivities=sensitivities)
    if continuation and _method_of(method, model) == "bisection" and not isinstance(recipe(model), FieldRecipe):
        return _seeded_bisection(rod, dFs, bracket, width, n, dt, progress, **kw)
    if not (continuation and _method_of(method, model) == "departure"):
        if _method_of(method, model) != "exact":
            probe = Scene(rod, float(np.max(dFs)), kind=model, n=n, mode=mode, dt=dt)
            n, dt = probe.size(), probe.step() if dt is None else dt
        fn = lambda dF: critical_velocity(rod, dF, bracket=bracket, n=n, dt=dt, **kw)
        return jax.jit(jax.vmap(fn))(jnp.asarray(dFs))

    def search(dF, lo, hi, start):
        n_, dt_ = _resolution(rod, dF, model, n, mode, dt)
        f = lambda x: jnp.asarray(x, jnp.result_type(float))  # arrays: traced, not static
        return _velocity_search(rod, f(dF), f(lo), f(hi), f(start), n=n_, dt=dt_, **kw)

    F0 = float(theory.reference_load(rod))

    def p6(dF):
        k = theory.stiffness(rod, mode, F0 + dF)
        return float(rod.R * theory.velocity_intercept(k, theory.friction_amplitude(rod)))

    return _along_curve(search, dFs, p6, bracket, margin, progress)


def _bisect_near(rod, dF, guess, lo, hi, *, model, mode, n, dt, rtol, max_iter, t1, width, sensitivities, scheme):
    """Label bisection from `guess`·(1 ∓ `width`) inside [`lo`, `hi`] and the sensitivities at its
    lowest buckled run (`boundary_curve`'s seeded path), runs of the scheme `scheme`."""
    params = _params_of(rod, dF=dF)
    scene_of2 = lambda v0, p: _scene(_rod_of(type(rod), p), p["dF"], v0, model, n, mode, dt, "sine",
                                     jax.random.key(0), scheme)
    res = expanding_bisection(_label(lambda v0: scene_of2(v0, params), t1), guess, width, rtol, max_iter,
                              floor=lo, ceiling=hi)
    sub = {k: params[k] for k in sensitivities}
    sens = departure_sensitivities(lambda x, s: scene_of2(x, {**params, **s}), res.hi, sub, t1) if sub else {}
    return _named(res), sens


def _on_devices(fn, devices, batched: int = 2):
    """`fn(shared, *batch)` over a batch of points (the last `batched` arguments; e.g. loads and
    guesses), one point per device (`shard_map` over the local devices: each device runs its own
    search, with no step in lockstep with the others), jitted once."""
    from jax.sharding import Mesh, PartitionSpec as P

    mesh = Mesh(np.asarray(devices), ("batch",))
    local = lambda shared, *b: jax.vmap(fn, (None,) + (0,) * batched)(shared, *b)
    return jax.jit(jax.shard_map(local, mesh=mesh, in_specs=(P(),) + (P("batch"),) * batched, out_specs=P("batch"),
                                 check_vma=False))


def _in_chunks(run, width, idx, args_of, out, bar):
    """`run(*args_of(chunk))` (`_on_devices` over `width` devices) over the points `idx`, `width`
    at a time (the last chunk padded with its last point), each point's result put in `out[i]`."""
    for start in range(0, len(idx), width):
        chunk = idx[np.arange(start, start + width).clip(max=len(idx) - 1)]
        res = run(*args_of(chunk))
        k = min(width, len(idx) - start)
        for j in range(k):
            out[chunk[j]] = jax.tree_util.tree_map(lambda a: np.asarray(a)[j], res)
        bar.update(k)


def _seeded_bisection(rod, dFs, bracket, width, n, dt, progress, *, model, mode, rtol, max_iter, t1, method,
                      sensitivities):
    """`boundary_curve` by label bisection around the field model's boundary (its docstring):
    as many loads at once as there are local devices (`jaxrod boundary` makes one per core)."""
    guess, _ = boundary_curve(rod, dFs, model="field", mode=mode, rtol=1e-4, sensitivities=())
    guess = np.asarray(guess.root)
    # a field search that failed leaves no prediction: the middle of the bracket (geometric)
    guess = np.where(np.isfinite(guess), guess, math.sqrt(bracket[0] * bracket[1]))
    dtype = jnp.result_type(float)
    lo, hi = (jnp.asarray(b, dtype) for b in bracket)
    # the scheme of each load (the 3D rod's implicit default below the wall's wrinkling load, the
    # explicit leapfrog past it): one compiled search per scheme, at its largest load's resolution
    schemes = [Scene(rod, float(dF), make_perturbation("sine", 1.0, mode), kind=model, n=n, mode=mode).scheme()
               for dF in dFs]
    bar = _progress(len(dFs), progress)
    out = [None] * len(dFs)
    for scheme in dict.fromkeys(schemes):
        idx = np.flatnonzero([s_ == scheme for s_ in schemes])
        probe = Scene(rod, float(np.max(dFs[idx])), make_perturbation("sine", 1.0, mode), kind=model, n=n, mode=mode,
                      dt=dt, scheme_key=scheme)
        n_, dt_ = probe.size(), probe.step()
        one = lambda r, dF, g, n_=n_, dt_=dt_, scheme=scheme: _bisect_near(
            r, dF, g, lo, hi, model=model, mode=mode, n=n_, dt=dt_, rtol=rtol, max_iter=max_iter, t1=t1, width=width,
            sensitivities=tuple(sensitivities), scheme=scheme)
        devices = jax.local_devices()[:len(idx)]
        args_of = lambda chunk: (rod, jnp.asarray(dFs[chunk], dtype), jnp.asarray(guess[chunk], dtype))
        _in_chunks(_on_devices(one, devices), len(devices), idx, args_of, out, bar)
    bar.close()
    return jax.tree_util.tree_map(lambda *a: jnp.asarray(np.stack(a)), *out)


def critical_load_curve(mus, amplitude, *, perturbation="sine", realizations=1, seed=0, model="field",
                        n=None, dt=None, mode=6, bracket=(1e-2, 100.0), rtol=1e-6, max_iter=60, t1=2.0,
                        method=None, rod_overrides=None, sensitivities=("mu", "amplitude"), seeded=True,
                        width=0.2, progress=False):
    """ΔF*(μ) for an array of friction coefficients and `realizations` random perturbations
    each (keys `fold_in(key(seed), i·realizations + r)`), vmapped.

    With `seeded` and label bisection on a model other than the field model (the 3D rod's
    default), each point is predicted by the field model's ΔF* (same perturbation, key and
    horizon; to 1e-4) and bisected from ±`width` around it, moved and widened while its ends agree
    ([`jaxrod.boundary.expanding_bisection`][], inside `bracket`), the points on the local devices
    at once, one per device (the E4 driver's search: a bracket around the field model's root,
    `jaxrod.experiments.e4.rod3d`); otherwise one vmapped, jitted search over `bracket` each.

    **Returns:** `(RootResult, sensitivities)` with batch axes (len(mus), realizations).
    """

    from ..params import RodChannel

    mus = np.asarray(mus, float)
    overrides = dict(rod_overrides or {})
    if seeded and _method_of(method, model, perturbation) == "bisection" and not isinstance(recipe(model), FieldRecipe):
        return _seeded_critical_load(mus, amplitude, bracket, width, n, dt, progress, perturbation=perturbation,
                                     realizations=realizations, seed=seed, model=model, mode=mode, rtol=rtol,
                                     max_iter=max_iter, t1=t1, overrides=overrides, sensitivities=sensitivities)
    base = RodChannel.reference(mu=float(mus.max()), **overrides)
    if _method_of(method, model, perturbation) != "exact":
        probe = Scene(base, float(bracket[1]), make_perturbation(perturbation, 1.0, mode), kind=model, n=n,
                      mode=mode, dt=dt)
        n = probe.size()
        dt = probe.step() if dt is None else dt
    root_key = jax.random.key(seed)

    def one(mu, r, i):
        rod = RodChannel.reference(mu=mu, **overrides)
        key = jax.random.fold_in(root_key, i * realizations + r)
        return critical_load(rod, amplitude, model=model, perturbation=perturbation, mode=mode, n=n, dt=dt,
                             key=key, bracket=bracket, rtol=rtol, max_iter=max_iter, t1=t1, method=method,
                             sensitivities=sensitivities)

    idx = jnp.arange(len(mus))
    reals = jnp.arange(realizations)
    run = jax.vmap(jax.vmap(one, (None, 0, None)), (0, None, 0))
    return jax.jit(run)(jnp.asarray(mus), reals, idx)


def _seeded_critical_load(mus, amplitude, bracket, width, n, dt, progress, *, perturbation, realizations, seed, model,
                          mode, rtol, max_iter, t1, overrides, sensitivities):
    """`critical_load_curve` by label bisection around the field model's ΔF* (its docstring), one
    point per local device, one compiled search at the resolution and scheme of the largest first
    bracket's top."""
    from ..params import RodChannel

    guess, _ = critical_load_curve(mus, amplitude, perturbation=perturbation, realizations=realizations, seed=seed,
                                   model="field", mode=mode, bracket=bracket, rtol=1e-4, t1=t1,
                                   rod_overrides=overrides, sensitivities=())
    guess = np.asarray(guess.root, float).reshape(-1)
    guess = np.where(np.isfinite(guess), guess, math.sqrt(bracket[0] * bracket[1]))
    mu_of = np.repeat(mus, realizations)
    index = np.arange(len(mu_of))  # i·realizations + r, as the vmapped curve's keys
    top = min(float(np.max(guess)) * (1 + width), float(bracket[1]))
    base = RodChannel.reference(mu=float(mus.max()), **overrides)
    probe = Scene(base, top, make_perturbation(perturbation, 1.0, mode), kind=model, n=n, mode=mode, dt=dt)
    n_, dt_, scheme = probe.size(), probe.step(), probe.scheme()
    dtype = jnp.result_type(float)
    lo, hi = (jnp.asarray(b, dtype) for b in bracket)
    root_key = jax.random.key(seed)

    def one(amp, mu, i, g):
        params = _params_of(RodChannel.reference(mu=mu, **overrides), amplitude=amp)
        key = jax.random.fold_in(root_key, i)
        scene_of2 = lambda dF, p: _scene(_rod_of(RodChannel, p), dF, p["amplitude"], model, n_, mode, dt_,
                                         perturbation, key, scheme)
        res = expanding_bisection(_label(lambda dF: scene_of2(dF, params), t1), g, width, rtol, max_iter,
                                  floor=lo, ceiling=hi)
        sub = {k: params[k] for k in sensitivities}
        sens = departure_sensitivities(lambda x, s: scene_of2(x, {**params, **s}), res.hi, sub, t1) if sub else {}
        return _named(res), sens

    devices = jax.local_devices()[:len(index)]
    out = [None] * len(index)
    bar = _progress(len(index), progress)
    args_of = lambda chunk: (jnp.asarray(amplitude, dtype), jnp.asarray(mu_of[chunk], dtype), jnp.asarray(chunk),
                             jnp.asarray(guess[chunk], dtype))
    _in_chunks(_on_devices(one, devices, batched=3), len(devices), index, args_of, out, bar)
    bar.close()
    shape = (len(mus), realizations)
    return jax.tree_util.tree_map(lambda *a: jnp.asarray(np.stack(a).reshape(shape + np.shape(a[0]))), *out)
