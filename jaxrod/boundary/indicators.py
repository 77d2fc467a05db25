"""The buckling indicators whose roots are the boundary: the single mode's exact state at a
horizon against its stick line, a rod's max|θ(T)| against the buckling threshold."""

from __future__ import annotations


import jax.numpy as jnp

from ..integrators.base import RunOptions
from ..models import SingleMode, exact_solution
from ..scene import Scene
from ..simulate import simulate

__all__ = ['single_mode_indicator', 'rod_indicator', 'smooth_single_mode_indicator']


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
    q0, v0 = scene.initial_state()
    model = scene.model()
    sol = simulate(
        model, scene.integrator(), q0, v0, t1, n_save=101,
        options=RunOptions(buckle_threshold=1e200, save_state=False), throw=False,
    )
    amp = model.amplitude(sol.q_final)
    return jnp.log(jnp.maximum(amp, 1e-300) / scene.threshold)


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

