"""The lock-up case μL/ℓ = 1, r/ℓ = 0.02, μ = 0.5, far load 2.5 F₀, injected, for two materials:
the reference nitinol (d = 1.5 mm, E = 77 GPa, ρ_v = 6450 kg/m³) and a softer, lighter rod
(d = 3 mm, E = 2 GPa, ρ_v = 1200 kg/m³). In units of F₀ and ℓ they are the same case; the push
(0.3 m for the reference) is scaled by ℓ, the speed (5 mm/s) by ℓ/√(r/g) and the damping
(20/s) by √(g/r), so that the two runs are the same in time units √(r/g) too. Writes
two_materials.json beside this file.

    python studies/lockup/two_materials.py   # about 2 min on a 2-core CPU
"""

import json
import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402

_ROOT, _, _REL = os.path.dirname(os.path.abspath(__file__)).rpartition(os.sep + "studies")
HERE = _ROOT + os.sep + "results" + _REL  # this study's data: the same folder under results/

import jaxrod as jr  # noqa: E402
from jaxrod.lockup.push import inject, push_rod, units  # noqa: E402

MATERIALS = {"reference nitinol": None,
             "d 3 mm, E 2 GPa, rho_v 1200": jr.RodChannel(L=1.0, d=3e-3, E=2e9, rho_v=1200.0, nu=0.4, R=0.01, g=9.81,
                                                          mu_s=0.5, mu_d=0.5)}


def main():
    ref = push_rod(1.0, 0.02, 0.5)
    _, ell_ref = units(ref)
    out = {}
    for name, material in MATERIALS.items():
        rod = push_rod(1.0, 0.02, 0.5, material)
        F0, ell = units(rod)
        time_scale = np.sqrt(float(rod.R) / float(ref.R))  # √(r/g) against the reference's
        push, speed, c = 0.3 * ell / ell_ref, 5e-3 * (ell / ell_ref) / time_scale, 20.0 / time_scale
        t = time.perf_counter()
        r = inject(rod, 2.5 * F0, speed, push / speed, n_save=201, damping=c)
        tail = r["push"] >= 0.8 * r["push"].max()
        out[name] = dict(L=float(rod.L), r=float(rod.R), F0=F0, ell=ell, EA_over_F0=float(rod.EA) / F0, n=int(r["n"]),
                         push=push, speed=speed, damping=c, wall_s=time.perf_counter() - t,
                         entry_force_over_F0_last_fifth=[float(r["f_in"][tail].min()), float(r["f_in"][tail].max())],
                         drag_over_F0=c * float(rod.rho) * float(rod.L) * speed / F0,
                         helical_over_ell=float(r["helical"][-1] / ell), sinusoidal_over_ell=float(r["sinusoidal"][-1] / ell),
                         result=int(r["result"]))
        print(name, json.dumps(out[name]), flush=True)
    with open(os.path.join(HERE, "two_materials.json"), "w") as fh:
        json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
