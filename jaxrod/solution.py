"""The solution structure shared by every integrator."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

__all__ = ["Solution"]


class Solution(eqx.Module):
    """What every integrator returns, whatever the model.

    **Fields:**

    - `ts`: save times [s], shape (n_save,).
    - `q`, `v`: the state at `ts` — coordinates (modal amplitude A [rad] of the single-mode
      model, nodal angles θ [rad] of the field model, modal amplitudes of the Galerkin model)
      and their velocities [rad/s], shape (n_save, *dof); `None` when the run was made with
      `save_state=False`.
    - `stuck`: whether the system is at rest and held by static friction, shape (n_save,).
    - `amplitude`: the largest deflection max|θ| [rad] at `ts`, shape (n_save,).
    - `energies`: named energies at `ts` (kinetic and potential parts; J for the rod models),
      each of shape (n_save,).
    - `dissipated`: energy dissipated by friction (and, for the 3D rod, contact and viscous
      damping) up to `ts`, shape (n_save,).
    - `work_in`: work done on the system by driven boundaries up to `ts` (the 3D rod's pushed
      end under displacement control; zero otherwise), shape (n_save,).
    - `observables`: model-specific records at `ts` (empty for the reduced models; the 3D
      rod's θ at every node, end reactions, wall and axial forces, ...: see
      [`jaxrod.rod3d.Rod3D.observables`][]).
    - `buckled`: whether the amplitude passed the buckling threshold; `t_buckle` when it did
      [s] (`inf` if never).
    - `t_stop`: when the run stopped (buckled, stuck under a constant load, or `t1`) [s];
      after it the state is frozen and saves repeat the final state.
    - `q_final`, `v_final`: the state at `t_stop`.
    - `result`: a [`jaxrod.RESULTS`][] code (int32 scalar).
    - `n_steps`: time steps (or, for the exact solution, slip phases) taken.
    - `step_stats`: for an error-controlled scheme ([`jaxrod.AdaptiveImplicitLeapfrog`][]),
      the steps it used: `rejected` (attempts rejected), `h_min`, `h_max` [s] (smallest and
      largest accepted step), `forced` (steps taken at `dt_min` with the estimate above the
      tolerance); `None` for a fixed step.
    """

    ts: Float[Array, " n_save"]
    q: Float[Array, "n_save ..."] | None
    v: Float[Array, "n_save ..."] | None
    stuck: Bool[Array, " n_save"]
    amplitude: Float[Array, " n_save"]
    energies: dict[str, Float[Array, " n_save"]]
    dissipated: Float[Array, " n_save"]
    work_in: Float[Array, " n_save"]
    observables: dict[str, Array]
    buckled: Bool[Array, ""]
    t_buckle: Float[Array, ""]
    t_stop: Float[Array, ""]
    q_final: Float[Array, "..."]
    v_final: Float[Array, "..."]
    result: Int[Array, ""]
    n_steps: Int[Array, ""]
    step_stats: dict | None = None

    @property
    def total_energy(self) -> Float[Array, " n_save"]:
        """Mechanical energy plus the energy dissipated, minus the work put in (constant if the
        balance closes)."""
        return sum(self.energies.values()) + self.dissipated - self.work_in

    @property
    def energy_balance(self) -> Float[Array, " n_save"]:
        """E(t) + dissipated(t) − work_in(t) − E(0) [J]: zero for an exact scheme."""
        total = self.total_energy
        return total - total[..., :1]

    def energy_balance_error(self) -> Float[Array, ""]:
        """max |E(t) + D(t) − E(0)| over the saves, relative to the largest energy term seen."""
        total = self.total_energy
        scale = jnp.max(jnp.stack([jnp.max(jnp.abs(e)) for e in self.energies.values()]))
        return jnp.max(jnp.abs(total - total[0])) / jnp.maximum(scale, jnp.finfo(total.dtype).tiny)
