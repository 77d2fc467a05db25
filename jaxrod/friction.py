r"""Friction laws, from smooth to sharp.

Friction enters every model as a bounded acceleration per degree of freedom: the single-mode
oscillator's `f sgn(Ȧ)`, the field model's `μN/(ρR) sgn(θ_t)` at each node. A law says how a
velocity is updated over a step `h` under that bound (`update`, used by the fixed-step
integrators) and what force it exerts as a function of velocity (`acceleration`, used by ODE
solvers and explicit schemes).

| law | sticks exactly | differentiable | fails where |
|---|---|---|---|
| [`jaxrod.Coulomb`][] (proximal) | yes | piecewise (kinks at stick/slip) | — |
| [`jaxrod.Tanh`][] | no: creeps at speed ~ ε·(elastic/friction force) | yes | long horizons, h·f/ε ≫ 1 |

`Coulomb.acceleration` is the plain sign law: an explicit scheme built on it chatters and
never sticks (kept as the documented failure case, see `jaxrod.SymplecticEuler`).
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._numerics import safe_norm

__all__ = ["AbstractFriction", "Coulomb", "Tanh", "coulomb_prox"]


def coulomb_prox(
    v_trial: Float[Array, "..."],
    v_prev: Float[Array, "..."],
    h: ArrayLike,
    f_s: Float[Array, "..."],
    f_d: Float[Array, "..."],
) -> Float[Array, "..."]:
    """The exact (implicit) Coulomb friction impulse over a step `h`: the proximal map of the
    set-valued law, a soft threshold with a static/dynamic switch.

    A degree of freedom at rest (`v_prev == 0`) stays exactly at rest while the trial velocity
    the other forces would give it is within `h·f_s`; otherwise it slips, losing `h·f_d` of
    speed. One that was moving stops exactly when its trial speed is within `h·f_d`.

    **Arguments:**

    - `v_trial`: velocity after the non-friction impulse [rad/s or m/s].
    - `v_prev`: velocity at the start of the step (selects the static or dynamic bound).
    - `h`: step [s].
    - `f_s`, `f_d`: static and dynamic friction bounds, as accelerations [rad/s² or m/s²].

    **Returns:** the velocity after friction, exactly zero where the point sticks.
    """
    threshold = h * jnp.where(v_prev == 0, f_s, f_d)
    slips = jnp.abs(v_trial) > threshold
    return jnp.where(slips, v_trial - h * f_d * jnp.sign(v_trial), jnp.zeros_like(v_trial))


class AbstractFriction(eqx.Module):
    """A friction law acting as a bounded acceleration per degree of freedom."""

    @abc.abstractmethod
    def update(self, v_trial, v_prev, h, f_s, f_d):
        """Velocity after the friction impulse of a step `h` [s] applied to `v_trial`."""

    @abc.abstractmethod
    def acceleration(self, v, f_s, f_d):
        """Friction acceleration (opposing `v`) as a function of velocity, for ODE solvers."""

    @abc.abstractmethod
    def impulse_2d(self, u, W, bound_stick, bound_slip):
        """The vector law at contact points (the 3D rod): per point, the 2D impulse `p` [N·s]
        for the tangential slip velocities `u` (n, 2) [m/s] of points with inverse mass `W`
        (n, 2, 2), under the impulse bounds `bound_stick` (to hold) and `bound_slip` (when
        sliding) [N·s], (n,). Returns `(p, sticks)`: `sticks` marks the points held at rest."""


class Coulomb(AbstractFriction):
    """The exact set-valued Coulomb law with static (`f_s`) and dynamic (`f_d`) bounds.

    `update` is [`jaxrod.coulomb_prox`][]: exact stick, and slip with the dynamic bound.
    `acceleration` is `f_d·sgn(v)`, which only an explicit scheme uses — and which chatters
    around zero velocity instead of sticking.
    """

    def update(self, v_trial, v_prev, h, f_s, f_d):
        return coulomb_prox(v_trial, v_prev, h, f_s, f_d)

    def acceleration(self, v, f_s, f_d):
        return f_d * jnp.sign(v)

    def impulse_2d(self, u, W, bound_stick, bound_slip):
        """The exact proximal step of the vector law: stick, p = −W⁻¹u, while |W⁻¹u| ≤
        `bound_stick`; otherwise the impulse of norm `bound_slip` that maximises dissipation,
        p = −(W + λI)⁻¹u with |p| = `bound_slip` (a 1D secular equation in λ, solved by Newton)."""
        det = W[:, 0, 0] * W[:, 1, 1] - W[:, 0, 1] * W[:, 1, 0]

        def solve(A_det, A, b):
            return jnp.stack([A[:, 1, 1] * b[:, 0] - A[:, 0, 1] * b[:, 1],
                              -A[:, 1, 0] * b[:, 0] + A[:, 0, 0] * b[:, 1]], -1) / A_det[:, None]

        p_stick = -solve(det, W, u)
        sticks = safe_norm(p_stick) <= bound_stick
        slips = ~sticks & (bound_slip > 0)
        # slip: Newton on φ(λ) = 1/|p(λ)| − 1/c (concave, increasing), from a λ₀ left of the root
        c = jnp.where(slips, bound_slip, 1.0)
        trW = W[:, 0, 0] + W[:, 1, 1]
        us = jnp.where(slips[:, None], u, jnp.array([[1.0, 0.0]], u.dtype) * 2.0 * trW[:, None])
        lam = jnp.maximum(0.0, safe_norm(us) / c - trW)
        eye = jnp.eye(2, dtype=u.dtype)
        for _ in range(8):
            A = W + lam[:, None, None] * eye[None]
            Ad = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
            p = -solve(Ad, A, us)
            pn = safe_norm(p)
            dphi = jnp.sum(p * solve(Ad, A, p), -1) / pn**3
            lam = jnp.maximum(lam - (1.0 / pn - 1.0 / c) / dphi, 0.0)
        A = W + lam[:, None, None] * eye[None]
        p_slip = -solve(A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0], A, us)
        return jnp.where(sticks[:, None], p_stick, jnp.where(slips[:, None], p_slip, 0.0)), sticks


class Tanh(AbstractFriction):
    """The smoothed law `f_d·tanh(v/ε)` (no static coefficient: it never sticks).

    **Arguments:**

    - `eps`: regularisation velocity ε [same unit as the velocity: rad/s for modal and
      angular velocities], > 0. A dynamic leaf: continuation in ε never recompiles.

    Near zero velocity the law is a viscous damper of coefficient f_d/ε, so a state held by
    friction creeps at speed ≈ ε·(elastic force)/f_d and a loaded rod (negative stiffness)
    eventually runs away. Explicit steps need h·f_d/ε ≲ 2.
    """

    eps: Float[Array, "..."] = eqx.field(converter=jnp.asarray)

    def update(self, v_trial, v_prev, h, f_s, f_d):
        return v_trial - h * self.acceleration(v_trial, f_s, f_d)

    def acceleration(self, v, f_s, f_d):
        return f_d * jnp.tanh(v / self.eps)

    def impulse_2d(self, u, W, bound_stick, bound_slip):
        """The explicit smoothed impulse −`bound_slip`·tanh(|u|/ε)·u/|u| (never sticks)."""
        x = safe_norm(u) / self.eps
        small = x < 1e-4
        xs = jnp.where(small, 1.0, x)
        tanhc = jnp.where(small, 1.0 - x**2 / 3.0, jnp.tanh(xs) / xs)  # tanh(x)/x
        return -(bound_slip * tanhc / self.eps)[:, None] * u, jnp.zeros(u.shape[:1], bool)
