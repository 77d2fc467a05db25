"""The picture of one simulation: θ(s, t) as an image and the modal power spectrum."""

from __future__ import annotations

import numpy as np

from ..modal import modal_spectrum
from ..output import subplots
from ..registry import name_of


def plot_simulation(scene, sol, path: str | None = None):
    """θ(s,t) (left) and the modal power spectrum at the start, the middle and the end of the
    run (right). **Returns:** the `matplotlib.figure.Figure` (a notebook shows it inline); also
    written as a PNG to `path` when given."""

    s, theta = (np.asarray(x) for x in scene.field_of(sol.q))
    ts = np.asarray(sol.ts)
    stop = float(sol.t_stop)
    keep = ts <= stop + 1e-12
    keep[: min(2, len(keep))] = True  # at least two frames, also for a rod stuck at once
    fig, (ax0, ax1) = subplots(1, 2, figsize=(12, 4.5), gridspec_kw={"width_ratios": [1.4, 1]})
    vmax = max(float(np.max(np.abs(theta[keep]))), 1e-12)
    im = ax0.imshow(
        theta[keep].T, aspect="auto", origin="lower", cmap="RdBu_r", vmin=-vmax, vmax=vmax,
        extent=[ts[0], ts[keep][-1], s[0], s[-1]],
    )
    fig.colorbar(im, ax=ax0, label="θ [rad]")
    ax0.set_xlabel("t [s]")
    ax0.set_ylabel("s [m]")
    verdict = f"buckled at t = {float(sol.t_buckle):.4g} s" if bool(sol.buckled) else "not buckled"
    ax0.set_title(f"{name_of(scene.kind)} model, F = {float(scene.F):.4g} N: {verdict}")
    n_modes = min(40, theta.shape[1])
    grid = theta if _interior_nodes(s, float(scene.rod.L)) else _resample(s, theta, float(scene.rod.L))
    idx = np.flatnonzero(keep)
    for i, lab in ((idx[min(1, len(idx) - 1)], "early"), (idx[len(idx) // 2], "middle"), (idx[-1], "final")):
        p = np.asarray(modal_spectrum(grid[i], n_modes))
        if not np.any(p > 0):
            continue
        ax1.plot(np.arange(1, n_modes + 1), p, "o-", ms=3, label=f"{lab}, t = {ts[i]:.3g} s")
    ax1.set_xlabel("mode m")
    ax1.set_ylabel("normalised modal power")
    ax1.set_yscale("log")
    ax1.set_ylim(1e-8, 1.5)
    if ax1.get_legend_handles_labels()[0]:
        ax1.legend()
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def _interior_nodes(s, L) -> bool:
    """Whether `s` [m] are the equally spaced interior nodes jL/(n + 1) the DST-I needs."""
    return bool(np.allclose(s, np.arange(1, len(s) + 1) * L / (len(s) + 1), rtol=0, atol=1e-12 * L))


def _resample(s, theta, L, n=128):
    """θ on n equally spaced interior nodes (for the DST-I spectrum)."""
    nodes = np.arange(1, n + 1) * L / (n + 1)
    return np.stack([np.interp(nodes, s, row, left=0.0, right=0.0) for row in theta])
