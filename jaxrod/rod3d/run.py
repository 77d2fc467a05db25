"""Time stepping of the 3D rod: projected velocity Verlet (kick → friction prox → drift →
kick → friction prox), the same scheme as the reduced models, on positions and rotations."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .._results import RESULTS
from ..integrators.base import save_grid
from ..modal import dominant_mode, modal_spectrum
from .model import Rod3D, Rod3DState
from .so3 import exp_so3

__all__ = ["Rod3DSolution", "simulate_rod3d", "step_limit"]


class Rod3DSolution(eqx.Module):
    """What a 3D run returns (SI units; `n_save` saved times, n segments, n + 1 nodes).

    - `ts`: save times [s]; `theta`: angle of every node from the channel bottom [rad]
      (n_save, n+1), directly comparable with the field model's θ(s, t);
    - `x`: node positions (n_save, n+1, 3) [m] (only with `save_state`);
    - `energies`: dict of (n_save,) arrays [J]: kinetic, rotational, stretch, shear, bend,
      twist, gravity (zero on the bottom, with any body force), contact;
    - `dissipated`: energy removed by friction, contact damping and viscous damping [J];
    - `work_in`: work done on the rod by the pushed end (displacement control) [J];
    - `reaction`: compressive support forces along x at node 0 and node n [N] (n_save, 2);
    - `end_displacement`: how far the pushed end has moved [m];
    - `normal_force`: wall force per length at every node [N/m] (n_save, n+1);
    - `axial_force`: compressive force of every segment [N] (n_save, n);
    - `height`: largest height of the centre line above the channel bottom [m] (n_save,);
    - `gap`: largest distance of a node inside the clearance circle, R − r [m]: > 0 where the
      rod has lifted off the wall (buckled upward, away from it);
    - `amplitude`: max |θ| over the interior nodes [rad];
    - `buckled`, `t_buckle` [s] (`inf` if not), `result` (a `jaxrod.RESULTS` code),
      `n_steps`, `dt` [s], `final`: the final [`Rod3DState`][].
    """

    ts: Float[Array, " n_save"]
    theta: Float[Array, "n_save n1"]
    x: Float[Array, "n_save n1 3"] | None
    energies: dict
    dissipated: Float[Array, " n_save"]
    work_in: Float[Array, " n_save"]
    reaction: Float[Array, "n_save 2"]
    end_displacement: Float[Array, " n_save"]
    normal_force: Float[Array, "n_save n1"]
    axial_force: Float[Array, "n_save n"]
    height: Float[Array, " n_save"]
    gap: Float[Array, " n_save"]
    amplitude: Float[Array, " n_save"]
    buckled: Bool[Array, ""]
    t_buckle: Float[Array, ""]
    result: Int[Array, ""]
    n_steps: Int[Array, ""]
    dt: Float[Array, ""]
    final: Rod3DState

    @property
    def total_energy(self) -> Float[Array, " n_save"]:
        return sum(self.energies.values())

    @property
    def energy_balance(self) -> Float[Array, " n_save"]:
        """E(t) + dissipated(t) − work_in(t) − E(0) [J]: zero for an exact scheme."""
        e = self.total_energy
        return e + self.dissipated - self.work_in - e[..., :1]

    def modal_spectrum(self, n_modes: int | None = None):
        """Normalised modal power of θ at the interior nodes, per save (as the field model)."""
        return modal_spectrum(self.theta[..., 1:-1], n_modes)

    def dominant_mode(self, n_modes: int | None = None):
        return dominant_mode(self.theta[..., 1:-1], n_modes)


def _interior_amplitude(model, x):
    if not model.channel:  # θ is an angle on the channel wall: no buckling test without one
        return jnp.zeros((), x.dtype)
    return jnp.max(jnp.abs(model.theta(x)[1:-1]))


def _kick(model, s, f, tau, h):
    J = model.inertia
    v = s.v + h * f / model.mass[:, None]
    J = J[None, :]
    w = s.w + h * (tau - jnp.cross(s.w, J * s.w)) / J
    v, w = model.constrain(v, w)
    return v, w


def _work(model, v0, w0, vt, wt, v1, w1):
    """Energy removed by an impulse that took (vt, wt) to (v1, w1) over a half step that began
    at (v0, w0): impulse · mean velocity (the midpoint rule of the reduced models)."""
    return jnp.sum(model.mass[:, None] * (vt - v1) * 0.5 * (v0 + v1)) + jnp.sum(
        model.inertia[None, :] * (wt - w1) * 0.5 * (w0 + w1)
    )


def _step(model: Rod3D, s: Rod3DState, cache, h):
    f, tau, N, fd = cache
    half = 0.5 * h
    v_t, w_t = _kick(model, s, f, tau, half)
    v1, w1, stuck = model.friction_step(s.x, v_t, s.Q, w_t, N, s.stuck, half)
    v1, w1 = model.constrain(v1, w1)
    lost = _work(model, s.v, s.w, v_t, w_t, v1, w1) - half * jnp.sum(fd * 0.5 * (s.v + v1))
    x = s.x + h * v1
    Q = jnp.einsum("jab,jbc->jac", exp_so3(-h * w1), s.Q)
    t = s.t + h
    f_c, tau, N, fd = model.forces(x, Q, v1)
    s_half = Rod3DState(x, v1, Q, w1, stuck, t)
    v_t, w_t = _kick(model, s_half, f_c, tau, half)
    v2, w2, stuck = model.friction_step(x, v_t, Q, w_t, N, stuck, half)
    v2, w2 = model.constrain(v2, w2)
    lost = lost + _work(model, v1, w1, v_t, w_t, v2, w2) - half * jnp.sum(fd * 0.5 * (v1 + v2))
    # work of the pushed end: support force (minus the other forces on the node) × velocity
    work = -0.5 * (f[-1, 0] + f_c[-1, 0]) * v1[-1, 0] * h if model.control == "displacement" else 0.0 * h
    return Rod3DState(x, v2, Q, w2, stuck, t), (f_c, tau, N, fd), lost, work


def _observe(model, s, f, D, Wk, x0_end):
    return dict(
        theta=model.theta(s.x),
        x=s.x,
        energies=model.energy_terms(s),
        dissipated=D,
        work_in=Wk,
        reaction=jnp.stack([-f[0, 0], f[-1, 0]]),
        end_displacement=x0_end - s.x[-1, 0],
        normal_force=model.contact_normal(s.x, s.v)[0] / model.voronoi,
        axial_force=model.axial_force(s.x, s.Q),
        height=jnp.max(s.x[:, 2]) + model.rod.R + model.static_sag(),
        gap=jnp.max(-model.penetration(s.x)[0]) if model.channel else jnp.zeros((), s.x.dtype),
        amplitude=_interior_amplitude(model, s.x),
    )


def _all_stuck(model, s):
    """Every free node held by static friction at the last step and at rest (a stuck rod under
    a constant load stays stuck: nothing can release it)."""
    held, _ = model.held()
    free = ~jnp.any(held, -1)
    return jnp.all(jnp.where(free, s.stuck, True)) & jnp.all(jnp.where(free[:, None], s.v == 0, True))


@eqx.filter_jit
def _run(model, s0, h, m: int, n_save: int, threshold: float, stop_on_buckle: bool, stop_when_stuck: bool = False):
    """`n_save − 1` intervals of `m` steps; a member that has buckled (with `stop_on_buckle`),
    got stuck (with `stop_when_stuck`, constant loads only) or become non-finite is frozen,
    and the loop over intervals ends once every member of a vmapped batch is frozen (the
    remaining saves repeat the frozen state)."""
    cache0 = model.forces(s0.x, s0.Q, s0.v)
    zero = jnp.zeros((), s0.x.dtype)
    x0_end = s0.x[-1, 0]
    stuck_ok = stop_when_stuck and model.control != "displacement"

    def frozen(c):
        s, b = c[0], c[4]
        bad = ~jnp.all(jnp.isfinite(s.x))
        return (b & stop_on_buckle) | bad | (_all_stuck(model, s) & stuck_ok)

    def one_step(c):
        s, cache, D, Wk, b, tb, n = c
        s, cache, dD, dW = _step(model, s, cache, h)
        nb = _interior_amplitude(model, s.x) > threshold
        tb = jnp.where(nb & ~b, s.t, tb)
        return s, cache, D + dD, Wk + dW, b | nb, tb, n + 1

    def body(_, c):
        return jax.lax.cond(frozen(c), lambda c: c, one_step, c)

    first = _observe(model, s0, cache0[0], zero, zero, x0_end)
    obs0 = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n_save,) + a.shape), first)
    c0 = (s0, cache0, zero, zero, jnp.zeros((), bool), jnp.asarray(jnp.inf, s0.x.dtype), jnp.zeros((), jnp.int32))

    def cond(carry):
        i, c, _ = carry
        return (i < n_save) & ~frozen(c)

    def interval(carry):
        i, c, obs = carry
        c = jax.lax.fori_loop(0, m, body, c)
        s, cache, D, Wk = c[:4]
        o = _observe(model, s, cache[0], D, Wk, x0_end)
        # write this save and repeat it into every later one (overwritten if the run goes on)
        later = jnp.arange(n_save) >= i
        obs = jax.tree_util.tree_map(
            lambda a, b: jnp.where(later.reshape((-1,) + (1,) * b.ndim), b[None], a), obs, o
        )
        return i + 1, c, obs

    _, c, obs = jax.lax.while_loop(cond, interval, (jnp.asarray(1), c0, obs0))
    return c, obs


@eqx.filter_jit
def _limit(model, s0):
    return 2.0 / model.max_frequency(s0)


def step_limit(model: Rod3D, state: Rod3DState) -> float:
    """The explicit step limit 2/ω_max [s] at `state` (stiffest of the axial, shear, bending,
    twist and contact vibrations, by power iteration)."""
    return float(_limit(model, state))


def simulate_rod3d(
    model: Rod3D,
    state0: Rod3DState,
    t1: float,
    n_save: int = 101,
    *,
    dt: float | None = None,
    dt_fraction: float = 0.5,
    buckle_threshold: float = 0.5,
    stop_on_buckle: bool = True,
    stop_when_stuck: bool = False,
    save_state: bool = False,
) -> Rod3DSolution:
    """Integrate the 3D rod from `state0` to `t1` [s] with projected velocity Verlet.

    **Arguments:**

    - `model`, `state0`: the [`Rod3D`][] and its initial state (e.g. `model.initial_state(F)`).
    - `t1`: horizon [s] > 0; `n_save`: number of saved times ≥ 2 (t = 0 and t1 included).
    - `dt`: fixed step [s]; default `dt_fraction` × the stability limit 2/ω_max measured at
      `state0`. A `dt` at or above the limit is refused with a `ValueError`.
    - `buckle_threshold`: max |θ| [rad] past which the rod counts as buckled; with
      `stop_on_buckle` the run is frozen there (remaining saves repeat the state).
    - `stop_when_stuck`: freeze the run once every free node is at rest and held by static
      friction (force or dead-load control only: the state can then never change).
    - `save_state`: keep node positions at every save.

    **Returns:** a [`Rod3DSolution`][].
    """
    if not (isinstance(t1, (int, float)) and math.isfinite(t1) and t1 > 0):
        raise ValueError(f"argument t1 = {t1!r} is invalid: expected a finite horizon > 0 s.")
    if not (isinstance(n_save, int) and n_save >= 2):
        raise ValueError(f"argument n_save = {n_save!r} is invalid: expected an int >= 2.")
    if not (0 < dt_fraction < 1):
        raise ValueError(f"argument dt_fraction = {dt_fraction!r} is invalid: expected a value in (0, 1).")
    limit = step_limit(model, state0)
    if dt is None:
        dt = dt_fraction * limit
    elif not (dt > 0 and dt < limit):
        raise ValueError(
            f"argument dt = {dt!r} s is invalid: the explicit step limit of this rod is "
            f"{limit:.4g} s (2/ω_max); use 0 < dt < {limit:.4g} s."
        )
    m, h = save_grid(t1, n_save, dt)
    c, obs = _run(model, state0, jnp.asarray(h, state0.x.dtype), m, n_save, float(buckle_threshold), bool(stop_on_buckle), bool(stop_when_stuck))
    s, _, _, _, buckled, tb, n = c
    finite = jnp.all(jnp.isfinite(s.x))
    return Rod3DSolution(
        ts=jnp.linspace(0.0, t1, n_save),
        theta=obs["theta"],
        x=obs["x"] if save_state else None,
        energies=obs["energies"],
        dissipated=obs["dissipated"],
        work_in=obs["work_in"],
        reaction=obs["reaction"],
        end_displacement=obs["end_displacement"],
        normal_force=obs["normal_force"],
        axial_force=obs["axial_force"],
        height=obs["height"],
        gap=obs["gap"],
        amplitude=obs["amplitude"],
        buckled=buckled,
        t_buckle=tb,
        result=jnp.where(finite, RESULTS.successful, RESULTS.nonfinite).astype(jnp.int32),
        n_steps=n,
        dt=jnp.asarray(h),
        final=s,
    )
