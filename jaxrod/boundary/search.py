"""The user-level searches of one point: the critical velocity v₀* and the critical load ΔF* of a
rod (pure, vmappable); curves of them are `jaxrod.boundary.curves`.

The reduced rod models are searched with runs that stop as soon as their label is known and the
departure rate of [`jaxrod.boundary.departure_rate`][] (`method="departure"`, the default), or by
bisection on the label alone (`method="bisection"`, the baseline); the single mode by Newton on
its exact solution. Curves go along the loads in order, each search started from a prediction
made of its neighbours' roots (`continuation=True`), or all points at once (vmapped).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp

from .. import theory
from ..registry import make_perturbation, perturbation_class, recipe
from ..scene import Scene
from .indicators import crossing_state, departure_rate, departure_sensitivities, single_mode_indicator
from .roots import bisection, departure_secant, implicit_sensitivities, safeguarded_newton

__all__ = ['METHODS', 'critical_velocity', 'critical_load']


_ROD_KEYS = ("L", "d", "E", "rho_v", "nu", "R", "g")


def _params_of(rod, **extra) -> dict:
    """The rod's numbers as a flat dict of leaves (μ_s = μ_d = `mu`), plus `extra`."""
    return {"mu": rod.mu_d, "mu_excess": rod.mu_s - rod.mu_d, **{f: getattr(rod, f) for f in _ROD_KEYS},
            **extra}


def _rod_of(rod_type, p: dict):
    """The rod of the parameters: μ_d = `mu`, μ_s = `mu` + `mu_excess` (so a sensitivity to `mu`
    moves both coefficients together, and a rod with μ_s > μ_d keeps its static excess)."""
    return rod_type(*(p[f] for f in _ROD_KEYS), p["mu"] + p["mu_excess"], p["mu"])


def _resolution(rod, dF, model, n, mode, dt, perturbation="sine"):
    """Static n and dt from concrete values (the largest load of the search)."""
    if n is not None and dt is not None:
        return n, dt
    if any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves((rod, dF))):
        raise ValueError(
            "pass n and dt explicitly when the rod or the load is traced (e.g. under vmap): "
            "they are static settings."
        )
    probe = Scene(rod, dF, make_perturbation(perturbation, 1.0, mode), kind=model, n=n, mode=mode, dt=dt)
    return probe.size(), probe.step()


def _scene(rod, dF, v0, kind, n, mode, dt, perturbation, key, scheme=None):
    pert = make_perturbation(perturbation, v0, mode, key)
    return Scene(rod, dF, pert, kind, n, mode, dt, scheme_key=scheme)


METHODS = ("departure", "bisection")


def _method_of(method, model, perturbation="sine"):
    """The search method: `"exact"` where the model's `search_method` is the closed form and the
    perturbation projects exactly onto its mode (the single mode under a sine velocity),
    else `method`, by default the model's `search_method` (`"departure"` for the reduced models,
    label `"bisection"` for the 3D rod, and for the single mode under other perturbations).

    The 3D rod's departure rate (on the node positions, `Rod3D.translation`, tangents in float64:
    `for_tangents`; roots confirmed by a stable run, `departure_secant`) is opt-in: it compiles
    longer than bisection saves (benchmarks/README.md, boundary_cost.py)."""
    cls = recipe(model)
    if cls.search_method == "exact" and perturbation_class(perturbation).projects_exactly:
        return "exact"
    if method is None:
        return "departure" if cls.search_method == "departure" else "bisection"
    if method not in METHODS:
        raise ValueError(f"method = {method!r} is invalid: expected one of {METHODS}.")
    return method


def _confirms(model) -> bool:
    """Whether a departure-rate search confirms its root with a stable run: for a model whose
    default search is not the departure rate (the 3D rod's is not linear near its root)."""
    return recipe(model).search_method != "departure"


def _named(res):
    """A search that did not converge names no root: NaN beside its result code."""
    from .roots import ROOT_RESULTS

    return eqx.tree_at(lambda r: r.root, res, jnp.where(res.result == ROOT_RESULTS.converged, res.root, jnp.nan))


def _label(scene_of, t1):
    return lambda x: crossing_state(scene_of(x), t1)[1]


def _search(scene_of, lo, hi, lam, method, start, rtol, max_iter, t1, geometric, confirm=False, atol=0.0):
    """The root of the label of `scene_of(x)` in [lo, hi] by `method` (`confirm`: see
    `departure_secant`; the 3D rod's departure rate is not linear near its root)."""
    if method == "bisection":
        return _named(bisection(_label(scene_of, t1), lo, hi, rtol, max_iter, geometric=geometric, atol=atol))
    return departure_secant(lambda x: departure_rate(scene_of, x, t1), lo, hi, lam, start=start,
                            rtol=rtol, max_iter=max_iter, geometric=geometric, confirm=confirm, atol=atol)


def critical_velocity(
    rod,
    dF,
    *,
    model: str = "field",
    perturbation: str = "sine",
    mode: int = 6,
    n: int | None = None,
    dt: float | None = None,
    key=None,
    bracket=(1e-4, 1.0),
    start=None,
    method: str | None = None,
    rtol: float = 1e-6,
    max_iter: int = 60,
    t1: float | None = None,
    horizon: float = 10.0,
    sensitivities: tuple[str, ...] = ("mu", "dF"),
):
    """v₀* [m/s]: the smallest perturbation amplitude that buckles the rod at ΔF [N].

    `model="mode"` uses the exact single-mode solution (sine perturbation of `mode`, whose
    amplitude is the lateral speed v₀ = R·Ȧ₀) and Newton's method; `"field"`/`"galerkin"` run a
    [`jaxrod.scene.Scene`][] until it sticks or buckles (at most `t1` [s]; default the model's
    `search_horizon`: 2 s, the 3D rod 0.4 s) and search by `method`
    (`"departure"`, the default for field and Galerkin: [`jaxrod.boundary.departure_secant`][],
    first run at `start` if given, e.g. a prediction; `"bisection"` on the label, the default
    for `"rod3d"`). `n`, `dt` are static: pass them when vmapping over
    dF. Pure and vmappable over `rod` leaves, `dF`, `start` and `key`.

    **Returns:** `(RootResult, sensitivities)`: the root in m/s (`nan` unless converged) and
    dv₀*/dp for p in `sensitivities` (names: `mu` (μ_s and μ_d moved together), `dF`, `R`, any
    rod field) by the implicit function theorem.
    """
    dF = jnp.asarray(dF, jnp.result_type(float))
    lam = theory.max_growth_rate(rod, theory.reference_load(rod) + dF)
    return _critical(rod, dict(dF=dF), lambda v0, p: (p["dF"], v0), bracket[0], bracket[1], start, rtol, 0.0, True,
                     lam, dF, _IDENTITY, model=model, perturbation=perturbation, mode=mode, n=n, dt=dt, key=key,
                     method=method, max_iter=max_iter, t1=t1, horizon=horizon, sensitivities=sensitivities)


def critical_load(
    rod,
    amplitude,
    *,
    model: str = "field",
    perturbation: str = "sine",
    mode: int = 6,
    n: int | None = None,
    dt: float | None = None,
    key=None,
    bracket=(0.05, 100.0),
    start=None,
    method: str | None = None,
    rtol: float = 1e-6,
    max_iter: int = 60,
    t1: float = 2.0,
    horizon: float = 10.0,
    sensitivities: tuple[str, ...] = ("mu", "amplitude", "R"),
):
    """ΔF* [N]: the load above F⁰_m* at which a perturbation of `amplitude` (m/s for velocity
    perturbations) just buckles the rod (the root of the label in ΔF).

    The bracket [N] must be positive; the search runs on log ΔF (`start` [N], `value` and
    `derivative` of the result refer to that variable) to a bracket of relative width `rtol` in
    ΔF (log1p(`rtol`) in log ΔF, whatever the load). Models and methods as
    [`jaxrod.boundary.critical_velocity`][].

    **Returns:** `(RootResult, sensitivities)`, root in N, with dΔF*/dp for p in
    `sensitivities` (`mu`, `amplitude`, `R`, any rod field). For `model="mode"` with a sine
    perturbation this is P7 (δF = ρf²/(ω_m²Ȧ₀²) measured from F⁰_m).
    """
    dtype = jnp.result_type(float)
    amplitude = jnp.asarray(amplitude, dtype)
    # Loads span decades and the runs depend on them through λ ∝ √ΔF: search log ΔF.
    lo, hi = jnp.log(jnp.asarray(bracket[0], dtype)), jnp.log(jnp.asarray(bracket[1], dtype))
    y0 = None if start is None else jnp.log(jnp.asarray(start, dtype))
    log_tol = math.log1p(rtol)  # a bracket of relative width `rtol` in ΔF is one of log1p(rtol) in log ΔF
    F0 = theory.reference_load(rod)
    lam = lambda y: theory.max_growth_rate(rod, F0 + jnp.exp(y))
    return _critical(rod, dict(amplitude=amplitude), lambda dF, p: (dF, p["amplitude"]), lo, hi, y0, 0.0, log_tol,
                     False, lam, bracket[1], _LOG, model=model, perturbation=perturbation, mode=mode, n=n, dt=dt,
                     key=key, method=method, max_iter=max_iter, t1=t1, horizon=horizon, sensitivities=sensitivities)


# the search variable y of a root x: (x of y, the result in x); v₀ is searched as is, ΔF as log ΔF
_IDENTITY = (lambda y: y, lambda res: res)
_LOG = (jnp.exp, lambda res: eqx.tree_at(lambda r: (r.root, r.lo, r.hi), res,
                                         (jnp.exp(res.root), jnp.exp(res.lo), jnp.exp(res.hi))))


def _critical(rod, known: dict, point, lo, hi, start, rtol, atol, geometric, lam, size_load, variable, *, model,
              perturbation, mode, n, dt, key, method, max_iter, t1, horizon, sensitivities):
    """The critical value x of a search in y (`variable`: x of y, and the result back in x) over
    [`lo`, `hi`], the rod's other value `known` (`dF` or `amplitude`), `point(x, params)` the
    (ΔF, amplitude) of a run; the single mode's closed form (`"exact"`) or runs of scenes at the
    static resolution of the load `size_load`. **Returns:** `(RootResult, sensitivities)` in x."""
    x_of, back = variable
    t1 = recipe(model).search_horizon if t1 is None else t1
    key = jax.random.key(0) if key is None else key
    method = _method_of(method, model, perturbation)
    rod_of = lambda p: _rod_of(type(rod), p)
    params = _params_of(rod, **known)
    sub = {k: params[k] for k in sensitivities}

    if method == "exact":
        def g2(x, p):
            r = rod_of(p)
            dF, amplitude = point(x, p)
            m = recipe(model).build(r, theory.reference_load(r) + dF, None, mode)
            return single_mode_indicator(amplitude / r.R, m.k, m.f_s, m.f_d, horizon=horizon)

        res = _named(back(safeguarded_newton(lambda y: g2(x_of(y), params), lo, hi, rtol, max_iter,
                                             geometric=geometric, atol=atol)))
        sens = implicit_sensitivities(lambda x, s: g2(x, {**params, **s}), res.root, sub) if sub else {}
        return res, sens

    n, dt = _resolution(rod, size_load, model, n, mode, dt, perturbation)
    scene_of2 = lambda x, p: _scene(rod_of(p), *point(x, p), model, n, mode, dt, perturbation, key)
    res = back(_search(lambda y: scene_of2(x_of(y), params), lo, hi, lam, method, start, rtol, max_iter, t1,
                       geometric, _confirms(model), atol=atol))
    # the lowest buckled run lies within about rtol of the root: the tangents there give dx/dp
    sens = departure_sensitivities(lambda x, s: scene_of2(x, {**params, **s}), res.hi, sub, t1) if sub else {}
    return res, sens
