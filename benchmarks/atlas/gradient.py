"""Failure atlas, entry 3 (`gradient`): the tanh law under explicit fixed steps.

dA(T)/dȦ₀ of `ProjectedVerlet(dt, Tanh(ε))` by `jax.grad` against central finite differences
and against the exact (sharp-law) derivative, as h·f/ε grows (single mode, ΔF = 5 N). Use
instead: `ProjectedVerlet` with Coulomb (exact piecewise gradients), or keep h·f/ε ≲ 1.

Run by `benchmarks/failure_atlas.py --only gradient`; returns (CSV rows, summary row, data for
the figure).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr

from .common import mode_at, scales


def entry_gradient(quick):
    m = mode_at(5.0)
    lam, a, vc = scales(m)
    f = float(m.f_d)
    dt = 1e-4
    T = 5.0 / lam
    # friction acts in two half kicks of h/2: the linearised tanh update 1 − (h/2)f/ε is unstable past h·f/ε = 4
    hfe = [0.1, 1.0, 3.0, 4.5, 10.0, 30.0] if quick else [0.1, 0.3, 1.0, 2.0, 3.0, 3.9, 4.1, 5.0, 10.0, 30.0, 100.0]
    opts = jr.RunOptions(early_exit=False, save_state=False)

    def final(v0, eps):
        sol = jr.simulate(m, jr.ProjectedVerlet(dt, jr.Tanh(eps)), 0.0, v0, T, n_save=2, options=opts, throw=False)
        return sol.q_final

    grad = jax.jit(jax.vmap(jax.grad(final), (0, None)))
    val = jax.jit(jax.vmap(final, (0, None)))
    exact_d = jax.jit(jax.vmap(lambda v0: jax.jvp(lambda x: jr.exact_solution(0.0, x, m.k, m.f_s, m.f_d, T)[0],
                                                  (v0,), (jnp.ones_like(v0),))[1]))
    K = 9 if quick else 21
    v0s = 0.8 * vc * (1 + jnp.linspace(-0.01, 0.01, K))  # a 2 % window
    h = 1e-6 * 0.8 * vc
    d_ex = np.asarray(exact_d(v0s))
    rows, out = [], {}
    for x in hfe:
        eps = dt * f / x
        g = np.asarray(grad(v0s, eps))
        fd = (np.asarray(val(v0s + h, eps)) - np.asarray(val(v0s - h, eps))) / (2 * h)
        fin = np.isfinite(g) & np.isfinite(fd)
        rel_fd = float(np.max(np.abs(g - fd) / np.maximum(np.abs(fd), 1e-300))) if fin.all() else float("inf")
        rel_ex = float(np.max(np.abs(g - d_ex) / np.abs(d_ex))) if fin.all() else float("inf")
        # roughness: largest second difference across the window (the exact derivative is smooth)
        noise = float(np.max(np.abs(np.diff(g, 2))) / np.abs(np.mean(d_ex)))
        rows.append(dict(h_f_over_eps=x, eps=eps, eps_rel=eps / vc, dt=dt, window_points=K,
                         grad_vs_fd_max_rel=rel_fd, grad_vs_exact_max_rel=rel_ex, grad_roughness=noise, exact_roughness=float(np.max(np.abs(np.diff(d_ex, 2))) / np.abs(np.mean(d_ex))),
                         grad_max_abs=float(np.max(np.abs(g))), exact_derivative=float(np.mean(d_ex)),
                         all_finite=bool(fin.all())))
        out[x] = (np.asarray(v0s) / vc, g, fd)
        print(f"  gradient h·f/ε = {x:5.1f} (ε' = {eps / vc:.1e}): max |grad − FD|/|FD| = {rel_fd:9.2e}, "
              f"max |grad − exact|/|exact| = {rel_ex:9.2e}, roughness = {noise:9.2e}")
    out["exact"] = (np.asarray(v0s) / vc, d_ex)
    at1 = [r for r in rows if r["h_f_over_eps"] == 1.0][0]
    lo = [r for r in rows if r["h_f_over_eps"] < 4.0]
    hi = [r for r in rows if r["h_f_over_eps"] > 4.0]
    summary = dict(
        failure="smoothed law under explicit fixed steps: gradients",
        measurement=(f"single mode ΔF = 5 N, explicit Verlet on tanh, dt = {dt:g} s, dA(5/λ)/dȦ₀ by jax.grad vs "
                     f"central finite differences, {K} points in a 2 % window around Ȧ₀ = 0.8 Ȧ_cr"),
        number=(f"h·f/ε < 4: grad = FD to {max(r['grad_vs_fd_max_rel'] for r in lo):.0e} (vs the sharp-law derivative: "
                f"{at1['grad_vs_exact_max_rel']:.0e} at h·f/ε = 1, the ε-bias); h·f/ε > 4: grad vs FD up to "
                f"{max(r['grad_vs_fd_max_rel'] for r in hi):.0e}, vs exact up to "
                f"{max(r['grad_vs_exact_max_rel'] for r in hi):.0e}, roughness up to "
                f"{max(r['grad_roughness'] for r in hi):.0e} of the derivative"),
        use_instead="ProjectedVerlet with Coulomb (exact piecewise gradients), or keep h·f/ε ≲ 1",
    )
    return rows, summary, out
