"""Root finding inside a bracket: the safeguarded Newton iteration, bisection, smooth-law
continuation, and sensitivities of a root by the implicit function theorem."""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int


__all__ = ['ROOT_RESULTS', 'RootResult', 'safeguarded_newton', 'departure_secant', 'bisection', 'expanding_bisection', 'implicit_sensitivities', 'continuation']


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
        3: "the indicator was not finite (a run failed: non-finite state or a step above its limit)",
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


# measured on the field model (benchmarks/boundary_cost.py): aiming 5 % short of the predicted
# root and stepping back a quarter of the bracket after an overshoot
_SHORT, _BACK = 0.05, 0.25


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
    atol: float = 0.0,
) -> RootResult:
    """Find x in [`lo`, `hi`] with g(x) = 0, where g(lo) ≤ 0 < g(hi).

    Newton steps x − g/g′ (g′ by `jax.jvp`), replaced by a bisection step whenever they leave
    the current bracket or are not finite; the bracket is updated by the sign of g at every
    evaluation. Stops — before evaluating again — when the next Newton step would be smaller
    than `rtol`·|x| + `atol` (the root is then that Newton point, whose error is of the order of
    the step squared) or the bracket is narrower than `rtol`·|x| + `atol` (`atol` for a search in
    log x, where a relative tolerance on x is an absolute one on log x).

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
        small = ok & ((jnp.abs(newton - x) <= (rtol * jnp.abs(x) + atol)) | (gx == 0))
        return newton, ok, small

    # state: x, g(x), g'(x), lo, hi, evaluations after the bracket checks
    def cond(s):
        x, gx, dx, lo, hi, n = s
        _, _, small = newton_of(x, gx, dx, lo, hi)
        narrow = (hi - lo) <= (rtol * jnp.abs(x) + atol)
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
    narrow = (hi - lo) <= (rtol * jnp.abs(x) + atol)
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


def departure_secant(
    evaluate: Callable,
    lo,
    hi,
    rate_bound,
    *,
    start=None,
    rtol: float = 1e-6,
    max_iter: int = 40,
    geometric: bool = True,
    confirm: bool = False,
    atol: float = 0.0,
) -> RootResult:
    """The boundary x* in [`lo`, `hi`] from runs that stop as soon as their label is known:
    `evaluate(x)` returns `(label, u)` with u ≈ λ·(x − x*) > 0 for a buckled run (see
    [`jaxrod.boundary.departure_rate`][]) and no number for a stable one; the label is a
    boolean (True: buckled) or 1.0 / 0.0, NaN for a failed run, which ends the search with
    `ROOT_RESULTS.nonfinite` and the bracket known so far.

    Each iteration steps from the lowest buckled point x₁ to x₁ − u₁/s, with s the slope of u
    between the two lowest buckled points (a secant on the linear branch), or `rate_bound`
    (an upper bound on λ, e.g. [`jaxrod.theory.max_growth_rate`][], or a function of x giving
    one; the step then stops short
    of the root and stays on the buckled side) while only one is known or the secant slope is
    not positive. A step that leaves the bracket (the largest stable x, the smallest buckled x)
    becomes a bisection. Stops when the next step would be smaller than `rtol`·x₁ + `atol` (the
    root is that step's end) or the bracket is narrower than `rtol`·x + `atol`.

    `lo` and `hi` are trusted, not run (a stable `lo` is run only when the iteration ends next
    to it, so that a bracket without the root is reported); the first run is at `start`
    (default `hi`), e.g. a prediction from a neighbouring root. With `confirm`, a secant root is
    accepted only once a stable run 0.9·`rtol`·|x₁| below the lowest buckled point x₁ holds it (a
    buckled one there continues the secant): the result then lies in a label bracket of
    relative width `rtol` (for a rate that is not linear so close to the root, as the 3D rod's).

    **Returns:** a [`jaxrod.boundary.RootResult`][] (`value`: u at x₁; `derivative`: the slope
    s used last; pure and vmappable).
    """
    dtype = jnp.result_type(float)
    lo = jnp.asarray(lo, dtype)
    hi = jnp.asarray(hi, dtype)
    bound = rate_bound if callable(rate_bound) else (lambda x, b=jnp.asarray(rate_bound, dtype): b)
    x0 = hi if start is None else jnp.clip(jnp.asarray(start, dtype), lo, hi)
    nan = jnp.asarray(jnp.nan, dtype)
    lo_bound, hi_bound = lo, hi

    def candidate(lo, hi, x1, u1, x2, u2, again):
        have1, have2 = jnp.isfinite(u1), jnp.isfinite(u2)
        secant = (u2 - u1) / (x2 - x1)
        lam = bound(jnp.where(have1, x1, hi))
        s = jnp.where(have2 & (secant > 0) & jnp.isfinite(secant), jnp.minimum(secant, lam), lam)
        c = x1 - u1 / s
        small = have1 & (jnp.abs(x1 - c) <= (rtol * jnp.abs(x1) + atol))
        # aim a little short of the predicted root: an overshoot costs a run that only moves lo
        aim = x1 - (1 - _SHORT) * u1 / s
        # after an overshoot the root lies just above lo: step a fraction of the way back up
        # (half of it after a second stable run in a row)
        back = lo + jnp.where(again, 0.5, _BACK) * (x1 - lo)
        # before the first buckled run: grow from the stable side by at most 25 %
        fallback = jnp.where(have1, jnp.where(lo > lo_bound, back, _mid(lo, hi, geometric)),
                             jnp.minimum(_mid(lo, hi, geometric), lo * 1.25))
        ok = have1 & jnp.isfinite(aim) & (aim > lo) & (aim < hi)
        return jnp.where(ok, aim, fallback), small & (c > lo), s

    # state: next x, lo, hi, (x1, u1) lowest buckled, (x2, u2) second lowest, lo run?, n,
    # done, invalid, root, slope, last run stable?
    def cond(st):
        return ~st[9] & (st[8] < max_iter)

    def body(st):
        x, lo, hi, x1, u1, x2, u2, lo_run, n, done, invalid, root, s, was_stable, failed = st
        label, u = evaluate(x)
        label = jnp.asarray(label).astype(dtype)
        failed = jnp.isnan(label)
        buckled = label > 0
        n = n + 1
        invalid = invalid | (buckled & (x <= lo_bound)) | (~buckled & ~failed & (x >= hi_bound))
        lower = buckled & (x < x1)
        x2, u2 = jnp.where(lower, x1, jnp.where(buckled & (x < x2), x, x2)), jnp.where(
            lower, u1, jnp.where(buckled & (x < x2), u, u2))
        x1, u1 = jnp.where(lower, x, x1), jnp.where(lower, u, u1)
        hi = jnp.where(buckled, jnp.minimum(hi, x), hi)
        lo = jnp.where(buckled | failed, lo, jnp.maximum(lo, x))
        lo_run = lo_run | (~buckled & ~failed & (x <= lo_bound))
        c, small, s = candidate(lo, hi, x1, u1, x2, u2, was_stable & ~buckled)
        narrow = (hi - lo) <= (rtol * jnp.abs(hi) + atol)
        # ending next to an untested lower end: run it once, to tell a root from a bad bracket
        unconfirmed = small & ~narrow if confirm else jnp.zeros_like(small)  # no stable run holds it yet
        accepted = (small & ~unconfirmed) | narrow
        check_lo = accepted & (lo <= lo_bound) & ~lo_run
        finished = invalid | failed | (accepted & ~check_lo)
        root = jnp.where(small, c, _mid(lo, hi, False))
        x_next = jnp.where(check_lo, lo_bound, jnp.where(unconfirmed, x1 - 0.9 * (rtol * jnp.abs(x1) + atol), c))
        return x_next, lo, hi, x1, u1, x2, u2, lo_run, n, finished, invalid, root, s, ~buckled, failed

    inf = jnp.asarray(jnp.inf, dtype)
    st = (x0, lo, hi, inf, nan, inf, nan, jnp.array(False), jnp.array(0), jnp.array(False),
          jnp.array(False), nan, nan, jnp.array(False), jnp.array(False))
    x, lo, hi, x1, u1, x2, u2, lo_run, n, done, invalid, root, s, _, failed = jax.lax.while_loop(cond, body, st)
    result = jnp.where(
        failed, ROOT_RESULTS.nonfinite, jnp.where(
            invalid, ROOT_RESULTS.invalid_bracket,
            jnp.where(done, ROOT_RESULTS.converged, ROOT_RESULTS.max_iterations)),
    ).astype(jnp.int32)
    # a failed search names no root (its bracket still says what is known)
    root = jnp.where(done & ~invalid & ~failed, root, jnp.nan)
    return RootResult(root, lo, jnp.minimum(hi, x1), u1, s, n.astype(jnp.int32), result)


def bisection(g, lo, hi, rtol: float = 1e-10, max_iter: int = 200, geometric: bool = True,
              atol: float = 0.0) -> RootResult:
    """Plain bisection on the sign of g (the baseline; no derivatives), to `rtol`·|x| + `atol`. `g` may
    return a boolean label (True: above the root). A NaN value (a failed run, see
    [`jaxrod.boundary.crossing_state`][]) ends the search with `ROOT_RESULTS.nonfinite` and the
    bracket known so far: it says nothing about the side of the root."""
    dtype = jnp.result_type(float)
    label = g

    def g(x):
        y = jnp.asarray(label(x))
        return jnp.where(y, 1.0, 0.0).astype(dtype) if y.dtype == bool else y

    lo = jnp.asarray(lo, dtype)
    hi = jnp.asarray(hi, dtype)
    g_lo, g_hi = g(lo), g(hi)
    finite = jnp.isfinite(g_lo) & jnp.isfinite(g_hi)
    valid = (g_lo <= 0) & (g_hi > 0)

    def cond(s):
        lo, hi, n, gx = s
        return (hi - lo > (rtol * jnp.abs(hi) + atol)) & (n < max_iter) & valid & jnp.isfinite(gx)

    def body(s):
        lo, hi, n, _ = s
        x = _mid(lo, hi, geometric)
        gx = g(x)
        return jnp.where(gx <= 0, x, lo), jnp.where(gx > 0, x, hi), n + 1, gx

    lo, hi, n, gx = jax.lax.while_loop(cond, body, (lo, hi, jnp.array(0), jnp.where(finite, g_hi, jnp.nan)))
    ok = hi - lo <= (rtol * jnp.abs(hi) + atol)
    result = jnp.where(~jnp.isfinite(gx), ROOT_RESULTS.nonfinite, jnp.where(
        ~valid, ROOT_RESULTS.invalid_bracket,
        jnp.where(ok, ROOT_RESULTS.converged, ROOT_RESULTS.max_iterations))).astype(jnp.int32)
    return RootResult(0.5 * (lo + hi), lo, hi, gx, jnp.nan * gx, (n + 2).astype(jnp.int32), result)


def expanding_bisection(g, guess, width: float = 0.04, rtol: float = 1e-2, max_iter: int = 16,
                        floor: float = 1e-12, ceiling: float = float("inf")) -> RootResult:
    """Geometric bisection on a label (True above the root) from a first bracket
    `guess`·(1 ∓ `width`) around a prediction: while its two ends agree the bracket moves toward
    the root, widened by a factor that squares at every move (1 + 2`width`, then its square, …)
    and clipped to [`floor`, `ceiling`]; once they differ it is bisected geometrically until
    hi − lo ≤ `rtol`·hi. One label per iteration, `max_iter` labels in all (the first two
    included), and `g` is called at one place in the program (a loop whose first two iterations
    label the bracket's ends): a label that is a whole simulation compiles once, not three times
    as with [`jaxrod.boundary.bisection`][]. From a good prediction a narrow bracket takes a few
    labels, against the dozen of a bisection over decades (benchmarks/README.md, "the user's
    boundary command").

    **Returns:** a `RootResult` (`evaluations` counts the labels): `converged`;
    `invalid_bracket` when the bracket reached `floor` or `ceiling` with both ends alike;
    `max_iterations`; `nonfinite` when a label is NaN (a failed run: nothing is known of its side)."""
    dtype = jnp.result_type(float)

    def label(x):
        y = jnp.asarray(g(x))
        return jnp.where(y, 1.0, 0.0).astype(dtype) if y.dtype == bool else (y > 0).astype(dtype) + 0 * y

    guess = jnp.asarray(guess, dtype)
    floor, ceiling = jnp.asarray(floor, dtype), jnp.asarray(ceiling, dtype)
    lo = jnp.clip(guess * (1 - width), floor, ceiling)
    hi = jnp.clip(guess * (1 + width), floor, ceiling)

    def bracketed(s):
        return (s[5] >= 2) & (s[2] == 0) & (s[3] == 1)

    def at_limit(s):  # both ends alike, and the bracket cannot move further that way
        lo, hi, g_lo, g_hi, _, n = s
        return (n >= 2) & (((g_lo == 1) & (g_hi == 1) & (lo <= floor)) | ((g_lo == 0) & (g_hi == 0) & (hi >= ceiling)))

    def narrow(s):
        return bracketed(s) & (s[1] - s[0] <= rtol * s[1])

    def cond(s):
        finite = jnp.isfinite(s[2]) & jnp.isfinite(s[3])
        return finite & ~narrow(s) & ~at_limit(s) & (s[5] < max_iter)

    def body(s):
        lo, hi, g_lo, g_hi, step, n = s
        inside = bracketed(s)
        below = g_lo == 1  # both ends buckled: the root lies below lo
        moved = jnp.where(below, jnp.maximum(lo / step, floor), jnp.minimum(hi * step, ceiling))
        x = jnp.where(n == 0, lo, jnp.where(n == 1, hi, jnp.where(inside, jnp.sqrt(lo * hi), moved)))
        gx = label(x)
        first = n < 2  # the ends themselves
        # inside: x replaces the end of its label; outside: the bracket moves to [x, lo] or [hi, x]
        new = (jnp.where(inside, jnp.where(gx == 0, x, lo), jnp.where(below, x, hi)),
               jnp.where(inside, jnp.where(gx == 0, hi, x), jnp.where(below, lo, x)),
               jnp.where(inside, jnp.where(gx == 0, gx, g_lo), jnp.where(below, gx, g_hi)),
               jnp.where(inside, jnp.where(gx == 0, g_hi, gx), jnp.where(below, g_lo, gx)))
        ends = (lo, hi, jnp.where(n == 0, gx, g_lo), jnp.where(n == 1, gx, g_hi))
        out = tuple(jnp.where(first, a, b) for a, b in zip(ends, new))
        return out + (jnp.where(inside | first, step, step * step), n + 1)

    zero = jnp.zeros((), dtype)
    s0 = (lo, hi, zero, zero, jnp.asarray(1 + 2 * width, dtype), jnp.array(0))
    lo, hi, g_lo, g_hi, _, n = s = jax.lax.while_loop(lambda s: (s[5] < 2) | cond(s), body, s0)
    finite = jnp.isfinite(g_lo) & jnp.isfinite(g_hi)
    result = jnp.where(~finite, ROOT_RESULTS.nonfinite, jnp.where(
        narrow(s), ROOT_RESULTS.converged, jnp.where(at_limit(s), ROOT_RESULTS.invalid_bracket,
                                                     ROOT_RESULTS.max_iterations))).astype(jnp.int32)
    return RootResult(jnp.sqrt(lo * hi), lo, hi, jnp.where(finite, g_hi, jnp.nan), jnp.nan * g_hi,
                      n.astype(jnp.int32), result)


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

