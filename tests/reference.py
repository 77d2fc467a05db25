"""Independent references for the single-mode model: an event-driven diffrax integration.

Each slip phase is integrated by Tsit5 at tight tolerances with a diffrax `Event` that finds
where the velocity vanishes (Newton root find); the stick test and the next phase's direction
are then decided on the host. Nothing here uses jaxrod's closed-form solution.
"""

import diffrax
import equinox as eqx
import jax.numpy as jnp
import numpy as np
import optimistix as optx


def _rhs(t, y, args):
    k, sigma, f_d = args
    return jnp.stack([y[1], -k * y[0] - sigma * f_d])


def _slowing(t, y, args, **kwargs):
    return args[1] * y[1]  # sigma * velocity: downcrosses zero where the phase ends


@eqx.filter_jit
def _phase(t0, t1, y0, args, rtol, atol):
    event = diffrax.Event(_slowing, optx.Newton(rtol=1e-11, atol=1e-13), direction=False)
    return diffrax.diffeqsolve(
        diffrax.ODETerm(_rhs), diffrax.Tsit5(), t0=t0, t1=t1, dt0=1e-4, y0=y0, args=args,
        saveat=diffrax.SaveAt(t1=True, dense=True),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        event=event, max_steps=1_000_000,
    )


def event_driven_reference(A0, v0, k, f_s, f_d, ts, rtol=1e-12, atol=1e-14):
    ts = np.asarray(ts, dtype=float)
    A_out = np.full(ts.shape, np.nan)
    v_out = np.full(ts.shape, np.nan)
    t, A, v = 0.0, float(A0), float(v0)
    T = float(ts[-1])
    n_phases = 0
    while t < T:
        if v == 0.0:
            if abs(k * A) <= f_s:  # sticks for good: the load is constant
                sel = ts >= t
                A_out[sel], v_out[sel] = A, 0.0
                break
            sigma = -np.sign(k * A)
        else:
            sigma = np.sign(v)

        args = (jnp.asarray(float(k)), jnp.asarray(float(sigma)), jnp.asarray(float(f_d)))
        sol = _phase(jnp.asarray(t), jnp.asarray(T), jnp.array([A, v]), args, rtol, atol)
        t_end = float(sol.ts[-1])
        sel = (ts >= t) & (ts <= t_end)
        for i in np.flatnonzero(sel):
            y = np.asarray(sol.evaluate(ts[i]))
            A_out[i], v_out[i] = y[0], y[1]
        y_end = np.asarray(sol.ys[-1])
        n_phases += 1
        if t_end >= T and not bool(sol.event_mask):
            break
        t, A, v = t_end, float(y_end[0]), 0.0
    return A_out, v_out, n_phases
