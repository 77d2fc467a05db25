r"""Gradient-based search for the stable-zone boundary and the critical load.

The package: `indicators` (the functions whose roots are the boundary), `roots` (the solver,
continuation, implicit sensitivities), `search` (`critical_velocity`, `critical_load` and curves
of them).

**The indicator.** A root finder needs a function of the searched value x (the perturbation
amplitude, or the load) that changes sign at the boundary and whose derivative is informative on
both sides. The label "buckled" is a step function; instead jaxrod measures the state at a
finite horizon T against the stick line:

- single mode: `g = A(T)/a − 1`, a = f/|k| the half-width of the stick line. A stable state
  ends stuck at |A| ≤ a (g ≤ 0); an unstable one passes the saddle at A = a and runs away
  (g > 0). The exact piecewise solution is continuous in (Ȧ₀, k, f) and, in each slip phase,
  smooth; at the boundary itself the trajectory is still slipping towards the saddle at time
  T, so g is smooth there and its root lies above the separatrix by a relative
  ≈ 2e^{−2λT} (λ = √|k|; T = `horizon`/λ, default 10: 4e-9).
- field and Galerkin models: `g = log(max|θ(T)|/θ_c)` with θ_c the buckling threshold
  (0.5 rad) and the buckling stop lifted: stuck rods give g < 0 (the stuck amplitude grows
  with the perturbation), growing rods g > 0. The sharp law makes θ(T) piecewise smooth in the
  inputs (kinks where a node's stick/slip sequence changes), and continuous — the proximal
  step is a continuous map — so g is continuous and its forward derivative exists almost
  everywhere. The root converges to the 2 s / 0.5 rad classification boundary as T grows.

**The solver** is a safeguarded Newton iteration (derivatives by forward-mode AD through the
integrator) inside a bracket kept valid by the sign of g (= the buckled label); a Newton step
that leaves the bracket, or is not finite, is replaced by bisection (geometric for positive
brackets). Everything is pure and vmappable: a batch of boundary points is one `vmap`.

**Sensitivities** of the root x*(p) follow from the implicit function theorem at the root,
dx*/dp = −(∂g/∂p)/(∂g/∂x): one forward-mode derivative per parameter, no differentiation
through the iterations.
"""

from .roots import ROOT_RESULTS as ROOT_RESULTS
from .roots import RootResult as RootResult
from .roots import safeguarded_newton as safeguarded_newton
from .roots import bisection as bisection
from .roots import implicit_sensitivities as implicit_sensitivities
from .roots import continuation as continuation
from .indicators import single_mode_indicator as single_mode_indicator
from .indicators import rod_indicator as rod_indicator
from .indicators import smooth_single_mode_indicator as smooth_single_mode_indicator
from .search import critical_velocity as critical_velocity
from .search import critical_load as critical_load
from .search import boundary_curve as boundary_curve
from .search import critical_load_curve as critical_load_curve

__all__ = ['ROOT_RESULTS', 'RootResult', 'safeguarded_newton', 'bisection', 'implicit_sensitivities', 'continuation', 'single_mode_indicator', 'rod_indicator', 'smooth_single_mode_indicator', 'critical_velocity', 'critical_load', 'boundary_curve', 'critical_load_curve']
