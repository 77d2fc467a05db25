"""The solution structure shared by every integrator."""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array, Bool, Float, Int

__all__ = ["Solution"]


class Solution(eqx.Module):
    """What every integrator returns, whatever the model.

    **Fields:**

    - `ts`: save times [s], shape (n_save,).
    - `q`: generalised coordinates at `ts` (the modal amplitude A [rad] of the single-mode
      model; nodal angles θ [rad] of the field model), shape (n_save, *dof).
    - `v`: their velocities [rad/s], same shape as `q`.
    - `stuck`: whether the rod is stuck at each save time (velocity exactly zero and the
      elastic force inside the static friction bound), shape (n_save,).
    - `result`: a [`jaxrod.RESULTS`][] code (int32 scalar).
    - `n_steps`: time steps (or, for the exact solution, slip phases) taken.
    """

    ts: Float[Array, " n_save"]
    q: Float[Array, "n_save ..."]
    v: Float[Array, "n_save ..."]
    stuck: Bool[Array, " n_save"]
    result: Int[Array, ""]
    n_steps: Int[Array, ""]
