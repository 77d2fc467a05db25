"""Root finding inside a bracket: the safeguarded Newton iteration, bisection, smooth-law
continuation, and sensitivities of a root by the implicit function theorem."""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int


__all__ = ['ROOT_RESULTS', 'RootResult', 'safeguarded_newton', 'bisection', 'implicit_sensitivities', 'continuation']


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

