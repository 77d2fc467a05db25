r"""An independent reference for the field model P1 (docs: /work/shared/PHYSICS.md, sections 1–4),
in plain NumPy. It shares no code with `jaxrod` and does not import it.

    ρ θ_tt + EI θ_ssss + F θ_ss + (ρg/R) θ + (μN/R) sgn(θ_t) ∋ 0,   θ = θ_ss = 0 at s = 0, L,

with N = w = ρg and μ_s = μ_d = μ (the reference paper's runs; only that case is implemented).

**Space: spectral collocation.** θ_j = θ(s_j, t) at the n interior nodes s_j = jL/(n+1)
[rad]. The elastic operator is applied through the sine transform with the *exact* wavenumbers
ω_m = mπ/L, m = 1..n: (Aθ) = Σ_m k_m a_m sin(ω_m s_j) with a_m the discrete sine coefficients
of θ and k_m = (ω_m²/ρ)(EIω_m² + ρg/(Rω_m²) − F) [1/s²] (P3), so every resolved mode has its
exact stiffness (jaxrod's default is the finite-difference D₂², whose mode-m wavenumber² is
(4/Δ²)sin²(mπΔ/2L)). Friction acts at every node (nodal quadrature of the friction force):
a bound f = μN/(ρR) [rad/s²] on each node's angular acceleration.

**Time: Moreau–Jean θ-scheme, θ = 1/2 (trapezoidal / Crank–Nicolson on the linear part).**
With v = θ_t [rad/s], step h [s]:

    q⁺ = q⁻ + h[(1−θ)v⁻ + θv⁺],   v⁺ − v⁻ = −hA[(1−θ)q⁻ + θq⁺] + h·g + h·r,
    r_j ∈ −f·Sgn(v⁺_j)  (Sgn(0) = [−1, 1]),

g an optional constant forcing acceleration [rad/s²]. Eliminating q⁺: v⁺ = v_free + W r with
W = h(I + h²θ²A)⁻¹ (symmetric positive definite while h·θ·√|k_m| < 1). The friction impulse is
found *exactly* each step as the solution of this one-step problem (a linear complementarity
problem in r): a primal–dual active-set iteration (each node sticks, slips +, slips −; the
stick nodes' r solves W_SS r_S = −(v_free + W r)_S), started from the per-node trial guess
r = 0 and repeated until the sets repeat, which is the exact KKT solution; projected
Gauss–Seidel is the fallback should the sets cycle (counted in `FieldP1.fallbacks`).

**Order.** Second order (trapezoidal, A-stable, energy-conserving) on the linear part; first
order in h at friction events (a stop or reversal inside a step), as any event-capturing scheme.

**Stick.** A node is held exactly (v⁺_j = 0) while the friction it needs is within f. The
whole rod is *stuck* when every node is at rest and |Aq|_j ≤ f at every node (the set-valued
law of P1 with μ_s: then, under a constant load, it never moves again): the run stops there,
labelled stable. It is labelled *buckled* at the first step with max_j|θ_j| > `threshold`
(0.5 rad by default), and stable if neither happens by t1 (2 s by default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Rod", "FieldP1", "RunResult", "sine_velocity", "noise_coefficients", "noise_field",
           "critical_velocity", "critical_load_random_force", "bisect"]


@dataclass(frozen=True)
class Rod:
    """The rod in its channel, SI units: length `L` [m], diameter `d` [m], Young's modulus `E`
    [Pa], density `rho_v` [kg/m³], clearance `R` [m], gravity `g` [m/s²], friction `mu` [-].
    Defaults: the reference rod of PHYSICS.md section 1."""

    L: float = 3.0
    d: float = 1.5e-3
    E: float = 77e9
    rho_v: float = 6450.0
    R: float = 5.125e-3
    g: float = 9.81
    mu: float = 0.3

    @property
    def EI(self) -> float:
        """Bending rigidity E·πd⁴/64 [N·m²]."""
        return self.E * math.pi * self.d**4 / 64

    @property
    def rho(self) -> float:
        """Mass per length ρ_v·πd²/4 [kg/m]."""
        return self.rho_v * math.pi * self.d**2 / 4

    @property
    def w(self) -> float:
        """Weight per length ρg = N [N/m]."""
        return self.rho * self.g

    @property
    def friction(self) -> float:
        """f = μN/(ρR) [rad/s²]: the friction bound on a node's angular acceleration."""
        return self.mu * self.w / (self.rho * self.R)

    def F0(self, m: int = 6) -> float:
        """F⁰_m = EIω_m² + ρg/(Rω_m²) [N] (P5); F⁰_6 = 1.308 N for the reference rod."""
        om2 = (m * math.pi / self.L) ** 2
        return self.EI * om2 + self.w / (self.R * om2)

    def k(self, m, F: float) -> np.ndarray:
        """k_m = (ω_m²/ρ)(F⁰_m − F) [1/s²] (P3)."""
        om2 = (np.asarray(m, float) * math.pi / self.L) ** 2
        return om2 / self.rho * (self.EI * om2 + self.w / (self.R * om2) - F)


@dataclass
class RunResult:
    """A run's outcome: `buckled` (max|θ| passed the threshold), `stuck` (held for good),
    `t_stop` [s] (when it buckled or stuck; t1 otherwise), final `q` [rad] and `v` [rad/s],
    `steps` taken, and `amplitude` (max|θ| at the stop) [rad]."""

    buckled: bool
    stuck: bool
    t_stop: float
    q: np.ndarray
    v: np.ndarray
    steps: int
    amplitude: float


class FieldP1:
    """P1 on `n` interior nodes under the axial load `F` [N], Moreau–Jean step `dt` [s] (see the
    module). `k` overrides the modal stiffnesses k_m [1/s²] (tests: k = 0 makes every node an
    independent Coulomb block); `friction` overrides f [rad/s²]."""

    def __init__(self, rod: Rod, F: float, n: int = 64, dt: float = 1e-4, theta: float = 0.5,
                 k: np.ndarray | None = None, friction: float | None = None):
        self.rod, self.F, self.n, self.dt, self.theta = rod, float(F), int(n), float(dt), float(theta)
        m = np.arange(1, n + 1)
        j = np.arange(1, n + 1)
        self.s = j * rod.L / (n + 1)  # node positions [m]
        self.k = rod.k(m, self.F) if k is None else np.asarray(k, float)
        self.f = rod.friction if friction is None else float(friction)
        S = np.sin(np.pi * np.outer(j, m) / (n + 1))  # DST-I: S @ S = (n+1)/2 · I
        self.S, self.c = S, 2.0 / (n + 1)
        h, th = self.dt, self.theta
        den = 1.0 + h * h * th * th * self.k
        if np.any(den <= 0):
            raise ValueError(f"dt = {dt} too large for the fastest growth: need h·θ·√|k_m| < 1.")
        modal = lambda d: self.c * (S * d[None, :]) @ S  # S diag(d) S⁻¹ [n × n]
        self.A = modal(self.k)  # acceleration per θ [1/s²]
        self.W = modal(h / den)  # Delassus matrix [s]
        self.Bv = modal((1.0 - h * h * th * (1 - th) * self.k) / den)  # v_free from v⁻
        self.Bq = modal(-h * self.k / den)  # v_free from q⁻ [1/s]
        self.P = modal(1.0 / den)
        self.gamma = 1.0 / np.diag(self.W)
        self.fallbacks = 0

    # -- one step ------------------------------------------------------------------------------

    def friction_impulse(self, vf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The exact friction r [rad/s²] and v⁺ = vf + W r for the free velocity `vf` [rad/s]:
        r_j ∈ −f Sgn(v⁺_j). **Returns:** (v⁺, r), with v⁺_j = 0 exactly at stick nodes."""
        W, f, gam = self.W, self.f, self.gamma
        if f == 0.0:
            return vf.copy(), np.zeros_like(vf)
        r = np.zeros_like(vf)
        prev = None
        for _ in range(60):
            v = vf + W @ r
            P = r - gam * v
            sets = np.where(P < -f, 1, np.where(P > f, -1, 0))  # +1: slips with v > 0
            if prev is not None and np.array_equal(sets, prev):
                v[sets == 0] = 0.0
                return v, r
            prev = sets
            r = -f * sets.astype(float)
            st = sets == 0
            if st.any():
                sl = ~st
                rhs = -(vf[st] + W[np.ix_(st, sl)] @ r[sl])
                r[st] = np.linalg.solve(W[np.ix_(st, st)], rhs)
        return self._pgs(vf)

    def _pgs(self, vf, sweeps: int = 10000, tol: float = 1e-14):
        """Projected Gauss–Seidel on the same problem (the fallback)."""
        self.fallbacks += 1
        W, f = self.W, self.f
        r = np.zeros_like(vf)
        v = vf.copy()
        for _ in range(sweeps):
            change = 0.0
            for j in range(self.n):
                new = min(max(r[j] - v[j] / W[j, j], -f), f)
                d = new - r[j]
                if d != 0.0:
                    v += W[:, j] * d
                    r[j] = new
                    change = max(change, abs(d))
            if change <= tol * f:
                break
        v[np.abs(r) < f] = 0.0
        return v, r

    def step(self, q, v, g=None):
        """One Moreau–Jean step from (q, v) with the constant forcing `g` [rad/s²] (optional)."""
        vf = self.Bv @ v + self.Bq @ q
        if g is not None:
            vf = vf + self.dt * (self.P @ g)
        v1, _ = self.friction_impulse(vf)
        q1 = q + self.dt * ((1 - self.theta) * v + self.theta * v1)
        return q1, v1

    def held(self, q, v) -> bool:
        """Whether the rod is stuck for good: every node at rest with |Aq|_j ≤ f."""
        return bool(np.all(v == 0.0) and np.all(np.abs(self.A @ q) <= self.f))

    # -- runs ------------------------------------------------------------------------------

    def run(self, q0, v0, t1: float = 2.0, threshold: float = 0.5) -> RunResult:
        """Integrate to `t1` [s], stopping when max|θ| > `threshold` [rad] or when stuck."""
        q, v = np.array(q0, float), np.array(v0, float)
        steps = int(math.ceil(t1 / self.dt - 1e-9))
        if self.held(q, v):
            return RunResult(False, True, 0.0, q, v, 0, float(np.max(np.abs(q))))
        for i in range(1, steps + 1):
            q, v = self.step(q, v)
            amp = float(np.max(np.abs(q)))
            if not math.isfinite(amp):
                raise FloatingPointError("non-finite state")
            if amp > threshold:
                return RunResult(True, False, i * self.dt, q, v, i, amp)
            if self.held(q, v):
                return RunResult(False, True, i * self.dt, q, v, i, amp)
        return RunResult(False, False, steps * self.dt, q, v, steps, float(np.max(np.abs(q))))

    def forced_shape(self, force: np.ndarray, duration: float = 1e-3) -> np.ndarray:
        """θ [rad] after the lateral force per length `force` [N/m] at the nodes has acted for
        `duration` [s] on the straight rod at rest (friction included), in ⌈duration/dt⌉ equal
        steps; the rod is then to be released from rest."""
        g = np.asarray(force, float) / (self.rod.rho * self.rod.R)
        n_steps = max(1, int(math.ceil(duration / self.dt - 1e-9)))
        sub = FieldP1(self.rod, self.F, self.n, duration / n_steps, self.theta, self.k, self.f)
        q, v = np.zeros(self.n), np.zeros(self.n)
        for _ in range(n_steps):
            q, v = sub.step(q, v, g)
        self.fallbacks += sub.fallbacks
        return q


# -- perturbations ------------------------------------------------------------------------------

def sine_velocity(model: FieldP1, v0: float, mode: int = 6):
    """(θ₀, θ̇₀) of the lateral velocity v₀ sin(mode·πs/L) [m/s] from the straight rod."""
    return np.zeros(model.n), v0 / model.rod.R * np.sin(mode * math.pi * model.s / model.rod.L)


def noise_coefficients(draws: np.ndarray, amplitude: float, modes: int) -> np.ndarray:
    """c_m, m = 1..`modes`, of the field amplitude·r_j on the interior nodes j = 1..grid−1 of
    `grid` = len(draws) + 1 equal segments: c_m = (2/grid) Σ_j amplitude·r_j sin(mπj/grid)
    (`draws` r_j uniform in [−1, 1])."""
    grid = len(draws) + 1
    j = np.arange(1, grid)
    m = np.arange(1, modes + 1)
    return (2.0 / grid) * np.sin(np.pi * np.outer(m, j) / grid) @ (amplitude * np.asarray(draws, float))


def noise_field(draws, amplitude: float, s: np.ndarray, L: float, modes: int) -> np.ndarray:
    """The grid field's sine series truncated to `modes` modes, at the points `s` [m]."""
    c = noise_coefficients(draws, amplitude, modes)
    m = np.arange(1, modes + 1)
    return np.sin(np.pi * np.outer(s, m) / L) @ c


# -- searches -----------------------------------------------------------------------------------

def bisect(label, lo: float, hi: float, rtol: float = 1e-4):
    """Geometric bisection of a boolean `label` (True: buckled) with label(lo) False and
    label(hi) True, to hi/lo − 1 ≤ `rtol`. **Returns:** (lo, hi, evaluations)."""
    if label(lo) or not label(hi):
        raise ValueError(f"[{lo}, {hi}] does not bracket the boundary")
    n = 2
    while hi / lo - 1 > rtol:
        x = math.sqrt(lo * hi)
        lo, hi = (lo, x) if label(x) else (x, hi)
        n += 1
    return lo, hi, n


def critical_velocity(rod: Rod, dF: float, n: int = 64, dt: float = 1e-4, mode: int = 6,
                      t1: float = 2.0, threshold: float = 0.5, bracket=(1e-4, 1.0), rtol: float = 1e-4):
    """v₀* [m/s] of the sine velocity v₀ sin(mode·πs/L) at F = F⁰_6 + `dF` [N] (the geometric
    mean of the final bracket), and the number of runs."""
    model = FieldP1(rod, rod.F0(6) + dF, n, dt)
    label = lambda v0: model.run(*sine_velocity(model, v0, mode), t1, threshold).buckled
    lo, hi, evals = bisect(label, *bracket, rtol)
    return math.sqrt(lo * hi), evals


def critical_load_random_force(rod: Rod, draws, amplitude: float = 2.0, n: int = 64, dt: float = 1e-4,
                               modes: int | None = None, duration: float = 1e-3, t1: float = 2.0,
                               threshold: float = 0.5, bracket=(0.05, 100.0), rtol: float = 1e-4):
    """ΔF* [N] above F⁰_6 of the random position perturbation: forces amplitude·(grid field,
    truncated to `modes` modes, default n) [N/m] for `duration` [s], then released from rest."""
    modes = n if modes is None else modes
    proto = FieldP1(rod, 0.0, n, dt)
    force = noise_field(draws, amplitude, proto.s, rod.L, min(modes, len(draws)))

    def label(dF):
        model = FieldP1(rod, rod.F0(6) + dF, n, dt)
        q0 = model.forced_shape(force, duration)
        return model.run(q0, np.zeros(n), t1, threshold).buckled

    lo, hi, evals = bisect(label, *bracket, rtol)
    return math.sqrt(lo * hi), evals
