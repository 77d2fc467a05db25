"""What an injection run shows: a steady slide, a lock, a state still changing, or a state the
model no longer resolves — one definition for every run of the rod (docs/physics.md §8).

A run is read over its loading push, cut into `Criterion.windows` equal parts of entry advance;
the last two parts are compared. With Δ the advance over a part, ρ = Δ(far end)/Δ(entry) the
transfer ratio and f̄ the mean entry force [F₀] over it:

- **sliding** (steady): ρ ≥ `slide` in the last part, and from the part before it ρ moved by at
  most `settle` and f̄ by at most `settle` × f̄ — the far end moves with the entry at a force that
  has stopped changing;
- **locked**: ρ ≤ `lock` in the last part (the far end has stopped) while f̄ still rises (and
  was positive before: a rod thrashing round the channel, its force changing sign, is not
  locked but transient or unresolved);
- **transient**: anything else — the far end lags the entry, or the entry force is still moving;
  such a run brackets nothing;
- **unresolved**: at some save the rod turns round the channel faster than the model resolves,
  fewer than `min_segments_per_turn` segments per helical turn or a helix angle past
  `max_helix_angle` (what a discrete rod of that many segments can represent; it overrides the
  others, as does **failed**, a non-finite record).

The soft-string closed forms are the steady, infinitely slow limit of the same definition:
their F_far,max is the largest far load a steady slide can push; a run that is transient says
nothing about it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["SLIDING", "LOCKED", "TRANSIENT", "UNRESOLVED", "FAILED", "Criterion", "turn_resolution", "verdict"]

SLIDING, LOCKED, TRANSIENT, UNRESOLVED, FAILED = "sliding", "locked", "transient", "unresolved", "failed"


class Criterion(NamedTuple):
    """The thresholds of `verdict` (module docstring)."""

    windows: int = 5
    slide: float = 0.9
    lock: float = 0.05
    settle: float = 0.02
    min_segments_per_turn: float = 8.0
    max_helix_angle: float = 30.0  # [deg]


def _check(criterion: Criterion) -> None:
    c = criterion
    if not (isinstance(c.windows, int) and c.windows >= 2):
        raise ValueError(f"Criterion.windows = {c.windows!r} is invalid: expected an int >= 2.")
    if not (0.0 <= c.lock < c.slide <= 1.0):
        raise ValueError(f"Criterion.lock, slide = {c.lock!r}, {c.slide!r} are invalid: expected 0 <= lock < slide <= 1.")
    for name in ("settle", "min_segments_per_turn", "max_helix_angle"):
        x = getattr(c, name)
        if not (isinstance(x, (int, float)) and 0.0 < x < math.inf):
            raise ValueError(f"Criterion.{name} = {x!r} is invalid: expected a finite float > 0.")


def turn_resolution(theta, l0: float, r: float, contact=None):
    """Per save, how well the rod's turn round the channel is resolved: the fewest segments per
    helical turn, 2π/max|Δθ|, and the largest helix angle, atan(r max|Δθ|/l̂) [deg], where Δθ is
    the change of the wall angle `theta` (saves, n + 1) [rad] from one node to the next (wrapped
    to (−π, π]), `l0` the segment length [m] and `r` the clearance [m]; with `contact` (saves,
    n + 1, bool), only between neighbours that both touch the wall (the angle of a node off the
    wall, a pinned end at the axis, says nothing of a helix). A straight or sinusoidal rod (|Δθ|
    small) has many segments per turn."""
    theta = np.asarray(theta, float)
    d = np.angle(np.exp(1j * np.diff(theta, axis=-1)))
    if contact is not None:
        contact = np.asarray(contact, bool)
        d = np.where(contact[..., 1:] & contact[..., :-1], d, 0.0)
    turn = np.max(np.abs(d), axis=-1)
    per_turn = np.where(turn > 0, 2 * np.pi / np.where(turn > 0, turn, 1.0), np.inf)
    return per_turn, np.degrees(np.arctan(r * turn / l0))


def verdict(push, far, f_in, theta=None, l0: float | None = None, r: float | None = None,
            criterion: Criterion = Criterion(), contact=None) -> dict:
    """The status of an injection run's loading phase (module docstring) from its saves: `push`
    the entry's advance [m], `far` the far end's [m], `f_in` the entry force [F₀]; with `theta`
    (saves, n + 1) [rad], `l0` and `r` [m] (and `contact`, as there), also its resolution
    (`turn_resolution`).

    **Returns:** a dict: `status` (one of `SLIDING`, `LOCKED`, `TRANSIENT`, `UNRESOLVED`,
    `FAILED`), `reason` (one line), `transfer` (ρ over the last two parts), `force` (f̄ over them
    [F₀]), and with `theta` `segments_per_turn` and `helix_angle` [deg] (the worst over the saves)
    and `f_unresolved` (the entry force at the first save past the bounds, or None)."""
    _check(criterion)
    push, far, f_in = (np.asarray(a, float) for a in (push, far, f_in))
    if not (push.shape == far.shape == f_in.shape and push.ndim == 1 and push.size >= 2 * criterion.windows):
        raise ValueError(f"push, far, f_in have shapes {push.shape}, {far.shape}, {f_in.shape}: expected equal 1D "
                         f"records of at least {2 * criterion.windows} saves.")
    out = dict(transfer=None, force=None)
    if theta is not None:
        per_turn, angle = turn_resolution(theta, l0, r, contact)
        bad = (per_turn < criterion.min_segments_per_turn) | (angle > criterion.max_helix_angle)
        out.update(segments_per_turn=float(np.min(per_turn)), helix_angle=float(np.max(angle)),
                   f_unresolved=float(f_in[np.argmax(bad)]) if bad.any() else None)
    if not (np.all(np.isfinite(push)) and np.all(np.isfinite(far)) and np.all(np.isfinite(f_in))):
        return dict(out, status=FAILED, reason="the record is not finite")
    if theta is not None and out["f_unresolved"] is not None:
        return dict(out, status=UNRESOLVED,
                    reason=f"{out['segments_per_turn']:.3g} segments per turn (at least {criterion.min_segments_per_turn:g}), "
                           f"helix angle {out['helix_angle']:.3g} deg (at most {criterion.max_helix_angle:g}), "
                           f"first past them at {out['f_unresolved']:.3g} F0")
    edges = push[0] + (push[-1] - push[0]) * np.arange(criterion.windows + 1) / criterion.windows
    if not push[-1] > push[0]:
        raise ValueError(f"push goes from {push[0]:g} to {push[-1]:g} m and does not advance: expected the entry's advance over a "
                         "loading phase.")

    def part(k):
        lo, hi = edges[k], edges[k + 1]
        i, j = int(np.searchsorted(push, lo)), int(np.searchsorted(push, hi, side="right")) - 1
        sel = slice(i, j + 1)
        rho = (far[j] - far[i]) / (push[j] - push[i]) if push[j] > push[i] else np.nan
        return float(rho), float(np.mean(f_in[sel]))

    (rho0, f0), (rho1, f1) = part(criterion.windows - 2), part(criterion.windows - 1)
    out.update(transfer=(rho0, rho1), force=(f0, f1))
    if rho1 <= criterion.lock and f1 > f0 > 0:
        return dict(out, status=LOCKED, reason=f"the far end stopped (transfer {rho1:.3g}) while the entry force rose "
                                               f"{f0:.4g} -> {f1:.4g} F0")
    settled = abs(rho1 - rho0) <= criterion.settle and abs(f1 - f0) <= criterion.settle * abs(f1)
    if rho1 >= criterion.slide and settled:
        return dict(out, status=SLIDING, reason=f"transfer {rho0:.3g} -> {rho1:.3g}, entry force {f0:.4g} -> {f1:.4g} F0")
    return dict(out, status=TRANSIENT, reason=f"transfer {rho0:.3g} -> {rho1:.3g}, entry force {f0:.4g} -> {f1:.4g} F0: "
                                              "not settled")
