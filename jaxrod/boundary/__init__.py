r"""Gradient-based search for the stable-zone boundary and the critical load.

The package: `indicators` (the functions whose roots are the boundary), `roots` (the solver,
continuation, implicit sensitivities), `search` (`critical_velocity`, `critical_load`: one point
each) and `curves` (`boundary_curve`, `critical_load_curve`).

**The indicator.** A root finder needs a function of the searched value x (the perturbation
amplitude, or the load) that changes sign at the boundary and says how far away it is.

- single mode: `g = A(T)/a − 1` of the exact piecewise solution at T = `horizon`/λ, a = f_s/|k|
  the largest amplitude static friction holds; smooth at the root (for μ_s = μ_d), whose bias
  ≈ 2e^{−2λT} is 4e-9 at the default horizon. Newton's method finds it in about 3 runs.
- field and Galerkin models: every run stops as soon as its label is known — stuck (it stays
  stuck) or past the buckling threshold. A rod just above the boundary leaves the marginally
  held state at its growth rate λ, and the component of q̇ along ∂q/∂x at the crossing
  (one forward-mode tangent) is u ≈ λ·(x − x*): linear in the distance to the boundary
  ([`jaxrod.boundary.departure_rate`][]). The amplitude at a fixed horizon, the indicator of
  earlier releases (`rod_indicator`, kept for comparison), is a jump at floating-point
  resolution there: its slope says nothing about the root.

**The solver** for the rods ([`jaxrod.boundary.departure_secant`][]) steps from the lowest
buckled run by a secant on u (the first step with the largest growth rate of the rod,
[`jaxrod.theory.max_growth_rate`][], which stops short of the root), inside a bracket kept by
the labels; a step that leaves the bracket becomes a bisection. `bisection` on the label alone
is the baseline. Everything is pure and vmappable; curves go along the loads, each search
started from its neighbours' roots (benchmarks/README.md: boundary_cost).

**Sensitivities** of the root x*(p) follow from the implicit function theorem,
dx*/dp = −(∂g/∂p)/(∂g/∂x): for the single mode at the root; for the rods from the tangents
∂q/∂p and ∂q/∂x at the crossing of the lowest buckled run, which the growing direction
dominates. One forward-mode run per parameter, no differentiation through the iterations.
"""

from .roots import ROOT_RESULTS as ROOT_RESULTS
from .roots import RootResult as RootResult
from .roots import safeguarded_newton as safeguarded_newton
from .roots import bisection as bisection
from .roots import expanding_bisection as expanding_bisection
from .roots import departure_secant as departure_secant
from .roots import implicit_sensitivities as implicit_sensitivities
from .roots import continuation as continuation
from .indicators import single_mode_indicator as single_mode_indicator
from .indicators import rod_indicator as rod_indicator
from .indicators import crossing_state as crossing_state
from .indicators import run_label as run_label
from .indicators import departure_rate as departure_rate
from .indicators import departure_sensitivities as departure_sensitivities
from .indicators import smooth_single_mode_indicator as smooth_single_mode_indicator
from .search import critical_velocity as critical_velocity
from .search import critical_load as critical_load
from .curves import boundary_curve as boundary_curve
from .curves import critical_load_curve as critical_load_curve
from .search import METHODS as METHODS

__all__ = ['ROOT_RESULTS', 'RootResult', 'safeguarded_newton', 'departure_secant', 'bisection', 'expanding_bisection', 'implicit_sensitivities', 'continuation', 'single_mode_indicator', 'rod_indicator', 'run_label', 'crossing_state', 'departure_rate', 'departure_sensitivities', 'smooth_single_mode_indicator', 'METHODS', 'critical_velocity', 'critical_load', 'boundary_curve', 'critical_load_curve']
