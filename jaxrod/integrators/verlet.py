"""Projected (proximal) velocity Verlet: the package's default integrator."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .projected import AbstractProjected

__all__ = ["ProjectedVerlet"]


class ProjectedVerlet(AbstractProjected):
    """Velocity Verlet with the friction impulse applied as an exact proximal step after each
    half kick: kick → prox → drift → kick → prox.

    With the [`jaxrod.Coulomb`][] law the friction acts on the very velocity that moves the
    position, so a degree of freedom held by static friction has exactly zero velocity and
    does not move at all (no creep). Second order while no velocity reverses or stops; an
    event (stop, reversal) inside a step costs a local error of first order in the velocity,
    so trajectories with many reversals converge at first order. Explicit: stable for
    `dt · ω_max < 2` with ω_max the model's highest frequency; no limit from the sharp law.

    **Arguments:**

    - `dt`: the largest step [s] (static). The step used is the largest `h ≤ dt` that puts
      every save time on a step.
    - `friction`: the friction law (default [`jaxrod.Coulomb`][]); with [`jaxrod.Tanh`][] the
      scheme is plain explicit Verlet on the smoothed law (needs `dt·f/ε ≲ 2`).
    """

    def step(self, model, q, v, a, t, h):
        half = 0.5 * h
        v_trial = model.kick(q, v, a, half)
        v_half = model.friction_update(self.friction, v_trial, v, half, t, q, a)
        lost, work_in = model.impulse_work(v, v_trial, v_half, a, half)
        q = model.drift(q, v_half, h)
        t1 = t + h
        a = model.accelerations(q, v_half, t1)
        v_trial = model.kick(q, v_half, a, half)
        v = model.friction_update(self.friction, v_trial, v_half, half, t1, q, a)
        lost2, work2 = model.impulse_work(v_half, v_trial, v, a, half)
        return q, v, a, (jax.tree_util.tree_map(jnp.add, lost, lost2), work_in + work2)
