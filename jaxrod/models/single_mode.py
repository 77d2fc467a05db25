r"""The single-mode Coulomb oscillator (P4) and its exact piecewise solution."""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from .. import theory
from .._numerics import float_leaf
from .._results import RESULTS
from ..params import RodChannel
from .dof import AbstractDOFModel
from .recipe import AbstractRecipe

__all__ = ["SingleMode", "SingleModeRecipe", "exact_solution"]


class SingleMode(AbstractDOFModel):
    r"""One sine mode of the rod in the channel: `Ä + k A + f sgn(Ȧ) = 0` (P4).

    A is the modal amplitude of the deflection angle θ = A sin(ω_m s) [rad]; the lateral
    velocity of the rod's crest is R·Ȧ. Friction is set-valued at Ȧ = 0: the mode sticks
    while |kA| ≤ `f_s` and slips against `f_d` otherwise.

    **Arguments** (all dynamic array leaves):

    - `k`: modal stiffness [1/s²] (P3); negative past the frictionless load.
    - `f_s`: static friction amplitude 4μ_s N/(πρR) [rad/s²], ≥ `f_d`.
    - `f_d`: dynamic friction amplitude 4μ_d N/(πρR) [rad/s²], ≥ 0.
    - `mode`: the mode number m (static; `None`: not known, as for an oscillator built from
      k, f_s, f_d alone).
    - `rod`: the rod it is a mode of (`None` likewise): a scene reads its field and projects
      perturbations with it.

    Build it from a rod with [`jaxrod.SingleMode.from_rod`][].
    """

    k: Float[Array, ""] = eqx.field(converter=float_leaf)
    f_s: Float[Array, ""] = eqx.field(converter=float_leaf)
    f_d: Float[Array, ""] = eqx.field(converter=float_leaf)
    mode: int | None = eqx.field(static=True, default=None)
    rod: RodChannel | None = None

    def __check_init__(self):
        import numpy as np

        vals = {}
        for name in ("k", "f_s", "f_d"):
            x = getattr(self, name)
            if isinstance(x, jax.core.Tracer):
                return
            vals[name] = np.asarray(x)
        if not np.all(np.isfinite(vals["k"])):
            raise ValueError(f"SingleMode.k = {vals['k']} is invalid: it must be finite.")
        for name in ("f_s", "f_d"):
            if not (np.all(np.isfinite(vals[name])) and np.all(vals[name] >= 0)):
                raise ValueError(
                    f"SingleMode.{name} = {vals[name]} is invalid: it must be finite and >= 0."
                )
        if np.any(vals["f_d"] > vals["f_s"]):
            raise ValueError(
                f"SingleMode.f_d = {vals['f_d']} is invalid: it must lie in [0, f_s] with "
                f"f_s = {vals['f_s']}."
            )

    @classmethod
    def from_rod(
        cls, rod: RodChannel, m: ArrayLike | None = None, F: ArrayLike | None = None,
        dF: ArrayLike | None = None,
    ) -> SingleMode:
        """Mode `m` (default: the rod's critical mode) of `rod` under the axial load `F` [N],
        or `F = F⁰_m + dF` when `dF` is given (exactly one of `F`, `dF`)."""
        if (F is None) == (dF is None):
            raise ValueError("SingleMode.from_rod needs exactly one of F and dF.")
        m = theory.critical_mode(rod) if m is None else m
        if dF is not None:
            F = theory.frictionless_load(rod, m) + float_leaf(dF)
        return cls(
            k=theory.stiffness(rod, m, F),
            f_s=theory.friction_amplitude(rod, rod.mu_s),
            f_d=theory.friction_amplitude(rod, rod.mu_d),
            mode=int(m) if isinstance(m, (int, np.integer)) else None,
            rod=rod,
        )

    def acceleration(self, q, t):
        return -self.k * q

    def friction_bounds(self, t):
        return self.f_s, self.f_d

    def kinetic_energy(self, v):
        return 0.5 * jnp.sum(v * v)

    def energy_terms(self, q, v, t):
        """Per unit modal mass [rad²/s²]: kinetic ½Ȧ² and potential ½kA²."""
        return {"kinetic": self.kinetic_energy(v), "potential": 0.5 * jnp.sum(self.k * q * q)}

    def max_frequency(self, q=None):
        return jnp.sqrt(jnp.maximum(self.k, 0.0))

    def linear_flow(self, q, v, t, h):
        c0, c1, _ = _stumpff(self.k * h**2)
        return q * c0 + v * h * c1, v * c0 - self.k * q * h * c1

    def check(self):
        return (
            jnp.isfinite(self.k)
            & jnp.isfinite(self.f_s)
            & (self.f_d >= 0)
            & (self.f_d <= self.f_s)
        )


# -- Closed-form pieces ------------------------------------------------------------------
# Within a slip phase of direction σ the motion obeys Ä = −kA − σf, whose solution for any
# sign of k is written with the Stumpff functions of z = kτ²:
#   c0 = cos√z | cosh√−z,  c1 = sin√z/√z | sinh√−z/√−z,  c2 = (1 − c0)/z,
#   A(τ) = A₀ c0 + Ȧ₀ τ c1 − σ f τ² c2,   Ȧ(τ) = Ȧ₀ c0 − (kA₀ + σf) τ c1.
# They are entire functions of z, so k may cross zero; series near z = 0 keep values and
# gradients finite there.

_SMALL = 1e-3


def _stumpff(z):
    small = jnp.abs(z) < _SMALL
    zs = jnp.where(small, 1.0, z)  # double-where: no NaN gradients in the unused branch
    pos = zs > 0
    r = jnp.sqrt(jnp.abs(zs))
    rp = jnp.where(pos, r, 0.0)
    rn = jnp.where(pos, 0.0, r)
    c0 = jnp.where(pos, jnp.cos(rp), jnp.cosh(rn))
    c1 = jnp.where(pos, jnp.sin(rp), jnp.sinh(rn)) / r
    half = jnp.where(pos, jnp.sin(rp / 2), jnp.sinh(rn / 2))
    c2 = 2 * half**2 / (r * r)
    c0s = 1 - z / 2 + z**2 / 24 - z**3 / 720
    c1s = 1 - z / 6 + z**2 / 120 - z**3 / 5040
    c2s = 0.5 - z / 24 + z**2 / 720 - z**3 / 40320
    return (
        jnp.where(small, c0s, c0),
        jnp.where(small, c1s, c1),
        jnp.where(small, c2s, c2),
    )


def _phase_state(A0, v0, k, sigma_f, tau):
    """State after slipping for `tau` with friction acceleration −`sigma_f` = −σf."""
    c0, c1, c2 = _stumpff(k * tau**2)
    A = A0 * c0 + v0 * tau * c1 - sigma_f * tau**2 * c2
    v = v0 * c0 - (k * A0 + sigma_f) * tau * c1
    return A, v


def _atan_ratio(y):
    """T(y) = atan(√y)/√y for y > 0, atanh(√−y)/√−y for −1 < y < 0, 1 at y = 0."""
    small = jnp.abs(y) < _SMALL
    ys = jnp.where(small, 1.0, y)
    pos = ys > 0
    r = jnp.sqrt(jnp.abs(ys))
    rp = jnp.where(pos, r, 0.0)
    rn = jnp.where(pos, 0.0, jnp.minimum(r, 1.0 - 1e-16))
    full = jnp.where(pos, jnp.arctan(rp), jnp.arctanh(rn)) / r
    return jnp.where(small, 1 - y / 3 + y**2 / 5 - y**3 / 7, full)


def _phase_duration(v_hat, g_hat, k):
    """Time until the slip velocity (of magnitude `v_hat` ≥ 0 along σ) next vanishes, when the
    opposing acceleration along σ is `g_hat` = σkA₀ + f; `inf` if it never does."""
    inf = jnp.inf
    # Decelerating (g_hat > 0): tau = x T(k x^2) with x = v_hat/g_hat; stops iff k x^2 > -1.
    g_pos = g_hat > 0
    x = v_hat / jnp.where(g_pos, g_hat, 1.0)
    y = k * x**2
    stops = g_pos & (y > -1)
    tau_dec = jnp.where(stops, x * _atan_ratio(jnp.where(stops, y, 0.0)), inf)
    # Accelerating first (g_hat <= 0): only a restoring k > 0 brings it back.
    kp = k > 0
    om = jnp.sqrt(jnp.where(kp, k, 1.0))
    tau_acc = jnp.where(kp, (math.pi / 2 + jnp.arctan2(-g_hat, v_hat * om)) / om, inf)
    return jnp.where(g_pos, tau_dec, tau_acc)


def exact_solution(
    A0: ArrayLike,
    Adot0: ArrayLike,
    k: ArrayLike,
    f_s: ArrayLike,
    f_d: ArrayLike,
    t: ArrayLike,
    max_phases: int = 100_000,
) -> tuple[Float[Array, ""], Float[Array, ""], Bool[Array, ""], Int[Array, ""], Int[Array, ""]]:
    """The exact state at time `t` of `Ä + kA + f sgn(Ȧ) = 0` from (A₀, Ȧ₀) at t = 0.

    Phase by phase (docs/physics.md §4): each slip phase is solved in closed form until Ȧ = 0;
    there the mode sticks for good if |kA| ≤ `f_s` (the load is constant, so nothing can
    release it), and otherwise slips the other way against `f_d`. Jittable and vmappable
    (vmap over `t` for a trajectory); forward-mode differentiable.

    **Arguments:** `A0` [rad], `Adot0` [rad/s], `k` [1/s²], `f_s` ≥ `f_d` ≥ 0 [rad/s²],
    `t` ≥ 0 [s] (scalars); `max_phases` (static) caps the number of slip phases.

    **Returns:** `(A, Adot, stuck, n_phases, result)` at time `t`.
    """
    A0, Adot0, k, f_s, f_d, t = map(float_leaf, (A0, Adot0, k, f_s, f_d, t))

    def slip_direction(A, v):
        # From rest the mode slips towards the net elastic force -kA.
        return jnp.where(v != 0, jnp.sign(v), -jnp.sign(k * A))

    def stuck_now(A, v):
        return (v == 0) & (jnp.abs(k * A) <= f_s)

    def cond(carry):
        _, _, _, done, n = carry
        return (~done) & (n < max_phases)

    def body(carry):
        A, v, t_start, _, n = carry
        sigma = slip_direction(A, v)
        g_hat = sigma * k * A + f_d
        tau = _phase_duration(jnp.abs(v), g_hat, k)
        remaining = t - t_start
        ends_later = tau >= remaining
        step = jnp.where(ends_later, remaining, tau)
        A_new, v_new = _phase_state(A, v, k, sigma * f_d, step)
        v_new = jnp.where(ends_later, v_new, 0.0)  # the phase ends exactly at rest
        done = ends_later | stuck_now(A_new, v_new)
        return A_new, v_new, t_start + step, done, n + 1

    start_done = stuck_now(A0, Adot0) | (t <= 0)
    A, v, _, done, n = jax.lax.while_loop(
        cond, body, (A0, Adot0, jnp.zeros_like(t), start_done, jnp.array(0))
    )
    result = jnp.where(
        done,
        jnp.where(jnp.isfinite(A) & jnp.isfinite(v), RESULTS.successful, RESULTS.nonfinite),
        RESULTS.max_steps,
    ).astype(jnp.int32)
    return A, v, stuck_now(A, v), n, result


class SingleModeRecipe(AbstractRecipe):
    """The single mode's recipe: mode `mode` of the scene, no size, 1e-4 s steps, the
    perturbation projected onto the mode, boundary searches on the exact solution."""

    model_class: ClassVar[type] = SingleMode
    size_name: ClassVar[None] = None
    min_size: ClassVar[int] = 1
    search_method: ClassVar[str] = "exact"  # Newton on the exact solution (`exact_solution`)
    default_dt: ClassVar[float] = 1e-4  # a scene's step [s]

    def build(self, rod, F, size, mode):
        return SingleMode.from_rod(rod, mode, F=F)

    def default_size(self, rod, F, perturbation) -> None:
        return None

    def step(self, model, rod, F, scheme_step) -> float:
        return self.default_dt

    def initial_state(self, model, perturbation, integrator, grid):
        """The perturbation projected onto the mode (`AbstractPerturbation.modal_state`; a field
        perturbation is drawn on `grid()`'s field model first)."""
        return perturbation.modal_state(model.mode, model.rod.R, grid)

    def field_of(self, model, q):
        """θ = A sin(mπs/L) on 129 points (any leading axes of `q`)."""
        s = jnp.linspace(0.0, model.rod.L, 129)
        shape = jnp.sin(model.mode * jnp.pi * s / model.rod.L)
        return s, jnp.tensordot(jnp.asarray(q), shape, axes=0)  # the outer product, without rank promotion

    def dominant_mode(self, model, q):
        return jnp.full(jnp.shape(q), model.mode)
