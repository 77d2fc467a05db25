r"""Gradient-based search for the stable-zone boundary and the critical load.

**The indicator.** A root finder needs a function of the searched value x (the perturbation
amplitude, or the load) that changes sign at the boundary and whose derivative is informative on
both sides. The label "buckled" is a step function; instead jaxrod measures the state at a
finite horizon T against the stick line:

- single mode: `g = A(T)/a − 1`, a = f/|k| the half-width of the stick line. A stable state
  ends stuck at |A| ≤ a (g ≤ 0); an unstable one passes the saddle at A = a and runs away
  (g > 0). The exact piecewise solution is continuous in (Ȧ₀, k, f) and, in each slip phase,
  smooth; at the boundary itself the trajectory is still slipping towards the saddle at time
  T, so g is smooth there and its root lies above the separatrix by a relative
  ≈ 2e^{−2λT} (λ = √|k|; T = `horizon`/λ, default 10: 4e-9).
- field and Galerkin models: `g = log(max|θ(T)|/θ_c)` with θ_c the buckling threshold
  (0.5 rad) and the buckling stop lifted: stuck rods give g < 0 (the stuck amplitude grows
  with the perturbation), growing rods g > 0. The sharp law makes θ(T) piecewise smooth in the
  inputs (kinks where a node's stick/slip sequence changes), and continuous — the proximal
  step is a continuous map — so g is continuous and its forward derivative exists almost
  everywhere. The root converges to the 2 s / 0.5 rad classification boundary as T grows.

**The solver** is a safeguarded Newton iteration (derivatives by forward-mode AD through the
integrator) inside a bracket kept valid by the sign of g (= the buckled label); a Newton step
that leaves the bracket, or is not finite, is replaced by bisection (geometric for positive
brackets). Everything is pure and vmappable: a batch of boundary points is one `vmap`.

**Sensitivities** of the root x*(p) follow from the implicit function theorem at the root,
dx*/dp = −(∂g/∂p)/(∂g/∂x): one forward-mode derivative per parameter, no differentiation
through the iterations.
"""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from . import theory
from .integrators.base import RunOptions
from .models import SingleMode, exact_solution
from .scene import Scene, make_perturbation
from .simulate import simulate

__all__ = [
    "ROOT_RESULTS",
    "RootResult",
    "safeguarded_newton",
    "bisection",
    "implicit_sensitivities",
    "single_mode_indicator",
    "rod_indicator",
    "critical_velocity",
    "critical_load",
]


class ROOT_RESULTS:
    """Result codes of a root search."""

    converged = 0
    max_iterations = 1
    invalid_bracket = 2
    nonfinite = 3
    messages = {
        0: "converged",
        1: "the iteration cap was reached before the tolerance",
        2: "the bracket does not contain a sign change (g(lo) <= 0 < g(hi) is required)",
        3: "the indicator was not finite",
    }


class RootResult(eqx.Module):
    """A root of the indicator and how it was found.

    - `root`: the boundary value x*; `lo`, `hi`: the final bracket (g(lo) ≤ 0 < g(hi)).
    - `value`: g at the last evaluated point; `derivative`: ∂g/∂x there.
    - `evaluations`: model evaluations (simulations) used, bracket checks included; each
      Newton evaluation is one forward-mode (jvp) run.
    - `result`: a `ROOT_RESULTS` code.
    """

    root: Float[Array, ""]
    lo: Float[Array, ""]
    hi: Float[Array, ""]
    value: Float[Array, ""]
    derivative: Float[Array, ""]
    evaluations: Int[Array, ""]
    result: Int[Array, ""]


def _mid(lo, hi, geometric):
    return jnp.where(geometric & (lo > 0), jnp.sqrt(lo * hi), 0.5 * (lo + hi))


def safeguarded_newton(
    g: Callable[[Float[Array, ""]], Float[Array, ""]],
    lo,
    hi,
    rtol: float = 1e-10,
    max_iter: int = 30,
    geometric: bool = True,
    start: str = "hi",
) -> RootResult:
    """Find x in [`lo`, `hi`] with g(x) = 0, where g(lo) ≤ 0 < g(hi).

    Newton steps x − g/g′ (g′ by `jax.jvp`), replaced by a bisection step whenever they leave
    the current bracket or are not finite; the bracket is updated by the sign of g at every
    evaluation. Stops — before evaluating again — when the next Newton step would be smaller
    than `rtol`·|x| (the root is then that Newton point, whose error is of the order of the
    step squared) or the bracket is narrower than `rtol`·|x|.

    **Arguments:** `g` (scalar → scalar, forward-differentiable), the bracket, `rtol`,
    `max_iter` (evaluations after the two bracket checks), `geometric` (bisect in log space
    for positive brackets), `start` (`"hi"`, `"lo"` or `"mid"`: where Newton starts).

    **Returns:** a [`jaxrod.boundary.RootResult`][] (pure, vmappable).
    """
    dtype = jnp.result_type(float)
    lo = jnp.asarray(lo, dtype)
    hi = jnp.asarray(hi, dtype)
    gd = lambda x: jax.jvp(g, (x,), (jnp.ones_like(x),))
    g_lo, d_lo = gd(lo)
    g_hi, d_hi = gd(hi)
    valid = (g_lo <= 0) & (g_hi > 0) & jnp.isfinite(g_lo) & jnp.isfinite(g_hi)
    if start == "hi":
        x, gx, dx = hi, g_hi, d_hi
    elif start == "lo":
        x, gx, dx = lo, g_lo, d_lo
    else:
        x = _mid(lo, hi, geometric)
        gx, dx = gd(x)

    def newton_of(x, gx, dx, lo, hi):
        newton = x - gx / dx
        # an infinite or zero derivative (overflowing growth, a flat capped indicator) gives no
        # usable Newton step: bisect instead, and never read it as convergence
        ok = jnp.isfinite(newton) & jnp.isfinite(dx) & (dx != 0) & (newton >= lo) & (newton <= hi)
        small = ok & ((jnp.abs(newton - x) <= rtol * jnp.abs(x)) | (gx == 0))
        return newton, ok, small

    # state: x, g(x), g'(x), lo, hi, evaluations after the bracket checks
    def cond(s):
        x, gx, dx, lo, hi, n = s
        _, _, small = newton_of(x, gx, dx, lo, hi)
        narrow = (hi - lo) <= rtol * jnp.abs(x)
        return valid & (n < max_iter) & ~small & ~narrow & jnp.isfinite(gx)

    def body(s):
        x, gx, dx, lo, hi, n = s
        newton, ok, _ = newton_of(x, gx, dx, lo, hi)
        inside = ok & (newton > lo) & (newton < hi)
        x_new = jnp.where(inside, newton, _mid(lo, hi, geometric))
        g_new, d_new = gd(x_new)
        lo = jnp.where(g_new <= 0, x_new, lo)
        hi = jnp.where(g_new > 0, x_new, hi)
        return x_new, g_new, d_new, lo, hi, n + 1

    x, gx, dx, lo, hi, n = jax.lax.while_loop(cond, body, (x, gx, dx, lo, hi, jnp.array(0)))
    newton, _, small = newton_of(x, gx, dx, lo, hi)
    narrow = (hi - lo) <= rtol * jnp.abs(x)
    converged = small | narrow
    root = jnp.where(small, newton, _mid(lo, hi, False))
    result = jnp.where(
        ~valid,
        ROOT_RESULTS.invalid_bracket,
        jnp.where(
            converged,
            ROOT_RESULTS.converged,
            jnp.where(jnp.isfinite(gx), ROOT_RESULTS.max_iterations, ROOT_RESULTS.nonfinite),
        ),
    ).astype(jnp.int32)
    evals = (2 + n + (1 if start == "mid" else 0)).astype(jnp.int32)
    return RootResult(root, lo, hi, gx, dx, evals, result)


def bisection(g, lo, hi, rtol: float = 1e-10, max_iter: int = 200, geometric: bool = True) -> RootResult:
    """Plain bisection on the sign of g (the baseline; no derivatives), to `rtol`·|x|."""
    dtype = jnp.result_type(float)
    lo = jnp.asarray(lo, dtype)
    hi = jnp.asarray(hi, dtype)
    g_lo, g_hi = g(lo), g(hi)
    valid = (g_lo <= 0) & (g_hi > 0)

    def cond(s):
        lo, hi, n, _ = s
        return (hi - lo > rtol * jnp.abs(hi)) & (n < max_iter) & valid

    def body(s):
        lo, hi, n, _ = s
        x = _mid(lo, hi, geometric)
        gx = g(x)
        return jnp.where(gx <= 0, x, lo), jnp.where(gx > 0, x, hi), n + 1, gx

    lo, hi, n, gx = jax.lax.while_loop(cond, body, (lo, hi, jnp.array(0), g_hi))
    ok = hi - lo <= rtol * jnp.abs(hi)
    result = jnp.where(~valid, ROOT_RESULTS.invalid_bracket,
                       jnp.where(ok, ROOT_RESULTS.converged, ROOT_RESULTS.max_iterations)).astype(jnp.int32)
    return RootResult(0.5 * (lo + hi), lo, hi, gx, jnp.nan * gx, (n + 2).astype(jnp.int32), result)


def implicit_sensitivities(g2: Callable, x_root, params: dict) -> dict:
    """dx*/dp for every parameter p of `params` by the implicit function theorem:
    dx*/dp = −(∂g/∂p)/(∂g/∂x) at the root, with `g2(x, params)` the indicator.

    **Returns:** a dict with the same keys as `params`.
    """
    _, dg_dx = jax.jvp(lambda x: g2(x, params), (x_root,), (jnp.ones_like(x_root),))
    out = {}
    for k in params:
        tangent = {j: jnp.zeros_like(v) if j != k else jnp.ones_like(v) for j, v in params.items()}
        _, dg_dp = jax.jvp(lambda p: g2(x_root, p), (params,), (tangent,))
        out[k] = -dg_dp / dg_dx
    return out


# -- indicators ------------------------------------------------------------------------------

def single_mode_indicator(Adot0, k, f_s, f_d, A0=0.0, horizon: float = 10.0):
    """g = A(T)/a − 1 of the exact single-mode solution at T = `horizon`/√|k|, a = f_d/|k|
    (k < 0 required: for k ≥ 0 there is no boundary and g is −1 or nan)."""
    lam = jnp.sqrt(jnp.abs(k))
    T = horizon / lam
    a = f_d / jnp.abs(k)
    sign = jnp.where(Adot0 < 0, -1.0, 1.0)  # perturbations of either sign: mirror to Ȧ₀ > 0
    A, _, _, _, _ = exact_solution(sign * A0, jnp.abs(Adot0), k, f_s, f_d, T)
    return A / a - 1.0


def rod_indicator(scene: Scene, t1: float = 0.5):
    """g = log(max|θ(T)|/θ_c) of a scene at T = `t1` [s], with the buckling stop lifted (the run
    still stops when the rod is stuck: it stays stuck)."""
    q0, v0 = scene.initial_state()
    model = scene.model()
    sol = simulate(
        model, scene.integrator(), q0, v0, t1, n_save=101,
        options=RunOptions(buckle_threshold=1e200, save_state=False), throw=False,
    )
    amp = model.amplitude(sol.q_final)
    return jnp.log(jnp.maximum(amp, 1e-300) / scene.threshold)


# -- user-level searches -------------------------------------------------------------------------

_ROD_KEYS = ("L", "d", "E", "rho_v", "nu", "R", "g")


def _params_of(rod, **extra) -> dict:
    """The rod's numbers as a flat dict of leaves (μ_s = μ_d = `mu`), plus `extra`."""
    return {"mu": rod.mu_d, **{f: getattr(rod, f) for f in _ROD_KEYS}, **extra}


def _rod_of(rod_type, p: dict):
    return rod_type(*(p[f] for f in _ROD_KEYS), p["mu"], p["mu"])


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
    `sensitivities` (names: `mu` (μ_s = μ_d), `dF`, `R`, any rod field).
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



# -- batches of boundary points (host-side drivers for the CLI and notebooks) ---------------------

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

    from .params import RodChannel

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


def smooth_single_mode_indicator(Adot0, k, f, eps, horizon: float = 10.0, solver=None):
    """As `single_mode_indicator`, with the friction smoothed to f·tanh(Ȧ/ε) and integrated
    by diffrax (forward-mode differentiable). The smooth law creeps, so its root differs from
    the sharp one by an amount that vanishes with ε."""
    import diffrax

    from .friction import Tanh
    from .integrators import DiffraxSmooth

    # in units x = A/a and τ = λt the equation is x'' − x + tanh(x'/ε') = 0, ε' = ε/(λa)
    lam = jnp.sqrt(jnp.abs(k))
    a = f / jnp.abs(k)
    integ = DiffraxSmooth(Tanh(eps / (a * lam)), solver or diffrax.Kvaerno5(), rtol=1e-10,
                          atol=1e-12, dt0=1e-3, adjoint=diffrax.ForwardMode())
    model = SingleMode(-jnp.ones_like(k), jnp.ones_like(f), jnp.ones_like(f))
    sol = simulate(model, integ, 0.0, Adot0 / (a * lam), horizon, n_save=2, throw=False)
    return sol.q[-1] - 1.0


def continuation(g_of_eps, eps_values, lo, hi, rtol=1e-10, max_iter=60, widen=1.5):
    """Roots of g_ε for decreasing ε, each seeding the next: the bracket for ε_{i+1} is
    [root_i/`widen`, root_i·`widen`] (falling back to the full [`lo`, `hi`] if it does not
    bracket). Host-side loop. **Returns:** a list of `RootResult`, one per ε."""
    out = []
    a, b = lo, hi
    for eps in eps_values:
        g = lambda x, eps=eps: g_of_eps(x, eps)
        r = safeguarded_newton(g, a, b, rtol, max_iter)
        if int(r.result) == ROOT_RESULTS.invalid_bracket:
            r = safeguarded_newton(g, lo, hi, rtol, max_iter)
        out.append(r)
        a, b = float(r.root) / widen, float(r.root) * widen
    return out
