"""Lock-up (beyond the paper, docs/physics.md §8): the 3D rod injected into a long channel
against a far load, for several μL/ℓ at once, beside the soft-string closed forms.

One geometry (r/ℓ = 0.02, the reference nitinol, L/ℓ fixed by the setting) and one vmapped run
([`jaxrod.lockup.push.inject_lanes`][]): lane (μL/ℓ, f_far) has μ = (μL/ℓ)/(L/ℓ) and the far
load f_far F₀, with f_far a fixed fraction of the largest soft-string F_far,max of the four
variants at its μL/ℓ (the grid is set from the closed forms before any run, never from the
3D results). From each lane: the steady entry force over the last fifth of the push, whether
it locked up (`jaxrod.lockup.push.locked`), the helical and sinusoidal extents, and the entry
force when a sinusoid and when a helix first appear. From the lanes together: F_far,max/F₀
bracketed by the largest sliding and the smallest locked far load, and μL_lock/ℓ bracketed by
the lanes without a far load.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..output import subplots, write_csv

__all__ = ["lockup", "SIZES"]

SPEED, DAMPING, PUSH_PER_LENGTH, R_OVER_ELL = 5e-3, 20.0, 0.075, 0.02
VARIANTS = [("chen", "with_weight"), ("chen", "without_weight"), ("wu_juvkam_wold", "with_weight"),
            ("wu_juvkam_wold", "without_weight")]
SIZES = {
    False: dict(L_over_ell=5.0, X=(0.5, 1.0, 2.0, 3.0, 4.0, 5.0), fractions=(0.0, 0.25, 0.5, 0.75, 1.0, 1.25),
                n=None, push=PUSH_PER_LENGTH, n_save=201),
    True: dict(L_over_ell=2.0, X=(0.5, 1.0, 2.0), fractions=(0.0, 0.5, 1.0, 1.25), n=None, push=PUSH_PER_LENGTH,
               n_save=101),
    "tiny": dict(L_over_ell=1.0, X=(0.5, 1.0), fractions=(0.0, 1.0), n=12, push=0.005, n_save=11),
}


def _soft(rod, X, f):
    """The soft string at μL/ℓ = X on the lane rod: F_far,max/F₀, μL_lock/ℓ and the entry force
    for the far load f F₀, per variant."""
    import jax.numpy as jnp

    from ..lockup import chain
    from ..lockup.push import units

    F0, ell = units(rod)
    EI, w, r = float(rod.EI), float(rod.rho * rod.g), float(rod.R)
    mu = X * ell / float(rod.L)
    out = {}
    for onset, law in VARIANTS:
        kw = dict(helical_onset=onset, helical_law=law)
        out[f"{onset}/{law}"] = dict(
            far_max=float(chain.far_force_max(rod.L, EI, w, r, mu, **kw)) / F0,
            lock=float(chain.lockup_length(EI, w, r, mu, **kw)) * mu / ell,
            entry=float(chain.entry_force(jnp.asarray(f * F0), rod.L, EI, w, r, mu, **kw)) / F0)
    return out


def _first(extent, f_in):
    i = np.flatnonzero(extent > 0)
    return float(f_in[i[0]]) if i.size else math.nan


def lockup(out, quick=False, progress=True) -> dict:
    """Run the lanes of the setting `quick` (False: L/ℓ = 5, μL/ℓ 0.5–5, 36 lanes; True: L/ℓ = 2,
    μL/ℓ 0.5–2, 12 lanes; "tiny": structure only) and write `lockup_lanes.csv` (one row per
    lane), `lockup_runs.csv` (every lane's saves) and `lockup.png`."""
    from ..lockup.push import inject_lanes, lane, locked, push_rod, units

    S = SIZES[quick]
    Lx = S["L_over_ell"]
    rod = push_rod(Lx, R_OVER_ELL, 1.0)  # μ = 1 gives L = L/ℓ · ℓ; each lane sets its own μ
    F0, ell = units(rod)
    refs = {X: max(max(v["far_max"] for v in _soft(rod, X, 0.0).values()), 1.0) for X in S["X"]}
    lanes = [(X, round(fr * refs[X], 6)) for X in S["X"] for fr in S["fractions"]]
    mus = np.array([X / Lx for X, _ in lanes])
    f_far = np.array([f for _, f in lanes])
    push = S["push"] * float(rod.L)
    if progress:
        print(f"  lock-up: {len(lanes)} lanes, L = {float(rod.L):.3g} m ({Lx:g} ell), r = {1e3 * float(rod.R):.3g} mm, "
              f"pushed {push:.3g} m at {1e3 * SPEED:g} mm/s", flush=True)
    rec = inject_lanes(rod, mus, f_far * F0, SPEED, push / SPEED, n=S["n"], n_save=S["n_save"], damping=DAMPING,
                       progress=progress)
    w = float(rod.rho * rod.g)
    rows, series = [], []
    for k, (X, f) in enumerate(lanes):
        one = lane(rec, k)
        tail = one["push"] >= 0.8 * one["push"][-1]
        adv_in = one["push"][tail][-1] - one["push"][tail][0]
        adv_far = one["u"][tail, 0][-1] - one["u"][tail, 0][0]
        soft = _soft(rod, X, f)
        lk = locked(one)
        row = dict(mu_L_over_ell=X, mu=float(mus[k]), far_load_over_F0=f, locked="" if lk is None else int(lk),
                   held_from_s=float(one["held_from"]), result=int(one["result"]),
                   entry_force_over_F0=float(np.mean(one["f_in"][tail])),
                   entry_force_min_over_F0=float(np.min(one["f_in"][tail])),
                   entry_force_max_over_F0=float(np.max(one["f_in"][tail])),
                   far_over_entry_advance=float(adv_far / adv_in) if adv_in > 0 else math.nan,
                   helical_over_ell=float(one["helical"][-1] / ell), sinusoidal_over_ell=float(one["sinusoidal"][-1] / ell),
                   entry_force_at_first_sinusoid_over_F0=_first(one["sinusoidal"] + one["helical"], one["f_in"]),
                   entry_force_at_first_helix_over_F0=_first(one["helical"], one["f_in"]),
                   max_wall_force_over_w=float(np.max(one["wall_force"][-1]) / w))
        row.update({f"soft_entry_{name}": v["entry"] for name, v in soft.items()})
        rows.append(row)
        series += [dict(lane=k, mu_L_over_ell=X, far_load_over_F0=f, t=one["t"][i], push=one["push"][i],
                        far_displacement=one["u"][i, 0], f_in=one["f_in"][i], helical_over_ell=one["helical"][i] / ell,
                        sinusoidal_over_ell=one["sinusoidal"][i] / ell) for i in range(len(one["t"]))]
    write_csv(os.path.join(out, "lockup_lanes.csv"), rows)
    write_csv(os.path.join(out, "lockup_runs.csv"), series)
    res = dict(model="rod3d", n_segments=int(rec["n"]), scheme=rec["scheme"], dt=float(rec["dt"]), L_over_ell=Lx, r_over_ell=R_OVER_ELL,
               L=float(rod.L), r=float(rod.R), F0=F0, ell=ell, speed=SPEED, damping=DAMPING, push=push, lanes=len(lanes),
               cap_over_F0=ell / float(rod.R), cases={})
    for X in S["X"]:
        mine = [r for r in rows if r["mu_L_over_ell"] == X and r["locked"] != ""]
        slides = [r["far_load_over_F0"] for r in mine if not r["locked"]]
        locks = [r["far_load_over_F0"] for r in mine if r["locked"]]
        soft = _soft(rod, X, 0.0)
        res["cases"][f"{X:g}"] = dict(
            far_max_3d_bracket=[max(slides) if slides else None, min(locks) if locks else None],
            far_max_soft={name: v["far_max"] for name, v in soft.items()},
            lockup_length_soft={name: v["lock"] for name, v in soft.items()})
    free = [r for r in rows if r["far_load_over_F0"] == 0.0 and r["locked"] != ""]
    res["lockup_length_3d_bracket"] = [max([r["mu_L_over_ell"] for r in free if not r["locked"]], default=None),
                                       min([r["mu_L_over_ell"] for r in free if r["locked"]], default=None)]
    _figure(out, rod, rows, res, S)
    return res


def _figure(out, rod, rows, res, S):
    import jax.numpy as jnp

    from ..lockup import chain
    from ..lockup.push import units

    F0, ell = units(rod)
    EI, w, r = float(rod.EI), float(rod.rho * rod.g), float(rod.R)
    fig, (a, b) = subplots(1, 2, figsize=(11, 4.5))
    colours = dict(zip(S["X"], ["C0", "C1", "C2", "C3", "C4", "C5"]))
    for X in S["X"]:
        mu = X * ell / float(rod.L)
        f_in = np.geomspace(0.05, 60.0, 200)
        for (onset, law), style in zip(VARIANTS[::2], ("-", "--")):
            f_far = np.asarray(chain.far_force(jnp.asarray(f_in * F0), rod.L, EI, w, r, mu, helical_onset=onset,
                                               helical_law=law)) / F0
            a.plot(f_in, f_far, style, color=colours[X], lw=1)
        mine = [q for q in rows if q["mu_L_over_ell"] == X]
        for q in mine:
            if q["locked"] == "":  # a failed lane: no point
                continue
            marker = "x" if q["locked"] else "o"
            a.plot(q["entry_force_over_F0"] if not q["locked"] else 60.0, q["far_load_over_F0"], marker,
                   color=colours[X], label=f"μL/ℓ = {X:g}" if q is mine[0] else None)
    a.set_xscale("log")
    a.set(xlabel="entry force / F₀ (last fifth of the push; x: locked)", ylabel="far load / F₀",
          title="3D rod (points) and soft string (— Chen, -- Wu & Juvkam-Wold)")
    a.legend(fontsize=8)
    X = np.linspace(0.8 * min(S["X"]), 6.0, 300)
    for onset, law in VARIANTS:
        fm = [float(chain.far_force_max(rod.L, EI, w, r, x * ell / float(rod.L), helical_onset=onset,
                                        helical_law=law)) / F0 for x in X]
        b.plot(X, fm, lw=1, label=f"{onset.replace('_', ' ')}, {law.replace('_', ' ')}")
    for key, c in res["cases"].items():
        lo, hi = c["far_max_3d_bracket"]
        x = float(key)
        if lo is not None and hi is not None:
            b.plot([x, x], [lo, hi], "k-", lw=3)
        elif lo is not None:
            b.plot(x, lo, "k^")
        elif hi is not None:
            b.plot(x, hi, "kv")
    b.plot([], [], "k-", lw=3, label="3D rod: largest sliding – smallest locked")
    top = max([v for c in res["cases"].values() for v in c["far_max_3d_bracket"] if v is not None]
              + [v for c in res["cases"].values() for v in c["far_max_soft"].values()])
    b.set(xlabel="μL/ℓ", ylabel="F_far,max / F₀", ylim=(0, 1.2 * top), title="largest force reaching the far end")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "lockup.png"), dpi=130)
