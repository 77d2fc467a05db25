"""The user-level searches: the critical velocity v₀* and the critical load ΔF* of a rod, single
points (pure, vmappable) and curves of them."""

from __future__ import annotations


import equinox as eqx
import jax
import jax.numpy as jnp

from .. import theory
from ..models import SingleMode
from ..scene import Scene, make_perturbation
from .indicators import rod_indicator, single_mode_indicator
from .roots import implicit_sensitivities, safeguarded_newton

__all__ = ['critical_velocity', 'critical_load', 'boundary_curve', 'critical_load_curve']


_ROD_KEYS = ("L", "d", "E", "rho_v", "nu", "R", "g")


def _params_of(rod, **extra) -> dict:
    """The rod's numbers as a flat dict of leaves (μ_s = μ_d = `mu`), plus `extra`."""
    return {"mu": rod.mu_d, "mu_excess": rod.mu_s - rod.mu_d, **{f: getattr(rod, f) for f in _ROD_KEYS},
            **extra}


def _rod_of(rod_type, p: dict):
    """The rod of the parameters: μ_d = `mu`, μ_s = `mu` + `mu_excess` (so a sensitivity to `mu`
    moves both coefficients together, and a rod with μ_s > μ_d keeps its static excess)."""
    return rod_type(*(p[f] for f in _ROD_KEYS), p["mu"] + p["mu_excess"], p["mu"])


def _resolution(rod, dF, model, n, mode, dt):
    """Static n and dt from concrete values (the largest load of the search)."""
    if n is not None and dt is not None:
        return n, dt
    try:
        probe = Scene(rod, dF, kind=model, n=n, mode=mode, dt=dt)
        n = probe.size()
        return n, probe.step()
    except (ValueError, jax.errors.ConcretizationTypeError):
        raise ValueError(
            "pass n and dt explicitly when the rod or the load is traced (e.g. under vmap): "
            "they are static settings."
        ) from None


def _scene(rod, dF, v0, kind, n, mode, dt, perturbation, key):
    pert = make_perturbation(perturbation, v0, mode, key)
    return Scene(rod, dF, pert, kind, n, mode, dt)


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
    rtol: float = 1e-8,
    max_iter: int = 40,
    t1: float = 0.5,
    horizon: float = 10.0,
    sensitivities: tuple[str, ...] = ("mu", "dF"),
):
    """v₀* [m/s]: the smallest perturbation amplitude that buckles the rod at ΔF [N].

    `model="mode"` uses the exact single-mode solution (sine perturbation of `mode`, whose
    amplitude is the lateral speed v₀ = R·Ȧ₀); `"field"`/`"galerkin"` use the projected
    Verlet run of a [`jaxrod.scene.Scene`][] (`n`, `dt` static: pass them when vmapping over
    dF). Pure and vmappable over `rod` leaves, `dF` and `key`.

    **Returns:** `(RootResult, sensitivities)`: the root in m/s and dv₀*/dp for p in
    `sensitivities` (names: `mu` (μ_s and μ_d moved together), `dF`, `R`, any rod field).
    """
    dtype = jnp.result_type(float)
    dF = jnp.asarray(dF, dtype)
    key = jax.random.key(0) if key is None else key

    rod_of = lambda p: _rod_of(type(rod), p)

    if model == "mode":
        def g2(v0, p):
            r = rod_of(p)
            F = theory.reference_load(r) + p["dF"]
            m = SingleMode.from_rod(r, mode, F=F)
            return single_mode_indicator(v0 / r.R, m.k, m.f_s, m.f_d, horizon=horizon)
    else:
        def g2(v0, p):
            return rod_indicator(_scene(rod_of(p), p["dF"], v0, model, n, mode, dt, perturbation, key), t1)

    if model != "mode":
        n, dt = _resolution(rod, dF, model, n, mode, dt)
    params = _params_of(rod, dF=dF)
    res = safeguarded_newton(lambda v: g2(v, params), bracket[0], bracket[1], rtol, max_iter)
    sens = {}
    if sensitivities:
        sub = {k: params[k] for k in sensitivities}
        sens = implicit_sensitivities(lambda x, s: g2(x, {**params, **s}), res.root, sub)
    return res, sens


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
    rtol: float = 1e-8,
    max_iter: int = 40,
    t1: float = 0.5,
    horizon: float = 10.0,
    sensitivities: tuple[str, ...] = ("mu", "amplitude", "R"),
):
    """ΔF* [N]: the load above F⁰_m* at which a perturbation of `amplitude` (m/s for velocity
    perturbations) just buckles the rod (the root of the indicator in ΔF).

    The bracket [N] must be positive; the search runs on log ΔF (`derivative` and `value` of
    the result refer to that variable).

    **Returns:** `(RootResult, sensitivities)`, root in N, with dΔF*/dp for p in
    `sensitivities` (`mu`, `amplitude`, `R`, any rod field). For `model="mode"` with a sine
    perturbation this is P7 (δF = ρf²/(ω_m²Ȧ₀²) measured from F⁰_m).
    """
    dtype = jnp.result_type(float)
    amplitude = jnp.asarray(amplitude, dtype)
    key = jax.random.key(0) if key is None else key

    rod_of = lambda p: _rod_of(type(rod), p)
    params = _params_of(rod, amplitude=amplitude)

    if model == "mode":
        def g2(dF, p):
            r = rod_of(p)
            F = theory.reference_load(r) + dF
            m = SingleMode.from_rod(r, mode, F=F)
            return single_mode_indicator(p["amplitude"] / r.R, m.k, m.f_s, m.f_d, horizon=horizon)
    else:
        def g2(dF, p):
            return rod_indicator(
                _scene(rod_of(p), dF, p["amplitude"], model, n, mode, dt, perturbation, key), t1
            )

    if model != "mode":
        n, dt = _resolution(rod, bracket[1], model, n, mode, dt)
    # Loads span decades and the indicator depends on them through λ ∝ √ΔF: Newton works on
    # log ΔF (6 evaluations instead of 9 for P7 from a factor-10 bracket).
    lo, hi = jnp.log(jnp.asarray(bracket[0], dtype)), jnp.log(jnp.asarray(bracket[1], dtype))
    res = safeguarded_newton(lambda y: g2(jnp.exp(y), params), lo, hi, rtol, max_iter, geometric=False)
    res = eqx.tree_at(lambda r: (r.root, r.lo, r.hi), res, (jnp.exp(res.root), jnp.exp(res.lo), jnp.exp(res.hi)))
    sens = {}
    if sensitivities:
        sub = {k: params[k] for k in sensitivities}
        sens = implicit_sensitivities(lambda x, s: g2(x, {**params, **s}), res.root, sub)
    return res, sens


def boundary_curve(rod, dFs, *, model="field", n=None, dt=None, mode=6, bracket=(1e-4, 1.0),
                   rtol=1e-6, max_iter=60, t1=0.5):
    """v₀*(ΔF) for an array of loads, vmapped (n and dt resolved once from the largest load).

    **Returns:** `(RootResult, sensitivities)` with a leading batch axis.
    """
    import numpy as np

    dFs = np.asarray(dFs, float)
    if model != "mode":
        probe = Scene(rod, float(np.max(dFs)), kind=model, n=n, mode=mode, dt=dt)
        n = probe.size()
        dt = probe.step() if dt is None else dt
    fn = lambda dF: critical_velocity(rod, dF, model=model, mode=mode, n=n, dt=dt, bracket=bracket,
                                      rtol=rtol, max_iter=max_iter, t1=t1, sensitivities=("mu", "dF"))
    return jax.jit(jax.vmap(fn))(jnp.asarray(dFs))


def critical_load_curve(mus, amplitude, *, perturbation="sine", realizations=1, seed=0, model="field",
                        n=None, dt=None, mode=6, bracket=(1e-2, 100.0), rtol=1e-6, max_iter=60, t1=0.5,
                        rod_overrides=None):
    """ΔF*(μ) for an array of friction coefficients and `realizations` random perturbations
    each (keys `fold_in(key(seed), i·realizations + r)`), vmapped.

    **Returns:** `(RootResult, sensitivities)` with batch axes (len(mus), realizations).
    """
    import numpy as np

    from ..params import RodChannel

    mus = np.asarray(mus, float)
    overrides = dict(rod_overrides or {})
    base = RodChannel.reference(mu=float(mus.max()), **overrides)
    if model != "mode":
        probe = Scene(base, float(bracket[1]), kind=model, n=n, mode=mode, dt=dt)
        n = probe.size()
        dt = probe.step() if dt is None else dt
    root_key = jax.random.key(seed)

    def one(mu, r, i):
        rod = RodChannel.reference(mu=mu, **overrides)
        key = jax.random.fold_in(root_key, i * realizations + r)
        return critical_load(rod, amplitude, model=model, perturbation=perturbation, mode=mode, n=n, dt=dt,
                             key=key, bracket=bracket, rtol=rtol, max_iter=max_iter, t1=t1,
                             sensitivities=("mu", "amplitude"))

    idx = jnp.arange(len(mus))
    reals = jnp.arange(realizations)
    run = jax.vmap(jax.vmap(one, (None, 0, None)), (0, None, 0))
    return jax.jit(run)(jnp.asarray(mus), reals, idx)

