"""Projected (proximal) leapfrog: one friction pass per step, velocities at half steps."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .projected import AbstractProjected

__all__ = ["ProjectedLeapfrog"]


class ProjectedLeapfrog(AbstractProjected):
    """Leapfrog with the friction impulse applied as an exact proximal step after each kick:
    kick → prox → drift, one friction pass per step.

    [`jaxrod.ProjectedVerlet`][] ends a step with a half kick and a friction pass at the new
    position, and starts the next with another half kick and pass at the same position. This
    scheme merges the two: a full kick of h and one pass with the bounds of a full step (μN·h),
    so the velocity it carries is the one of the half step that moves the position
    (v_{n+½} = prox_h(v_{n−½} + h·a_n), q_{n+1} = q_n + h·v_{n+½}). Positions are those of
    velocity Verlet while no contact changes between stick and slip; at such an event the two
    schemes differ by a local error of first order, the order of both. A degree of freedom held
    by static friction has exactly zero velocity and does not move (the hold condition is the
    same, |W⁻¹u| ≤ μ_s N h for the whole step). For models whose friction pass is most of the
    step (the 3D rod: cheaper per step than projected Verlet, docs/rod3d.md)
    it was the default before [`jaxrod.ImplicitLeapfrog`][] (which keeps this structure with an
    implicit kick); the reduced models keep projected Verlet.

    The first step of a run (t = 0) starts from the velocity at t = 0: its kick and friction
    pass are half a step, as velocity Verlet's first half. The velocity recorded at a save
    (and `Solution.v_final`) is the one at the saved position: the half kick and friction pass
    of `velocity_at`, which velocity Verlet would end its step with; between saves the run
    carries the half-step velocity, and the stop tests (stuck, buckled) read it.

    **Arguments:**

    - `dt`: the largest step [s] (static). The step used is the largest `h ≤ dt` that puts
      every save time on a step.
    - `friction`: the friction law (default [`jaxrod.Coulomb`][]).
    """

    def step(self, model, q, v, a, t, h, h_save=None, at_position=None, hk=None):
        """One step (`h` [s]); with `at_position` (a traced bool) where it is true, instead the
        velocity pass of `velocity_at` at the save step `h_save`, in the same computation: one
        copy of the friction pass to compile, not two (the 3D rod's run compiled 12.2 → 7.4 s
        without the second copy, e3e6015's CLI command). Then `h` must be 0 there, the carried
        velocity, the position (a drift of 0) and the forces (recomputed from the same inputs)
        come back unchanged, no work is counted, and the velocity at the position is returned as
        a fifth output. `hk`: the kick's length where not the step's (a variable step's mean of the
        two steps around the position, `jaxrod.AdaptiveImplicitLeapfrog`)."""
        if hk is None:
            hk = jnp.where(t > 0, h, 0.5 * h)  # the first step starts from the velocity at t = 0
        if at_position is not None:
            hk = jnp.where(at_position, jnp.where(t > 0, 0.5 * h_save, jnp.zeros_like(hk)), hk)
        h_kick = jnp.where(at_position, h_save, h) if at_position is not None else h
        v_trial, v_new, aux = self.kick_and_friction(model, q, v, a, hk, h_kick, t)
        lost, work_in = model.impulse_work(v, v_trial, v_new, a, hk)
        lost = self.kick_loss(model, v, v_new, aux, lost)
        v_run = v_new
        if at_position is not None:
            select = lambda new, old: jnp.where(at_position, old, new)
            v_run = jax.tree_util.tree_map(select, v_new, v)
            lost = jax.tree_util.tree_map(lambda x: jnp.where(at_position, jnp.zeros_like(x), x), lost)
            work_in = jnp.where(at_position, jnp.zeros_like(work_in), work_in)
        q = model.drift(q, v_run, h)
        a = model.accelerations(q, v_run, t + h)
        if at_position is None:
            return q, v_run, a, (lost, work_in)
        v_at = jax.tree_util.tree_map(lambda new, old: jnp.where(t > 0, new, old), v_new, v)
        return q, v_run, a, (lost, work_in), v_at

    def kick_and_friction(self, model, q, v, a, hk, h, t):
        """`(v_trial, v_new, aux)`: the kick of `hk` in a step of `h` (`kick_with_aux`) and the
        friction pass after it (`model.friction_update`)."""
        v_trial, aux = self.kick_with_aux(model, q, v, a, hk, h)
        return v_trial, model.friction_update(self.friction, v_trial, v, hk, t, q, a), aux

    def kick(self, model, q, v, a, hk, h):
        """The kick of `hk` [s] in a step of `h` [s]: `model.kick` (explicit, f/m)."""
        return model.kick(q, v, a, hk)

    def kick_with_aux(self, model, q, v, a, hk, h):
        """`(kick, aux)`: the kick and what `kick_loss` needs of it (nothing here)."""
        return self.kick(model, q, v, a, hk, h), None

    def kick_loss(self, model, v_prev, v_after, aux, lost):
        """`lost` [J] with the energy the kick itself removes added (none here: the kick is
        conservative)."""
        return lost

    velocity_in_step = True

    def velocity_at(self, model, q, v, a, t, h):
        """The velocity at the position `q` (time `t`) from the half-step velocity `v` the run
        carries: a half kick and a friction pass of h/2 (at t = 0, `v` itself)."""
        zero = jnp.zeros_like(jnp.asarray(h))
        return self.step(model, q, v, a, t, zero, h_save=h, at_position=jnp.array(True))[4]
