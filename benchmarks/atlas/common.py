"""What the failure-atlas entries share: the reference rod (μ = 0.3), the loaded single mode
and its scales, the field model's step limit and critical sine velocity."""

from __future__ import annotations

import jax
import jax.numpy as jnp

import jaxrod as jr
from jaxrod.boundary.roots import bisection

ROD = jr.RodChannel.reference(mu=0.3)


def mode_at(dF, mu=0.3):
    return jr.SingleMode.from_rod(jr.RodChannel.reference(mu=mu), dF=dF)


def scales(m):
    """λ = √|k| [1/s], a = f/|k| [rad], Ȧ_cr = f/λ [rad/s] of a loaded single mode."""
    lam = float(jnp.sqrt(-m.k))
    return lam, float(m.f_d) / lam**2, float(m.f_d) / lam


def field_limit(n, dF=0.0):
    return 2.0 / float(jr.FieldModel.from_rod(ROD, n, dF=dF).max_frequency())


def field_vcrit(n, dF, integ, t1=0.5, n_iter=30, bracket=(1e-4, 0.2)):
    model = jr.FieldModel.from_rod(ROD, n, dF=dF)
    opts = jr.RunOptions(save_state=False)

    def buckles(v0):
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(model)
        return jr.simulate(model, integ, q0, w0, t1, n_save=3, options=opts, throw=False).buckled

    r = jax.jit(lambda: bisection(buckles, *bracket, rtol=0.0, max_iter=n_iter))()
    return float(jnp.sqrt(r.lo * r.hi))
