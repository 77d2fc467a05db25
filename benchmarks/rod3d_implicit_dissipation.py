"""The implicit leapfrog's numerical dissipation against its step (issue [implicit3d]): the
energy a mode loses per period where the physics loses none, for the explicit leapfrog and the
implicit one (γ = 0.1, its default, and γ = 0).

- `free vibration`: a rod in space (no wall, gravity or friction; pinned ends, unloaded, 120
  segments) released at rest from the shape of its bending mode 20 (0.1 mm; period 11 ms; the
  segments along the chords, so no shear: a start with node velocities and no spins instead
  puts energy into the shear mode, which a step above its period aliases);
- `rolling`: the rod on the channel wall (60 segments, free ends, μ = 0.3 at the contact point,
  no load) released at rest 0.1 rad up the wall at every node: it rolls back and forth as a whole
  without slip (every contact stays stuck; period ≈ 2π√(1.5 R/g) = 0.18 s, the rolling rod's
  inertia 1.5 m; with pinned ends, held on the wall, it slides too and friction takes its energy).

Per case and step: the mechanical energy at each save over `--periods` periods (no stop), the
loss per period fitted as a geometric decay (`loss_per_period`), the part of it that `dissipated`
does not count (`uncounted_loss_per_period`: γ's loss is counted, the trapezoidal rule's own is
not), the largest step taken and the result code. Rows to
`benchmarks/results/rod3d_implicit_dissipation.csv`.

    python benchmarks/rod3d_implicit_dissipation.py   # ~3 min
"""

from __future__ import annotations

import math
import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.rod3d import Rod3D, step_limit  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_implicit_dissipation.csv")
STEPS = (1e-5, 5e-5, 1e-4, 3e-4)


def _cases():
    free = jr.RodChannel.reference(0.3).with_friction(0.0, 0.0)
    m_free = Rod3D(free, 120, channel=False, control="force", gravity=False)
    mode = 20
    omega = (mode * math.pi / float(free.L)) ** 2 * math.sqrt(float(free.EI) / float(free.rho))
    s = jnp.arange(121) / 120
    s0 = m_free.initial_state(0.0, lateral_offset=1e-4 * jnp.sin(mode * jnp.pi * s))
    rod = jr.RodChannel.reference(0.3)
    m_roll = Rod3D(rod, 60, control="force", ends="free")
    theta0 = 0.1
    s1 = m_roll.initial_state(0.0, lateral_offset=jnp.full(61, theta0 * float(rod.R)))
    period = 2 * math.pi * math.sqrt(1.5 * float(rod.R) / float(rod.g))
    return [("free vibration, mode 20, 120 segments", m_free, s0, 2 * math.pi / omega),
            ("rolling on the wall, mu 0.3, 60 segments", m_roll, s1, period)]


def _energy(model, integrator, state, t1, n_save):
    opts = jr.RunOptions(stop_on_buckle=False, stop_when_stuck=False, save_state=False)
    run = jax.jit(lambda q, v: jr.simulate(model, integrator, q, v, t1, n_save=n_save, options=opts, throw=False))
    sol = jax.block_until_ready(run(*state))
    return np.asarray(sum(sol.energies.values())), np.asarray(sol.dissipated), int(sol.result)


def main(periods=4.0):
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rows = []
    for name, model, state, T in _cases():
        limit = step_limit(model, state[0])
        schemes = [("explicit", 0.5 * limit, jr.ProjectedLeapfrog(0.5 * limit))]
        schemes += [(f"implicit, gamma {g}", h, jr.ImplicitLeapfrog(h, gamma=g)) for g in (0.1, 0.0) for h in STEPS]
        n_save = int(4 * periods) + 1
        for scheme, h, integrator in schemes:
            t0 = time.perf_counter()
            E, D, result = _energy(model, integrator, state, periods * T, n_save)
            sec = time.perf_counter() - t0
            # the mechanical energy left against the start (friction does no work in either case:
            # `dissipated` holds γ's counted loss, and friction's, ~0 here): what the scheme lost,
            # per period as a geometric decay over the run; and what `dissipated` leaves uncounted
            ratio = E[-1] / E[0] if result == 0 else float("nan")
            per_period = 1.0 - ratio ** (1.0 / periods) if result == 0 and ratio > 0 else float("nan")
            counted = (E[-1] + D[-1]) / E[0] if result == 0 else float("nan")
            uncounted = 1.0 - counted ** (1.0 / periods) if result == 0 and counted > 0 else float("nan")
            rows.append(dict(commit=commit, case=name, period_s=round(T, 5), scheme=scheme, dt=h,
                             dissipated=round(float(D[-1] / E[0]), 6) if result == 0 else "",
                             dt_over_explicit_limit=round(h / limit, 2), periods=periods,
                             energy_kept=round(float(ratio), 6) if result == 0 else "",
                             loss_per_period=round(float(per_period), 6) if result == 0 else "",
                             uncounted_loss_per_period=round(float(uncounted), 6) if result == 0 else "",
                             result=result, seconds=round(sec, 1)))
            print(rows[-1], flush=True)
    write_csv(OUT, rows)


if __name__ == "__main__":
    main()
