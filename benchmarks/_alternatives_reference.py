"""What a user without jaxrod would write, for `alternatives.py` (not a benchmark itself):

- `NumpyField`: projected Verlet on the FD field model in plain NumPy, vectorised over a
  (batch, n) array, operation for operation the scheme of `jaxrod.ProjectedVerlet` +
  `jaxrod.FieldModel(operator="fd")` + `Coulomb` (`alternatives.verify_numpy` checks it
  against jaxrod before it is timed);
- `scipy_member`: one trajectory by SciPy `solve_ivp` with the friction smoothed to
  f tanh(θ_t/ε), ε = EPS_V/R.

The scene: reference rod, μ = MU, ΔF = DF, sine mode-6 lateral velocity.
"""

from __future__ import annotations

import math
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

DF = 5.0
MU = 0.3
EPS_V = 1e-4  # m/s: the tanh regularisation as a lateral speed (1/200 of a 20 mm/s perturbation)


class NumpyField:
    """Projected Verlet on the FD field model, vectorised over a (batch, n) array in NumPy:
    the scheme of `jaxrod.ProjectedVerlet` + `jaxrod.FieldModel(operator="fd")` + `Coulomb`,
    operation for operation."""

    def __init__(self, n: int, threshold: float = math.inf):
        rod = jr.RodChannel.reference(mu=MU)
        model = jr.FieldModel.from_rod(rod, n, dF=DF)
        self.n = n
        self.EI = float(rod.EI)
        self.rho = float(rod.rho)
        self.wR = float(rod.w / rod.R)
        self.F = float(model.load(0.0))
        self.inv_h2 = 1.0 / float(model.spacing) ** 2
        self.spacing2 = float(model.spacing) ** 2
        fs, fd = model.friction_bounds(0.0)
        self.fs, self.fd = float(fs), float(fd)
        self.ke = float(rod.rho * rod.R**2 * model.spacing)  # kinetic energy = ke/2 |v|^2
        self.thr = threshold  # buckling stop: max|θ| past it freezes the member, as in jaxrod

    def d2(self, x):
        out = -2.0 * x
        out[:, 1:] += x[:, :-1]
        out[:, :-1] += x[:, 1:]
        return out / self.spacing2

    def acceleration(self, q):
        d2 = self.d2(q)
        return -(self.EI * self.d2(d2) + self.F * d2 + self.wR * q) / self.rho

    def prox(self, v_trial, v_prev, h):
        threshold = h * np.where(v_prev == 0, self.fs, self.fd)
        slips = np.abs(v_trial) > threshold
        return np.where(slips, v_trial - h * self.fd * np.sign(v_trial), 0.0)

    def work(self, v_prev, v_trial, v_after):
        return self.ke * np.sum(0.5 * (v_prev + v_after) * (v_trial - v_after), axis=-1)

    def run(self, q, v, h, steps, work=True):
        """`steps` steps of size `h` from (q, v) [rad, rad/s], shape (batch, n). With
        `work=False` the dissipated energy is not accumulated (timed runs: the jaxrod run timed
        returns only the final angles, so XLA drops that bookkeeping too)."""
        q, v = q.copy(), v.copy()
        a = self.acceleration(q)
        D = np.zeros(q.shape[0])
        done = np.zeros((q.shape[0], 1), bool)
        freeze = math.isfinite(self.thr)  # a NumPy user without a stop would not write it
        half = 0.5 * h
        for _ in range(steps):
            v_trial = v + half * a
            v_half = self.prox(v_trial, v, half)
            dD = self.work(v, v_trial, v_half) if work else 0.0
            q1 = q + h * v_half
            a1 = self.acceleration(q1)
            v_trial = v_half + half * a1
            v1 = self.prox(v_trial, v_half, half)
            if work:
                dD = dD + self.work(v_half, v_trial, v1)
            if freeze:
                q, v, a = (np.where(done, x, x1) for x, x1 in ((q, q1), (v, v1), (a, a1)))
                D = np.where(done[:, 0], D, D + dD)
                done = done | (np.max(np.abs(q1), axis=-1, keepdims=True) > self.thr)
            else:
                q, v, a, D = q1, v1, a1, D + dD
                np.max(np.abs(q), axis=-1) > self.thr  # the amplitude test jaxrod makes every step
        return q, v, D


def initial_states(n: int, v0: np.ndarray):
    rod = jr.RodChannel.reference(mu=MU)
    m = jr.FieldModel.from_rod(rod, n, dF=DF)
    q0, w0 = jax.vmap(lambda a: jr.SineVelocity(a, 6).initial_state(m))(jnp.asarray(v0))
    return np.asarray(q0), np.asarray(w0)


def scipy_member(n: int, v0: float, t1: float, method: str):
    from scipy.integrate import solve_ivp

    f = NumpyField(n)
    eps = EPS_V / float(jr.RodChannel.reference(mu=MU).R)
    q0, w0 = initial_states(n, np.array([v0]))

    def rhs(t, y):
        q, v = y[:n], y[n:]
        d2 = np.empty(n)
        d2[:] = -2.0 * q
        d2[1:] += q[:-1]
        d2[:-1] += q[1:]
        d2 /= f.spacing2
        d4 = -2.0 * d2
        d4[1:] += d2[:-1]
        d4[:-1] += d2[1:]
        d4 /= f.spacing2
        a = -(f.EI * d4 + f.F * d2 + f.wR * q) / f.rho - f.fd * np.tanh(v / eps)
        return np.concatenate([v, a])

    t0 = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t1), np.concatenate([q0[0], w0[0]]), method=method, rtol=1e-6, atol=1e-9)
    wall = time.perf_counter() - t0
    return wall, sol.y[:n, -1], int(sol.nfev), bool(sol.success)
