"""Implicit leapfrog: the projected leapfrog with a kick that solves with the model's stiffness,
so that its step is not bounded by the stiffest vibration."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._results import RESULTS
from .leapfrog import ProjectedLeapfrog

__all__ = ["ImplicitLeapfrog"]


class ImplicitLeapfrog(ProjectedLeapfrog):
    """Projected leapfrog whose kick is implicit in the model's conservative forces:
    Newmark's average-acceleration scheme in leapfrog form, (M + β h² H(qₙ) + γ h² H_d(qₙ)) Δv =
    h F(qₙ) − γ h² H_d v_{n−½}, then the friction pass (as [`jaxrod.ProjectedLeapfrog`][]: exact
    stick, static and dynamic μ) and the drift qₙ₊₁ = qₙ + h v_{n+½}.

    With β = ¼ (default) it is the trapezoidal rule on a linear system: stable at any step and,
    with γ = 0, without numerical dissipation; 0 < β < ¼ is stable up to a step 2/(ω_max √(1 − 4β));
    β = 0 is the explicit leapfrog. γ adds the numerical damping γ h H_d v, where H_d is the
    model's choice of the stiffness it damps (the 3D rod: shear, bend and twist, not stretch or the wall,
    `jaxrod.rod3d.hessian`): damping ratio γ h ω / 2 in such a mode of frequency ω. Without it
    the stiff modes that the friction pass excites at every stick–slip event keep their amplitude,
    aliased to the step's Nyquist frequency, and the friction pass reads them as slip (without
    the damping v₀* moves with the step, and large steps blow up: `docs/rod3d.md`, "The implicit
    step", gives the measurements). The stiffness is linearised at qₙ (one linear
    solve per step, no Newton iteration: nothing to fail to converge; a matrix that is not positive
    definite gives a non-finite state and the result code `nonfinite`). The model must provide
    `implicit_kick(q, v, a, hk, h, beta, gamma)` and `implicit_step` ([`jaxrod.rod3d.Rod3D`][]: a
    block-tridiagonal solve, `jaxrod.rod3d.hessian`). The friction pass sees each contact's own
    mass (as in the explicit scheme), not the stiffness that couples it to its neighbours within
    the step: the coupling acts at the next step, a first-order splitting error at stick–slip
    events, and past the wall's wrinkling load it lets the 3D rod wrinkle (its runs there end with
    the result code `inadequate`). With `coupled=True` the kick and the friction are solved
    together on the step's operator (`model.coupled_kick`, `jaxrod.rod3d.coupled`): right past
    the wrinkling load, several times the cost of a step at 500 segments, and no closer to the explicit
    scheme elsewhere (docs/rod3d.md, "Where the implicit step fails").

    **Arguments:**

    - `dt`: the largest step [s] (static).
    - `friction`: the friction law (default [`jaxrod.Coulomb`][]).
    - `beta`: Newmark's β (static, in [0, 1], default ¼).
    - `gamma`: the numerical damping γ (static, ≥ 0, default 0.1; 0: none, energy kept).
    - `coupled`: solve the friction with the kick on the step's operator (static, default
      `False`: the local friction pass after the kick).
    """

    beta: float = eqx.field(static=True, default=0.25)
    gamma: float = eqx.field(static=True, default=0.1)
    coupled: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        if not (isinstance(self.beta, (int, float)) and 0.0 <= self.beta <= 1.0):
            raise ValueError(f"ImplicitLeapfrog.beta = {self.beta!r} is invalid: expected a float in [0, 1].")
        if not (isinstance(self.gamma, (int, float)) and 0.0 <= self.gamma < float("inf")):
            raise ValueError(f"ImplicitLeapfrog.gamma = {self.gamma!r} is invalid: expected a finite float >= 0.")

    def kick_and_friction(self, model, q, v, a, hk, h, t):
        """With `coupled`, the kick and the friction solved together on the step's operator
        (`model.coupled_kick`, `jaxrod.rod3d.coupled`); else the kick, then the friction pass."""
        if not self.coupled:
            return super().kick_and_friction(model, q, v, a, hk, h, t)
        v_new, v_trial, impulse = model.coupled_kick(q, v, a, hk, h, self.beta, self.gamma)
        return v_trial, v_new, (impulse if self.gamma else None)

    def kick(self, model, q, v, a, hk, h):
        if not hasattr(model, "implicit_kick"):
            raise TypeError(f"ImplicitLeapfrog needs a model with implicit_kick; {type(model).__name__} has none "
                            "(use ProjectedLeapfrog or ProjectedVerlet).")
        return model.implicit_kick(q, v, a, hk, h, self.beta, self.gamma)

    def kick_with_aux(self, model, q, v, a, hk, h):
        """The kick and the damping's impulse it applied (`model.implicit_kick(..., with_impulse=True)`)."""
        if not self.gamma or not hasattr(model, "implicit_kick"):  # (`kick` names a model without it)
            return self.kick(model, q, v, a, hk, h), None
        return model.implicit_kick(q, v, a, hk, h, self.beta, self.gamma, with_impulse=True)

    def kick_loss(self, model, v_prev, v_after, aux, lost):
        """`lost` [J] with the work of the numerical damping added (`model.damping_loss` of the
        impulse the kick applied), so that `dissipated` counts it."""
        if aux is None:
            return lost
        return tuple(a + b for a, b in zip(lost, model.damping_loss(v_prev, v_after, aux)))

    def result(self, model, s, h, check_step_limit: bool = True):
        """The base code, or `RESULTS.inadequate` where the model says this scheme is outside
        its measured range (`model.implicit_inadequate(coupled)`, the 3D rod past the wall's
        wrinkling load with the local friction pass): a run that says so, not a wrong label."""
        code = super().result(model, s, h, check_step_limit)
        check = getattr(model, "implicit_inadequate", None)
        if check is None:
            return code
        return jnp.where((code == RESULTS.successful) & check(self.coupled), RESULTS.inadequate, code).astype(code.dtype)

    @classmethod
    def default_step(cls, model, q=None) -> float:
        """The model's accuracy step for this scheme (`model.implicit_step`, [s]), or half the
        explicit limit at `q` where that is larger (a rod of a few segments)."""
        return max(float(model.implicit_step), super().default_step(model, q))

    def step_limit(self, model):
        if self.beta >= 0.25:
            return jnp.inf
        om = model.max_frequency()
        return 2.0 / (om * jnp.sqrt(1.0 - 4.0 * self.beta))
