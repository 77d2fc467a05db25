"""The worst-case perturbation: the smallest lateral velocity field that buckles the rod.

For a direction ξ (a nodal velocity pattern) the critical scale s*(ξ) is the root in s of the
boundary indicator of the field model started from the velocity field s·ξ/‖ξ‖ (see
[`jaxrod.boundary`][]). The worst case minimises s*(ξ) over directions with optax; the
gradient ∇ξ s* = −∇ξ g / ∂g/∂s comes from the implicit function theorem at the root (one
vmapped forward-mode pass per iteration), never from differentiating the root iterations.
The indicator is piecewise smooth with steep flanks near the boundary, so the gradient is a
local, noisy guide: the search starts from the best of the sine field and `n_random` random
directions and keeps the best direction seen.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from . import theory
from .boundary import rod_indicator, safeguarded_newton
from .modal import modal_spectrum
from .perturbations import UserState
from .scene import Scene

__all__ = ["worst_case_velocity", "field_norm"]


def field_norm(u, norm: str):
    """‖u‖ of a nodal field: `"l2"` = root mean square over the nodes, `"max"` = max |u|."""
    if norm == "l2":
        return jnp.sqrt(jnp.mean(u * u))
    if norm == "max":
        return jnp.max(jnp.abs(u))
    raise ValueError(f"norm = {norm!r} is invalid: expected 'l2' or 'max'.")


def worst_case_velocity(
    rod,
    dF: float,
    *,
    n: int = 32,
    dt: float | None = None,
    norm: str = "l2",
    steps: int = 25,
    learning_rate: float = 0.05,
    t1: float = 0.3,
    bracket=(1e-4, 0.5),
    rtol: float = 1e-9,
    n_random: int = 16,
    seed: int = 0,
    mode: int = 6,
) -> dict:
    """Minimise the critical norm of a lateral velocity field over its direction.

    **Arguments:** `rod`, `dF` [N] (load above F⁰_m*), `n` field nodes, `dt` [s] (default 0.4 of
    the step limit), `norm` (`"l2"`: RMS over nodes; `"max"`), optax Adam `steps` and
    `learning_rate`, indicator horizon `t1` [s], scale `bracket` [m/s], `n_random` random
    directions for comparison, `seed`, the sine `mode` to start from.

    **Returns:** a dict with the worst-case field `u` [m/s at the nodes], its norm
    `norm_worst`, the sine mode-`mode` field's critical norm `norm_sine`, the norm history,
    the modal power spectrum of `u` and its dominant mode, the single-mode prediction (the
    smallest P6 intercept over the unstable modes, in the same norm, and its mode), and the
    critical norms of `n_random` random directions.
    """
    dt_ = dt or Scene(rod, 0.0, kind="field", n=n).step()
    s_nodes = jnp.arange(1, n + 1, dtype=rod.L.dtype) * rod.L / (n + 1)

    def g(scale, xi):
        u = scale * xi / field_norm(xi, norm)
        pert = UserState(jnp.zeros(n), u / rod.R)
        return rod_indicator(Scene(rod, dF, pert, "field", n, mode, dt_), t1)

    @jax.jit
    def critical(xi):
        r = safeguarded_newton(lambda s: g(s, xi), bracket[0], bracket[1], rtol, 80)
        return r.root, r.result

    @jax.jit
    def grad_critical(xi, root):
        dg_dxi = jax.jacfwd(lambda x: g(root, x))(xi)
        _, dg_ds = jax.jvp(lambda s: g(s, xi), (root,), (jnp.ones_like(root),))
        return -dg_dxi / dg_ds

    sine = jnp.sin(mode * jnp.pi * s_nodes / rod.L)
    norm_sine, res_sine = critical(sine)
    keys = jax.random.split(jax.random.key(seed + 1), n_random)
    rand = jax.vmap(lambda kk: jax.random.uniform(kk, (n,), minval=-1.0, maxval=1.0))(keys)
    rand_norms, rand_res = jax.vmap(critical)(rand)
    # multi-start: begin from the best of the sine field and the random directions
    cands = jnp.concatenate([sine[None], rand])
    norms = jnp.concatenate([norm_sine[None], jnp.where(rand_res == 0, rand_norms, jnp.inf)])
    xi = cands[int(jnp.argmin(norms))]
    import optax  # here: 0.2 s to import, which `import jaxrod` need not pay

    opt = optax.adam(learning_rate)
    with jax.numpy_dtype_promotion("standard"):
        state = opt.init(xi)
    best_xi, best = xi, float(jnp.min(norms))
    history = [best]
    for _ in range(steps):
        root, res = critical(xi)
        if int(res) == 0 and float(root) < best:
            best, best_xi = float(root), xi
        history.append(float(root))
        grad = grad_critical(xi, root)
        grad = jnp.where(jnp.isfinite(grad), grad, 0.0)
        # scale-free step: the direction, not its length, matters. optax mixes its int32 step
        # count with floats, which a user's strict dtype promotion would refuse.
        with jax.numpy_dtype_promotion("standard"):
            upd, state = opt.update(grad / (jnp.linalg.norm(grad) + 1e-30) * jnp.linalg.norm(xi), state)
            xi = optax.apply_updates(xi, upd)
    u = best * best_xi / field_norm(best_xi, norm)
    spectrum = np.asarray(modal_spectrum(u, min(n, 40)))
    # single-mode prediction: P6 intercept of every unstable mode, as a field norm
    F = theory.reference_load(rod) + dF
    m = jnp.arange(1, n + 1)
    k = theory.stiffness(rod, m, F)
    v_cr = rod.R * theory.velocity_intercept(k, theory.friction_amplitude(rod))
    to_norm = 1 / jnp.sqrt(2.0) if norm == "l2" else 1.0
    i = int(jnp.argmin(v_cr))
    buckles_at_worst = jax.vmap(lambda x: g(jnp.asarray(best), x) > 0)(rand)
    return {
        "u": np.asarray(u),
        "norm": norm,
        "norm_worst": best,
        "norm_sine": float(norm_sine),
        "sine_result": int(res_sine),
        "history": history,
        "spectrum": spectrum,
        "dominant_mode": int(np.argmax(spectrum)) + 1,
        "single_mode_prediction": float(v_cr[i] * to_norm),
        "single_mode_prediction_mode": i + 1,
        "random_norms": np.asarray(rand_norms),
        "random_results": np.asarray(rand_res),
        "random_buckle_at_worst_norm": float(np.mean(np.asarray(buckles_at_worst))),
        "indicator": lambda scale: float(g(jnp.asarray(scale), best_xi)),
    }
