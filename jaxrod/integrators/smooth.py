"""The smoothed friction law integrated by diffrax (adaptive, explicit or implicit)."""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from ..friction import AbstractFriction, Tanh
from .base import AbstractIntegrator, RunOptions, summarize

__all__ = ["DiffraxSmooth"]


class DiffraxSmooth(AbstractIntegrator):
    """`q̈ = a(q, t) − f_d·tanh(q̇/ε)` solved by a diffrax ODE solver with adaptive steps.

    The smooth law never sticks: a state held by friction creeps (at speed ≈ ε·|a|/f_d) and a
    loaded mode eventually runs away on long horizons. Near v = 0 the friction is a stiff
    damper of rate f_d/ε, so explicit solvers take steps of order ε/f_d; an implicit solver
    (e.g. `diffrax.Kvaerno5()`) does not.

    **Arguments:**

    - `friction`: a smooth law, default `Tanh(eps=1e-3)` (ε in the velocity's unit).
    - `solver`: a diffrax solver (default `diffrax.Tsit5()`; implicit: `diffrax.Kvaerno5()`).
    - `rtol`, `atol`: tolerances of the PID step-size controller.
    - `dt0`: initial step [s]; `max_steps`: cap on steps (result `max_steps` if reached).
    - `adjoint`: how diffrax differentiates the solve: the default supports reverse mode;
      `diffrax.ForwardMode()` supports forward mode (`jax.jvp`, as the boundary search uses).
    """

    friction: AbstractFriction = eqx.field(default_factory=lambda: Tanh(1e-3))
    solver: diffrax.AbstractSolver = diffrax.Tsit5()
    rtol: float = eqx.field(static=True, default=1e-8)
    atol: float = eqx.field(static=True, default=1e-10)
    dt0: float = eqx.field(static=True, default=1e-5)
    max_steps: int = eqx.field(static=True, default=1_000_000)
    adjoint: diffrax.AbstractAdjoint = eqx.field(default_factory=diffrax.RecursiveCheckpointAdjoint)

    def integrate(self, model, q0, v0, t1, n_save, options=RunOptions()):
        dtype = jnp.result_type(float)
        q0 = jnp.asarray(q0, dtype=dtype)
        v0 = jnp.asarray(v0, dtype=dtype)

        def rhs(t, y, args):
            q, v, _ = y
            fa = model.friction_acceleration(self.friction, v, t)
            # power dissipated = rate of kinetic energy removed by friction
            power = jax.jvp(model.kinetic_energy, (v,), (fa,))[1]
            return v, model.acceleration(q, t) - fa, power

        ts = jnp.linspace(0.0, t1, n_save, dtype=dtype)
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs),
            self.solver,
            t0=0.0,
            t1=t1,
            dt0=self.dt0,
            y0=(q0, v0, jnp.zeros((), dtype)),
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=self.rtol, atol=self.atol),
            max_steps=self.max_steps,
            adjoint=self.adjoint,
            throw=False,
        )
        qs, vs, Ds = sol.ys
        bad = sol.result != diffrax.RESULTS.successful
        return summarize(model, ts, qs, vs, Ds, options, sol.stats["num_steps"], bad)
