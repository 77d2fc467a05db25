"""Why the 3D rod's v₀* exceeds the field model's at low loads (E3 with the full model, issue
[rod3d]): the field model P1 is the quadratic part of the energy of a centre line on the
channel's cylinder, r = (s, R sin θ, −R cos θ). Exactly, |r''|² = R²(θ''² + θ'⁴) and the height
is R(1 − cos θ), so per length

    ½ρR²θ̇² + ½EIR²(θ''² + θ'⁴) − ½FR²θ'² + wR(1 − cos θ)

(the θ'⁴ term is the normal curvature of the path on the cylinder: it stiffens; the sine of
gravity softens), and the wall force is N = w cos θ + ρRθ̇² (gravity's normal part and the
centripetal force), not w. At low ΔF the position intercept f/|k| of mode 6 (0.33 rad at
0.5 N) nears the 0.5 rad threshold, so these terms decide whether a run gets there.

This script adds them to the field model (a subclass: the acceleration gains
[6EIθ'²θ'' + (w/R)(θ − sin θ)]/ρ, the friction bound the factor N/w from the velocity before
the impulse), searches v₀* by label bisection as the boundary search does, and appends
(ΔF, P1, exact geometry, exact geometry + N) rows to `field_exact_geometry.csv` beside it:

    python studies/paper/e3/diagnostics/field_exact_geometry.py 0.5 1 2 5 10 20 40 60
"""
import csv
import os
import jax, sys
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
from jaxrod.params import RodChannel
from jaxrod.boundary import critical_velocity
from jaxrod.boundary.roots import bisection
from jaxrod.models import FieldModel
from jaxrod.scene import Scene
from jaxrod.perturbations import SineVelocity
from jaxrod.simulate import simulate
from jaxrod.integrators.base import RunOptions

class FieldNL(FieldModel):
    def acceleration(self, q, t):
        r = self.rod
        h = self.spacing
        p = jnp.pad(q, 1)
        d1 = (p[2:] - p[:-2]) / (2 * h)
        d2 = (p[2:] - 2 * p[1:-1] + p[:-2]) / h**2
        corr = 6 * r.EI * d1**2 * d2 + (r.w / r.R) * (q - jnp.sin(q))
        return super().acceleration(q, t) + corr / r.rho

class FieldNLN(FieldNL):
    def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
        f_s, f_d = self.friction_bounds(t)
        r = self.rod
        scale = jnp.cos(q) + r.rho * r.R * v_prev**2 / r.w
        return friction.update(v_trial, v_prev, h, f_s * scale, f_d * scale)

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/
rod = RodChannel.reference(0.3)
for dF in [float(x) for x in sys.argv[1:]]:
    r, _ = critical_velocity(rod, dF, model="field", rtol=1e-4, sensitivities=())
    base = Scene(rod, dF, SineVelocity(1e-3), kind="field")
    n, dt = base.size(), base.step()
    out = []
    for cls in (FieldNL, FieldNLN):
        def lab(v0):
            s = Scene(rod, dF, SineVelocity(v0), kind="field", n=n, dt=dt)
            m2 = cls.from_rod(rod, n, F=s.F)
            q0, v0_ = s.initial_state()
            return simulate(m2, s.integrator(), q0, v0_, 0.4, n_save=201, options=RunOptions(buckle_threshold=0.5, save_state=False), throw=False).buckled
        res = jax.jit(lambda: bisection(lab, 0.5 * r.root, 2.0 * r.root, 1e-4, 60))()
        out.append(float(res.root))
    path = os.path.join(HERE, "field_exact_geometry.csv")
    new = not os.path.exists(path)
    with open(path, "a", newline="") as fh:
        w = csv.writer(fh)
        if new:
            w.writerow(["dF", "mu", "nodes", "t1", "P1_mm_s", "exact_geometry_mm_s", "exact_geometry_and_N_mm_s"])
        w.writerow([dF, 0.3, n, 0.4, 1e3 * float(r.root), 1e3 * out[0], 1e3 * out[1]])
    print(f"dF {dF}: P1 {1e3*float(r.root):.3f} mm/s; exact cylinder geometry {1e3*out[0]:.3f} ({100*(out[0]/float(r.root)-1):+.1f} %); "
          f"+ N = w cos θ + ρRθ̇² {1e3*out[1]:.3f} ({100*(out[1]/float(r.root)-1):+.1f} %)", flush=True)
