"""Convergence in the node count n of the random-perturbation results (E4's critical load ΔF*,
E5's dominant mode) at two friction coefficients: the numbers E4–E6 report are numbers of the
scene only if they stop moving with n.

The random fields belong to the scene (drawn on the paper's 500-segment grid, given to the model
as their sine series, `jaxrod.perturbations`), so a finer model resolves more of the same field.
Each row: one perturbation kind, one μ, one n; `realizations` seeds (the same keys at every n),
ΔF* from `critical_load_curve` (rtol 1e-4), the dominant mode of the state reached at
1.05 ΔF* (`dominant_modes_at`, as E5).
"""

from __future__ import annotations

import os

import numpy as np

from ..output import subplots, write_csv
from ..params import RodChannel
from ._stats import finite_mean_std

__all__ = ["convergence", "dominant_modes_at", "SIZES"]

SIZES = {
    "tiny": dict(mus=(0.3,), realizations=1, n={"random-velocity": (24, 32), "random-position": (24, 32)}, t1=0.3),
    True: dict(mus=(0.3, 0.9), realizations=2,
               n={"random-velocity": (128, 256), "random-position": (96, 192)}, t1=0.3),
    False: dict(mus=(0.3, 0.9), realizations=3,
                n={"random-velocity": (256, 499, 768), "random-position": (128, 256, 384)}, t1=0.5),
}
AMPLITUDES = {"random-velocity": 15e-3, "random-position": 2.0}


def dominant_modes_at(kind, amplitude, mus, dFs, n, realizations, seed=5, t1=2.0):
    """The dominant mode of the final state of field-model runs (`n` nodes) at μ = `mus[i]`,
    ΔF = `dFs[i, r]` [N], for the random perturbation `kind` of `amplitude` realized with key
    fold_in(key(seed), i·R + r) — the keys of `critical_load_curve(..., seed=seed)`, so each run
    repeats its search's realization. One vmapped batch; the step of the largest load.

    **Returns:** `(modes, buckled)`, arrays (len(mus), realizations)."""
    import jax
    import jax.numpy as jnp

    from ..modal import dominant_mode
    from ..registry import make_perturbation
    from ..scene import Scene

    R = realizations
    rod0 = RodChannel.reference()
    dt = Scene(rod0, float(np.nanmax(dFs)), kind="field", n=n).step()
    root_key = jax.random.key(seed)

    def mode_at(mu, dF, i, r):
        key = jax.random.fold_in(root_key, i * R + r)
        sc = Scene(RodChannel.reference(mu=mu), dF, make_perturbation(kind, amplitude, 6, key), "field", n, 6, dt)
        sol = sc.run(t1=t1, n_save=201, save_state=False)
        return dominant_mode(sol.q_final), sol.buckled

    run = jax.jit(jax.vmap(jax.vmap(mode_at, (None, 0, None, 0)), (0, 0, 0, None)))
    modes, buckled = run(jnp.asarray(mus), jnp.asarray(dFs), jnp.arange(len(mus)), jnp.arange(R))
    return np.asarray(modes), np.asarray(buckled)


def convergence(out, quick=False, progress=True, max_dF: float = 300.0):
    """ΔF* and the dominant mode against n for both random perturbations at the `SIZES` μ;
    writes convergence.csv / .png under `out`. Returns, per kind and μ, the n values, ΔF*
    (mean over realizations, and each), the dominant modes, and the relative change of the mean
    ΔF* between the two finest n."""
    from ..boundary import critical_load_curve

    S = SIZES[quick]
    mus = np.asarray(S["mus"], float)
    R = S["realizations"]
    res, rows = {"model": "field", "realizations": R, "seed": 5, "rtol": 1e-4}, []
    for kind, amp in AMPLITUDES.items():
        per_n = []
        for n in S["n"][kind]:
            if progress:
                print(f"  convergence: {kind}, n = {n}, μ = {S['mus']}, {R} realization(s)", flush=True)
            rr, _ = critical_load_curve(mus, amp, perturbation=kind, realizations=R, seed=5, n=n, t1=S["t1"],
                                        bracket=(1e-3, max_dF), rtol=1e-4)
            roots = np.asarray(rr.root, float)  # NaN where a search failed
            modes, buckled = dominant_modes_at(kind, amp, mus, roots * 1.05, n, R, seed=5)
            modes = np.where(np.isfinite(roots) & buckled, modes, np.nan)
            per_n.append((n, roots, modes))
            for i, mu in enumerate(mus):
                for r in range(R):
                    rows.append(dict(perturbation=kind, mu=mu, n=n, realization=r, dF_star=roots[i, r],
                                     dominant_mode=modes[i, r]))
        ns = np.array([n for n, _, _ in per_n])
        for i, mu in enumerate(mus):
            dF = np.array([finite_mean_std(roots[i])[0] for _, roots, _ in per_n])
            md = np.array([finite_mean_std(modes[i])[0] for _, _, modes in per_n])
            res[f"{kind}, mu={mu:g}"] = {
                "n": ns.tolist(), "dF_star_mean": dF.tolist(),
                "dF_star": [roots[i].tolist() for _, roots, _ in per_n],
                "dominant_mode_mean": md.tolist(), "dominant_mode": [modes[i].tolist() for _, _, modes in per_n],
                "last_change_rel": float(dF[-1] / dF[-2] - 1) if len(dF) > 1 else float("nan"),
            }
    _figure(os.path.join(out, "convergence.png"), res)
    write_csv(os.path.join(out, "convergence.csv"), rows)
    return res


def _figure(path, res):
    """ΔF* (mean over the realizations) and the dominant mode against n, one line per
    perturbation and μ (the `"kind, mu=…"` entries of `res`)."""
    fig, axes = subplots(1, 2, figsize=(11, 4.2))
    for key, r in res.items():
        if isinstance(r, dict):
            kind, mu = key.split(", mu=")
            axes[0].plot(r["n"], r["dF_star_mean"], "o-", label=f"{kind}, μ = {mu}")
            axes[1].plot(r["n"], r["dominant_mode_mean"], "o-", label=f"{kind}, μ = {mu}")
    axes[0].set_xlabel("field nodes n")
    axes[0].set_ylabel("ΔF* [N] (mean over realizations)")
    axes[0].set_yscale("log")
    axes[1].set_xlabel("field nodes n")
    axes[1].set_ylabel("dominant mode at 1.05 ΔF*")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.suptitle("random perturbations on the scene's 500-segment grid: convergence in n", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
