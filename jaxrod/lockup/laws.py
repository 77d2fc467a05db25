r"""The helix of a rod run against the laws the closed forms assume (docs/physics.md §8): along a
helical section of a saved state, the pitch against Lubinski's π√(8EI/F), the wall force per
length against Mitchell's r F²/(4EI) (with and without the weight w), and the change of the axial
force against the soft string's dF/ds = μN.

Everything here reads one save of a rod: the wall angle θ and the wall force per length N at
the n + 1 nodes, the compressive axial force F of the n segments, with the segment length l̂ [m].
Node 0 is the far end; s runs toward the entry, so a rod sliding toward its far end has
dF/ds = +μN.
"""

from __future__ import annotations

import numpy as np

__all__ = ["helix_against_laws"]


def _window_mean(a, half):
    """The mean of `a` over ±`half` samples (an int or one per sample; fewer at the ends)."""
    c = np.concatenate([[0.0], np.cumsum(a)])
    i = np.arange(a.size)
    lo, hi = np.maximum(i - half, 0), np.minimum(i + half + 1, a.size)
    return (c[hi] - c[lo]) / (hi - lo)


def helix_against_laws(theta, wall_force, axial_force, l0: float, EI: float, w: float, r: float, mu: float,
                       wave: float) -> dict:
    """Compare one save's helix with the laws (module docstring). `theta`, `wall_force` (n + 1,)
    [rad], [N/m]; `axial_force` (n,) [N]; `l0` [m]; `EI` [N·m²], `w` [N/m], `r` [m], `mu`;
    `wave` [m] the window (the buckle wavelength at the sinusoidal onset, 2π√(ℓr)).

    A node is helical where θ, unwrapped, spans more than 2π within one `wave` around it (a full
    turn: stricter than `push.extents`' π, so that the comparison is made on turns, not on a
    helix's ends, which the window already leaves out); the comparison uses the helical nodes at
    least half a window from the rod's ends, where the laws' averages over a turn hold.

    **Returns:** a dict of arrays over the nodes: `s` [m], `F` [N] (the segments' mean at each
    node), `N` [N/m] and `N_turn` (its mean over a window of one local pitch), `pitch` [m] (2π
    over |dθ/ds| averaged over the window), `pitch_lubinski` [m], `N_mitchell` [N/m] (r F²/(4EI)),
    `helical` (bool), `inner` (bool: the nodes compared); and the scalars over the inner nodes
    (NaN where there are none): `pitch_ratio` (median of the measured pitch over Lubinski's, both from the turn rate
    averaged over the window), `N_ratio` (median of
    N_turn/Mitchell), `N_ratio_with_weight` (against Mitchell + w), `soft_string_ratio` (the
    rise of F across the inner nodes over μ∫N ds there), `F_range` [N] (lowest and highest F
    there), `inner_length` [m]; over the whole rod `soft_string_ratio_whole` (F at the entry
    less F at the far end over μ∫N ds: the friction's bookkeeping, whatever the shape); over the
    winding nodes (θ spans more than π within the window, as `push.extents`' helix)
    `winding_length` [m], `reversals` (how often the windowed dθ/ds changes sign there: a helix
    that changes hand) and `wall_ratio_winding` (∫N ds over ∫ r F²/(4EI) ds there)."""
    theta, N, Fseg = (np.asarray(a, float) for a in (theta, wall_force, axial_force))
    n = Fseg.size
    if theta.shape != (n + 1,) or N.shape != (n + 1,):
        raise ValueError(f"theta, wall_force have shapes {theta.shape}, {N.shape}: expected ({n + 1},) for "
                         f"{n} segments of axial_force.")
    s = np.arange(n + 1) * l0
    th = np.unwrap(theta)
    F = np.concatenate([[Fseg[0]], 0.5 * (Fseg[1:] + Fseg[:-1]), [Fseg[-1]]])
    half = max(1, int(round(0.5 * wave / l0)))
    pad = np.pad(th, half, mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * half + 1)
    span = win.max(-1) - win.min(-1)
    helical, winding = span > 2 * np.pi, span > np.pi  # a full turn / half a turn within the window
    inner = helical.copy()
    inner[:half] = inner[-half:] = False  # the windows there are cut by the rod's ends
    rate = np.abs(np.gradient(th, s))
    rate_w = _window_mean(rate, half)
    pitch = np.where(rate_w > 0, 2 * np.pi / np.where(rate_w > 0, rate_w, 1.0), np.inf)
    lub = np.pi * np.sqrt(8 * EI / np.maximum(F, 1e-300))
    mitchell = r * F**2 / (4 * EI)
    turn_half = np.clip(np.round(0.5 * np.where(np.isfinite(pitch), pitch, 0.0) / l0), 1, n).astype(int)
    N_turn = _window_mean(N, turn_half)
    whole = (F[-1] - F[0]) / (mu * np.trapezoid(N, s)) if mu > 0 else np.nan
    turning = _window_mean(np.gradient(th, s), half)  # signed: its sign is the helix's hand
    hand = np.sign(turning[winding])
    reversals = int(np.count_nonzero(hand[1:] != hand[:-1])) if hand.size > 1 else 0
    on = np.where(winding, 1.0, 0.0)
    wall_ratio = (np.trapezoid(N * on, s) / np.trapezoid(mitchell * on, s)) if winding.any() else np.nan
    out = dict(s=s, F=F, N=N, N_turn=N_turn, pitch=pitch, pitch_lubinski=lub, N_mitchell=mitchell, helical=helical,
               inner=inner, soft_string_ratio_whole=float(whole), reversals=reversals,
               wall_ratio_winding=float(wall_ratio), winding_length=float(winding.sum() * l0))
    if not inner.any():
        return dict(out, pitch_ratio=np.nan, N_ratio=np.nan, N_ratio_with_weight=np.nan, soft_string_ratio=np.nan,
                    F_range=(np.nan, np.nan), inner_length=0.0)
    idx = np.flatnonzero(inner)
    i, j = idx[0], idx[-1]
    friction = mu * np.trapezoid(N[i:j + 1], s[i:j + 1]) if j > i else np.nan
    k_lub = _window_mean(np.sqrt(np.maximum(F, 0.0) / (2 * EI)), half)  # Lubinski's turn rate, same window
    return dict(out, pitch_ratio=float(np.median(k_lub[inner] / rate_w[inner])),
                N_ratio=float(np.median(N_turn[inner] / mitchell[inner])),
                N_ratio_with_weight=float(np.median(N_turn[inner] / (mitchell[inner] + w))),
                soft_string_ratio=float((F[j] - F[i]) / friction) if j > i else np.nan,
                F_range=(float(F[inner].min()), float(F[inner].max())), inner_length=float(s[j] - s[i]))
