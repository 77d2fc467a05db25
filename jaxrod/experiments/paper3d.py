"""The paper's experiments with the paper's model: the 3D rod ([`jaxrod.rod3d`][]) at the paper's
500 segments for E3, E4, E5 and E6C, beside the field model. Each part lives with its experiment
(`jaxrod.experiments.e3.rod3d`, `e4.rod3d`, `e5.rod3d`, `e6.rod3d`; what they share in
`jaxrod.experiments._paper3d`); this module keeps their old names one release (`jaxrod reproduce e3 e4 e5 e6
--model rod3d [--n N]`; docs/paper.md, "The experiments with the 3D rod").

Every search is label bisection of the 3D rod's runs (a run stops at its label: stuck, or past
the buckling threshold) to a relative bracket of 1 %, started from the field model's answer:

- **E3**: v₀*(ΔF) of the sine mode 6, μ = 0.3, a bracket ±4 % around the field model's v₀*,
  widened until two runs hold it (`e3.rod3d.boundary_3d`); the exponent of v₀* ∝ ΔF^p by least
  squares in log–log over all the loads, fixed before any run, beside the paper's −0.77.
- **E4**: ΔF*(μ) of the sine 15 mm/s (A), of random velocities ±15 mm/s (B) and of random
  positions (C: forces ±2 N/m for 1 ms; realization r: key `fold_in(key(0), r)`), in a bracket
  a factor `WIDTH` either side of the field model's ΔF* for the same perturbation (for B on 499
  nodes, the random grid resolved), squared while the bracket holds no boundary, up to
  `WIDTH`⁴; horizon 0.5 s. The 3D rod never sticks (it rocks on the wall, rolling without
  slip), so a stable run lasts the whole horizon: the field model's 2 s costs four times the
  runs and gave the same bracket as 0.5 s where both were run (docs/rod3d.md gives the brackets
  and the cost).
- **E5**: on E4's points of B and C, one run of each model at 1.05 times its own ΔF*, with the
  step of its search (near the boundary a 3D label can turn with a step 2·10⁻⁴ apart), and the
  dominant mode of θ at the stop with its share of the power (a few seconds a run at 500
  segments: the runs stop at buckling).
- **E6C**: the random position (forces ±2 N/m for 1 ms, key 6 as `jaxrod reproduce e6`) at
  μ = 0.9: ΔF* (horizon 0.5 s, bracket a factor 4), then runs at 1.05 ΔF* and at the paper's
  40 N, and the largest modes of θ at the stop with their shares of the power of 40 modes.

A sweep never loses finished work: E3 appends every run to `e3/rod3d_runs.csv` and replays it,
E4, E5 and E6C append every finished point to their CSV (with wall time, commit and date) and
skip the points already there when the command runs again.
"""

# The parts live with their experiments (`e3.rod3d`, `e4.rod3d`, `e5.rod3d`, `e6.rod3d`) and what they share in
# `_paper3d`; this module keeps their old names one release.
from ._paper3d import *  # noqa: F401,F403
from ._paper3d import (_best, _commit, _critical_load, _e4_points, _final_theta, _found, _modes,  # noqa: F401
                       _Points, _settings, _theta_3d)
from .e3.rod3d import e3, write_boundary  # noqa: F401
from .e4.rod3d import _plot_e4, e4, e4_point  # noqa: F401
from .e5.rod3d import _plot_e5, e5  # noqa: F401
from .e6.rod3d import e6c  # noqa: F401
