"""Scenes: the loaded rod, one model of it and one perturbation, from a few plain settings.

This is the layer the CLI and the sweeps use. ΔF is always measured from the frictionless load
of the rod's critical mode F⁰_m* (P5; 1.308 N for the reference rod), whatever the model.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from . import theory
from .integrators import AbstractFixedStep, ProjectedVerlet, default_for
from .integrators.base import RunOptions
from .models import FieldModel, GalerkinModel, SingleMode
from .params import RodChannel
from .perturbations import (
    AbstractPerturbation,
    RandomForce,
    RandomShape,
    RandomVelocity,
    SineVelocity,
    project_to_mode,
)
from .simulate import simulate

__all__ = ["Scene", "MODELS", "PERTURBATIONS", "DEFAULT_NODES", "DEFAULT_MODES", "DEFAULT_T1"]

MODELS = ("mode", "galerkin", "field", "rod3d")
PERTURBATIONS = ("sine", "random-velocity", "random-position", "random-shape")
DEFAULT_NODES = 128  # see benchmarks/README.md (field convergence) and `default_nodes`
DEFAULT_MODES = 32
DEFAULT_SEGMENTS = 60  # the 3D rod, as E1 and E6 (docs/rod3d.md)
DEFAULT_T1 = 2.0  # s, as the reference paper
DT_FRACTION = 0.4  # of the explicit step limit
SINGLE_MODE_DT = 1e-4  # s
GROWTH_FRACTION = 0.25  # of 1/λ_max


def _f(x):
    if isinstance(x, (int, float)):
        return jnp.asarray(x, dtype=jnp.result_type(float))
    return jnp.asarray(x)


def default_nodes(rod: RodChannel, F) -> int:
    """The field model's default node count for the load `F` [N] (concrete), from the
    convergence study in `benchmarks/field_convergence.py`: the critical sine velocity is within
    1 % of its converged value with 128 nodes while at most 32 modes are unstable
    (m_max = (L/π)√(F/EI) ≤ 32, ΔF ≲ 20 N for the reference rod), and needs 384 beyond (measured
    at ΔF = 60 N: 2.3 % off with 128 nodes, 1.1 % with 256, 0.35 % with 384)."""
    import math

    with jax.ensure_compile_time_eval():
        m_max = float(rod.L / math.pi * jnp.sqrt(jnp.maximum(F, 0.0) / rod.EI))
    return DEFAULT_NODES if m_max <= 32 else 384


def make_perturbation(kind: str, amplitude, mode: int = 6, key=None, duration=1e-3):
    """A perturbation of `kind`:

    - `"sine"`: lateral velocity `amplitude`·sin(`mode`·πs/L) [m/s];
    - `"random-velocity"`: uniform in ±`amplitude` [m/s] at every point;
    - `"random-position"`: random forces ±`amplitude` [N/m] for `duration` [s], then released
      from rest (the reference paper's position perturbation);
    - `"random-shape"`: random lateral displacement ±`amplitude` [m], from rest.
    """
    if kind not in PERTURBATIONS:
        raise ValueError(f"perturbation = {kind!r} is invalid: expected one of {PERTURBATIONS}.")
    if kind == "sine":
        return SineVelocity(amplitude, float(mode))
    key = jax.random.key(0) if key is None else key
    if kind == "random-velocity":
        return RandomVelocity(amplitude, key)
    if kind == "random-position":
        return RandomForce(amplitude, key, duration)
    return RandomShape(amplitude, key)


class Scene(eqx.Module):
    """A rod loaded to F = F⁰_m* + `dF`, one model of it, and one perturbation.

    **Arguments:**

    - `rod`: the [`jaxrod.RodChannel`][].
    - `dF`: load above the critical mode's frictionless load [N] (dynamic).
    - `perturbation`: any perturbation (dynamic leaves: amplitude, key, ...).
    - `kind`: `"mode"`, `"galerkin"`, `"field"` or `"rod3d"` (the full 3D rod,
      [`jaxrod.rod3d.Rod3D`][], under the dead load F with friction at the contact point;
      perturbations as lateral velocities or offsets of its nodes) (static).
    - `n`: nodes (field; default `default_nodes` of the load: 128, or 384 past 32 unstable
      modes), modes (Galerkin, default 32) or segments (3D rod, default 60) (static).
    - `mode`: the single-mode model's mode (static, default 6).
    - `dt`: fixed step [s] (static; default 0.4 of the step limit at ΔF = 0 for field and
      Galerkin, 1e-4 s for one mode, 0.5 of the explicit limit for the 3D rod).
    - `threshold`: buckling amplitude max|θ| [rad] (static, default 0.5).
    - `grid_dt`: step of that grid's forcing phase (static; default 0.4 of its limit).
    - `n_grid`: nodes of the field grid on which random perturbations are drawn before being
      projected onto the single mode (static).
    """

    rod: RodChannel
    dF: Float[Array, ""] = eqx.field(converter=_f)
    perturbation: AbstractPerturbation = eqx.field(default_factory=lambda: SineVelocity(0.01, 6.0))
    kind: str = eqx.field(static=True, default="field")
    n: int | None = eqx.field(static=True, default=None)
    mode: int = eqx.field(static=True, default=6)
    dt: float | None = eqx.field(static=True, default=None)
    n_grid: int = eqx.field(static=True, default=128)
    threshold: float = eqx.field(static=True, default=0.5)
    grid_dt: float | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        if self.kind not in MODELS:
            raise ValueError(f"model = {self.kind!r} is invalid: expected one of {MODELS}.")
        if not (isinstance(self.mode, int) and self.mode >= 1):
            raise ValueError(f"mode = {self.mode!r} is invalid: expected an int >= 1.")
        if self.n is not None and not (isinstance(self.n, int) and self.n >= (1 if self.kind == "galerkin" else 4)):
            raise ValueError(f"n = {self.n!r} is invalid for the {self.kind} model.")
        if self.dt is not None and not (isinstance(self.dt, (int, float)) and self.dt > 0):
            raise ValueError(f"dt = {self.dt!r} is invalid: expected a float > 0 [s].")

    @property
    def F(self) -> Float[Array, ""]:
        """The axial load [N]."""
        return theory.reference_load(self.rod) + self.dF

    def model(self):
        if self.kind == "mode":
            return SingleMode.from_rod(self.rod, self.mode, F=self.F)
        if self.kind == "galerkin":
            return GalerkinModel.from_rod(self.rod, self.n or DEFAULT_MODES, F=self.F)
        if self.kind == "rod3d":
            from .rod3d import Rod3D

            return Rod3D(self.rod, self.size(), control="load", end_load=self.F)
        return FieldModel.from_rod(self.rod, self.nodes(), F=self.F)

    def size(self) -> int | None:
        """The model's static size: field nodes, Galerkin modes, 3D segments (`None`: one mode)."""
        if self.kind == "field":
            return self.nodes()
        if self.kind == "galerkin":
            return self.n or DEFAULT_MODES
        if self.kind == "rod3d":
            return self.n or DEFAULT_SEGMENTS
        return None

    def nodes(self) -> int:
        """Field nodes: `n`, or `default_nodes` of the (concrete) load — at least the grid − 1
        interior nodes of a random velocity or shape, whose high modes decide the result (their
        vibration releases static friction: measured at μ = 0.3, ΔF* of a ±15 mm/s random
        velocity is 17.95, 14.87, 12.95, 13.04, 13.10 N with 128, 256, 499, 640, 768 nodes)."""
        if self.n is not None:
            return self.n
        grid = getattr(self.perturbation, "grid", None)
        least = grid - 1 if grid is not None and isinstance(self.perturbation, (RandomVelocity, RandomShape)) else 0
        try:
            return max(default_nodes(self.rod, self.F), least)
        except jax.errors.ConcretizationTypeError:
            raise ValueError(
                "Scene.n must be given explicitly when the load is traced (e.g. vmapped over "
                "dF): the node count is a static setting."
            ) from None

    def _grid_model(self):
        return FieldModel.from_rod(self.rod, self.n_grid, F=self.F)

    def step(self) -> float:
        """The fixed step [s], static, from the rod's concrete values: 0.4 of the stability limit
        2/ω_max at ΔF = 0 (compression only lowers the highest frequency), and — when the load
        is concrete — at most 0.25/λ_max, λ_max = F/(2√(EIρ)) the fastest growth rate of a
        loaded rod, so that fast-growing modes stay accurately resolved (the convergence study
        in benchmarks/README.md, field_convergence: v₀* within 0.1 % below 0.4 of the limit at n = 64)."""
        if self.dt is not None:
            return float(self.dt)
        if self.kind == "mode":
            return SINGLE_MODE_DT
        if self.kind == "rod3d":
            from .integrators import default_step

            try:
                return default_step(self.model(), scheme=self.scheme())
            except jax.errors.ConcretizationTypeError:
                raise ValueError("Scene.dt must be given explicitly for the 3D rod when the rod or the load "
                                 "is traced: the step is a static setting.") from None
        unloaded = eqx.tree_at(lambda s: s.dF, self, jnp.zeros(()))
        if self.kind == "field":
            model = FieldModel.from_rod(self.rod, self.nodes(), F=unloaded.F)
        else:
            model = unloaded.model()
        dt = DT_FRACTION * 2.0 / self._static_omega(model)
        try:
            with jax.ensure_compile_time_eval():
                lam = float(self.F / (2 * jnp.sqrt(self.rod.EI * self.rod.rho)))
        except jax.errors.ConcretizationTypeError:
            return dt
        return min(dt, GROWTH_FRACTION / lam) if lam > 0 else dt

    def scheme(self) -> str | None:
        """The scheme of the scene's runs (a key of `jaxrod.integrators.SCHEMES`; `None`: the
        model's own): the 3D rod runs its implicit default only under a perturbation measured
        adequate for it (`AbstractPerturbation.implicit_3d`: the sine velocity), else the
        explicit projected leapfrog."""
        return scheme_for(self.kind, self.perturbation)

    def integrator(self) -> AbstractFixedStep:
        """The run's integrator: the scene's scheme (`scheme`; `jaxrod.integrators.default_for`:
        the implicit leapfrog for the 3D rod under a sine velocity, else the projected leapfrog;
        projected Verlet for the reduced models) at `step()`."""
        return default_for(self.model(), self.step(), self.scheme())

    def initial_state(self):
        """(q₀, v₀) in the model's coordinates."""
        model = self.model()
        if self.kind != "mode":
            return self.perturbation.initial_state(model, self.integrator())
        if isinstance(self.perturbation, SineVelocity):
            # a sine velocity field projects exactly onto its own mode
            v = jnp.where(self.perturbation.mode == self.mode, self.perturbation.v0 / self.rod.R, 0.0)
            return jnp.zeros_like(v), v
        grid = self._grid_model()
        step = self.grid_dt or DT_FRACTION * 2.0 / self._static_omega(grid)
        q, v = self.perturbation.initial_state(grid, ProjectedVerlet(step))
        return project_to_mode(q, self.mode), project_to_mode(v, self.mode)

    def _static_omega(self, model) -> float:
        try:
            with jax.ensure_compile_time_eval():
                return float(jnp.max(model.max_frequency()))
        except jax.errors.ConcretizationTypeError:
            raise ValueError(
                "Scene.dt must be given explicitly when the rod's stiffness parameters are "
                "traced (e.g. vmapped over EI, rho or R): the step is a static setting."
            ) from None

    def run(self, t1: float = DEFAULT_T1, n_save: int = 201, save_state: bool = True, throw: bool = False):
        """Simulate the scene to `t1` [s]; returns a [`jaxrod.Solution`][]. The run stops when
        max|θ| passes `threshold` (buckled) or the rod is stuck."""
        q0, v0 = self.initial_state()
        return simulate(
            self.model(), self.integrator(), q0, v0, t1, n_save=n_save,
            options=RunOptions(buckle_threshold=self.threshold, save_state=save_state),
            throw=throw,
        )

    def field_of(self, q):
        """θ on a grid of nodes for plots: (s [m], θ [rad]) from the model's coordinates."""
        model = self.model()
        if self.kind == "rod3d":
            return jnp.linspace(0.0, self.rod.L, model.n + 1), model.theta(q.x)
        if self.kind == "field":
            return model.sample_points(), q
        if self.kind == "galerkin":
            return model.sample_points(), jax.vmap(model.field)(q) if q.ndim == 2 else model.field(q)
        s = jnp.linspace(0.0, self.rod.L, 129)
        shape = jnp.sin(self.mode * jnp.pi * s / self.rod.L)
        return s, q[..., None] * shape if jnp.ndim(q) else q * shape

    def dominant_mode(self, q):
        """The dominant sine mode of the state `q` (the model's own mode for one mode)."""
        return dominant_mode_of(self.kind, q, self.mode)


def scheme_for(kind: str, perturbation) -> str | None:
    """The scheme of a run of a model of `kind` under `perturbation` (see `Scene.scheme`)."""
    if kind == "rod3d" and not type(perturbation).implicit_3d:
        return "leapfrog"
    return None


def dominant_mode_of(kind: str, q, mode: int = 6):
    """The dominant sine mode of a state `q` of a model of `kind` (any leading axes): of θ at the
    nodes (field, 3D rod), the largest modal amplitude (Galerkin), or `mode` (single mode)."""
    from .modal import dominant_mode
    from .rod3d.state import wall_angle

    if kind == "field":
        return dominant_mode(q)
    if kind == "rod3d":
        return dominant_mode(wall_angle(q.x)[..., 1:-1])
    if kind == "galerkin":
        return jnp.argmax(jnp.abs(q), axis=-1) + 1
    return jnp.asarray(mode)
