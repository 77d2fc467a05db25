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

from ._numerics import safe_hypot


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
    def impulse_2d(self, u, W, bound_stick, bound_slip, guess=None):
        """The vector law at contact points (the 3D rod): per point, the 2D impulse
        `p = (p₁, p₂)` [N·s] for the tangential slip velocities `u = (u₁, u₂)` [m/s] of points
        with the symmetric inverse mass `W = (W₁₁, W₁₂, W₂₂)` [1/kg], under the impulse bounds
        `bound_stick` (to hold) and `bound_slip` (when sliding) [N·s]. Every entry is an array
        of one shape (one element per point: components as separate arrays, which fuse on
        CPU). `guess` (p₁, p₂), if given, is an impulse close to the answer (the last sweep's),
        which a law may use to start its iterations. Returns `(p, sticks)`: `sticks` marks the
        points held at rest."""


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

    def impulse_2d(self, u, W, bound_stick, bound_slip, guess=None):
        """The exact proximal step of the vector law: stick, p = −W⁻¹u, while |W⁻¹u| ≤
        `bound_stick`; otherwise the impulse of norm `bound_slip` that maximises dissipation,
        p = −(W + λI)⁻¹u with |p| = `bound_slip` (a 1D secular equation in λ, solved by Newton:
        8 iterations from a lower bound of the root, or 3 from the λ that the impulse `guess`
        satisfies for this u, −(u + W·guess)·guess/|guess|², kept between the root's bounds;
        the slip impulse is scaled onto the bound exactly).

        The slip equation is solved in units where it is of order one: λ = λ_max·t with
        λ_max = |u|/c (c the bound) and W' = W/λ_max, so that |(W' + tI)⁻¹û| = 1 for a unit û.
        Unscaled, a contact whose normal force vanishes (a node lifting off, c → 0) makes λ of
        order |u|/c and the Newton step's det·|y|² of order λ⁴, which overflows float32 (the
        friction pass's default) from c ≈ 1e-10 |u|/|W|: the state became non-finite."""
        W11, W12, W22 = W

        def adj(W, lam, b1, b2):  # adj(W + λI) b and det(W + λI): (W + λI)⁻¹ b = adj b / det
            a11, a22 = W[0] + lam, W[2] + lam
            return (a22 * b1 - W[1] * b2, a11 * b2 - W[1] * b1), a11 * a22 - W[1] * W[1]

        zero = jnp.zeros_like(W11)
        (y1, y2), det = adj(W, zero, *u)
        p_stick = (-y1 / det, -y2 / det)
        sticks = safe_hypot(*p_stick) <= bound_stick
        slips = ~sticks & (bound_slip > 0)
        # slip, scaled (above): Newton on φ(t) = 1/|p(t)| − 1 (concave, increasing) within the
        # root's bounds 1 − tr W' ≤ t* ≤ 1. With p = −y/D (y = adj û, D = det): φ = D/|y| − 1
        # and φ' = y·adj y/|y|³, so a step is one expression with one square root and one
        # division (on CPU each divided intermediate with several users is a kernel of its own)
        c = jnp.where(slips, bound_slip, 1.0)
        norm = jnp.where(slips, safe_hypot(*u), 1.0)
        scale = c / norm  # 1/λ_max
        us = (jnp.where(slips, u[0] / norm, 1.0), jnp.where(slips, u[1] / norm, 0.0))  # û
        Ws = (W11 * scale, W12 * scale, W22 * scale)  # W'
        lo = jnp.maximum(0.0, 1.0 - (Ws[0] + Ws[2]))
        t, iterations = lo, 8
        if guess is not None:
            g1, g2 = guess
            gg = g1 * g1 + g2 * g2
            est = -((u[0] + W11 * g1 + W12 * g2) * g1 + (u[1] + W12 * g1 + W22 * g2) * g2) / jnp.where(gg > 0, gg, 1.0)
            t, iterations = jnp.where(gg > 0, jnp.clip(est * scale, lo, 1.0), lo), 3

        for _ in range(iterations):
            (y1, y2), det = adj(Ws, t, *us)
            (z1, z2), _ = adj(Ws, t, y1, y2)
            yy = y1 * y1 + y2 * y2
            t = jnp.clip(t - (det * yy - yy * jnp.sqrt(yy)) / (y1 * z1 + y2 * z2), lo, 1.0)
        (y1, y2), _ = adj(Ws, t, *us)
        k = c / safe_hypot(y1, y2)  # onto |p| = c
        return tuple(jnp.where(sticks, ps, jnp.where(slips, -k * y, 0.0)) for ps, y in zip(p_stick, (y1, y2))), sticks


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

    def impulse_2d(self, u, W, bound_stick, bound_slip, guess=None):
        """The explicit smoothed impulse −`bound_slip`·tanh(|u|/ε)·u/|u| (never sticks)."""
        eps = self.eps.astype(u[0].dtype)  # the pass may compute in float32
        x = safe_hypot(*u) / eps
        small = x < 1e-4
        xs = jnp.where(small, 1.0, x)
        tanhc = jnp.where(small, 1.0 - x**2 / 3.0, jnp.tanh(xs) / xs)  # tanh(x)/x
        k = -bound_slip * tanhc / eps
        return (k * u[0], k * u[1]), jnp.zeros(x.shape, bool)
