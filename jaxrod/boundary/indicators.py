"""The buckling indicators whose roots are the boundary: the single mode's exact state at a
horizon against its stick line, a rod's max|θ(T)| against the buckling threshold."""

from __future__ import annotations


import jax
import jax.numpy as jnp
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, Float

from .._results import RESULTS
from ..integrators.base import RunOptions
from ..models import SingleMode, exact_solution
from ..scene import Scene
from ..simulate import simulate

__all__ = ['single_mode_indicator', 'rod_indicator', 'run_label', 'crossing_state', 'departure_rate', 'departure_sensitivities', 'smooth_single_mode_indicator']


def single_mode_indicator(Adot0, k, f_s, f_d, A0=0.0, horizon: float = 10.0):
    """g = A(T)/a − 1 of the exact single-mode solution at T = `horizon`/√|k|, a = f_s/|k| the
    largest amplitude static friction holds (k < 0 required: for k ≥ 0 there is no boundary and
    g is −1 or nan). With μ_s = μ_d, a is the saddle f/|k| and g is smooth at the root; with
    μ_s > μ_d a state that stops between f_d/|k| and f_s/|k| is held (g ≤ 0), one that stops
    beyond runs away, and g jumps at the root (the bracket still converges, by bisection)."""
    lam = jnp.sqrt(jnp.abs(k))
    T = horizon / lam
    a = f_s / jnp.abs(k)
    sign = jnp.where(Adot0 < 0, -1.0, 1.0)  # perturbations of either sign: mirror to Ȧ₀ > 0
    A, _, _, _, _ = exact_solution(sign * A0, jnp.abs(Adot0), k, f_s, f_d, T)
    return A / a - 1.0


def rod_indicator(scene: Scene, t1: float = 0.5):
    """g = log(max|θ(T)|/θ_c) of a scene at T = `t1` [s], with the buckling stop lifted (the run
    still stops when the rod is stuck: it stays stuck)."""
    problem = scene.resolve()  # the model built once
    sol = simulate(
        problem.model, problem.integrator, problem.q0, problem.v0, t1, n_save=101,
        options=RunOptions(buckle_threshold=1e200, save_state=False), throw=False,
    )
    amp = problem.model.amplitude(sol.q_final)
    return jnp.log(jnp.maximum(amp, 1e-300) / scene.threshold)


def run_label(sol) -> Float[Array, ""]:
    """The label of a finished run: 1.0 buckled, 0.0 not (held, or stable at its horizon), NaN
    when the run failed (its state became non-finite or its step was above the limit), which says
    nothing about the rod's stability: a search must not count it as stable."""
    ok = sol.result == RESULTS.successful
    return jnp.where(ok, sol.buckled.astype(jnp.result_type(float)), jnp.nan)


def crossing_state(scene: Scene, t1: float = 2.0, tangents: bool = False):
    """The state where the run of `scene` stops: `((q, v), label)` (`run_label`: 1.0 buckled,
    0.0 not, NaN for a failed run), at the first step past the
    buckling threshold, when the rod is stuck (then it stays stuck; the reduced models are
    frozen at the step they stick, the 3D rod at the next of 200 saves), or at `t1` [s] —
    whichever comes first, so that both labels are cheap. Differentiable (forward mode) in every
    leaf of the scene at a fixed step count; with `tangents`, the model is
    `AbstractModel.for_tangents` (what a forward-mode run needs)."""
    problem = scene.resolve()  # the model built once
    model = problem.model.for_tangents() if tangents else problem.model
    sol = simulate(
        model, problem.integrator, problem.q0, problem.v0, t1, n_save=201,
        options=RunOptions(buckle_threshold=scene.threshold, save_state=False), throw=False,
    )
    return (sol.q_final, sol.v_final), run_label(sol)


def _along(a, b):
    """<a, b>/<b, b>: the component of `a` along `b` (arrays or pytrees of them)."""
    a, b = ravel_pytree(a)[0], ravel_pytree(b)[0]
    return jnp.vdot(a, b) / jnp.vdot(b, b)


def departure_rate(scene_of, x, t1: float = 2.0):
    """Whether the scene `scene_of(x)` buckles, and how far x lies above the boundary x*.

    A rod just above the boundary lingers near the marginally held state, then leaves it along
    the fastest unstable direction w of the sliding rod: q − q_c ≈ c·(x − x*)·e^{λt}·w. At the
    crossing of the threshold both q̇ and ∂q/∂x carry that factor, so the component of q̇ along
    ∂q/∂x (one forward-mode tangent of the run of [`crossing_state`][])

    u = <q̇, ∂q/∂x> / <∂q/∂x, ∂q/∂x> ≈ λ·(x − x*)

    is linear in the distance to the boundary whatever the horizon, the threshold or the
    growth reached. Measured for the field model (μ = 0.3, ΔF = 5 N, benchmarks/README.md):
    u/(v₀ − v₀*) stays within 86–120 s⁻¹ from (v₀ − v₀*)/v₀* = 1e-7 to 0.1, where the
    amplitude at a fixed horizon jumps from 0.05 to 1e30 rad at the root.

    **Arguments:** `scene_of` (x → [`jaxrod.scene.Scene`][], forward differentiable in x; for
    the 3D rod u projects the node velocities on the nodes' tangent, `Rod3D.translation`), `x`, `t1` (horizon [s]: a run that neither sticks nor buckles by then
    counts as stable).

    **Returns:** `(label, u)`: the run's `run_label` (1.0 buckled, 0.0 not, NaN failed) and
    `u` in units of x per second (`nan` when not buckled).
    """
    x = jnp.asarray(x, jnp.result_type(float))
    (_, v), (dq, _), label = jax.jvp(
        lambda x: crossing_state(scene_of(x), t1, tangents=True), (x,), (jnp.ones_like(x),), has_aux=True
    )
    dq, v = scene_of(x).model().translation(dq, v)  # the 3D rod: node positions and velocities
    return label, jnp.where(label > 0, _along(v, dq), jnp.nan)


def departure_sensitivities(scene_of, x, params: dict, t1: float = 2.0) -> dict:
    """dx*/dp of the boundary for every p in `params`, from one buckled run at `x` just above
    it: the tangents ∂q/∂x and ∂q/∂p at the crossing are both dominated by the growing
    direction, and q depends on x and p through x − x*(p) there, so
    dx*/dp = −<∂q/∂p, ∂q/∂x>/<∂q/∂x, ∂q/∂x> (the implicit function theorem on the departure;
    the error is of the order of (x − x*)/x*). `scene_of(x, params)` builds the scene.

    **Returns:** a dict with the keys of `params`.
    """
    x = jnp.asarray(x, jnp.result_type(float))
    q_of = lambda xp: crossing_state(scene_of(*xp), t1, tangents=True)[0][0]
    keys = list(params)
    # the tangents along x and along every parameter, as one batched forward-mode run
    unit = lambda i: (jnp.asarray(i == 0, x.dtype),
                      {k: jnp.full_like(params[k], i == j + 1) for j, k in enumerate(keys)})
    tangents = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *[unit(i) for i in range(len(keys) + 1)])
    dq = jax.vmap(lambda t: jax.jvp(q_of, ((x, params),), (t,))[1])(tangents)
    dq_x = jax.tree_util.tree_map(lambda a: a[0], dq)
    return {k: -_along(jax.tree_util.tree_map(lambda a, j=j: a[j + 1], dq), dq_x) for j, k in enumerate(keys)}


def smooth_single_mode_indicator(Adot0, k, f, eps, horizon: float = 10.0, solver=None):
    """As `single_mode_indicator`, with the friction smoothed to f·tanh(Ȧ/ε) and integrated
    by diffrax (forward-mode differentiable). The smooth law creeps, so its root differs from
    the sharp one by an amount that vanishes with ε."""
    import diffrax

    from ..friction import Tanh
    from ..integrators import DiffraxSmooth

    # in units x = A/a and τ = λt the equation is x'' − x + tanh(x'/ε') = 0, ε' = ε/(λa)
    lam = jnp.sqrt(jnp.abs(k))
    a = f / jnp.abs(k)
    integ = DiffraxSmooth(Tanh(eps / (a * lam)), solver or diffrax.Kvaerno5(), rtol=1e-10,
                          atol=1e-12, dt0=1e-3, adjoint=diffrax.ForwardMode())
    model = SingleMode(-jnp.ones_like(k), jnp.ones_like(f), jnp.ones_like(f))
    sol = simulate(model, integ, 0.0, Adot0 / (a * lam), horizon, n_save=2, throw=False)
    return sol.q[-1] - 1.0

