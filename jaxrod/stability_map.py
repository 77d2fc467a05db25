"""E3: the stability map — straight or buckled over a grid of (ΔF, v₀) — and its boundary."""

from __future__ import annotations

import dataclasses
import json
import math
import os

import numpy as np

from . import theory
from .output import subplots, write_csv
from .params import RodChannel
from .registry import make_perturbation, name_of, recipe
from .map_columns import search_columns
from .sweeps import SweepResult, SweepSpec, sweep

__all__ = ["stability_map", "grid_boundary", "fit_power_law", "plot_maps"]


def grid_boundary(dF: np.ndarray, v0: np.ndarray, buckled: np.ndarray, ok: np.ndarray):
    """The boundary v₀(ΔF) read off a map: per ΔF, the geometric mean of the largest stable
    and the smallest buckled v₀, where the column is monotone (stable below, buckled above)
    and has both. `buckled`, `ok` of shape (len(dF), len(v0)).

    **Returns:** `(dF_b, v_b, lo, hi)` for the columns with a boundary.
    """
    out = []
    for i, f in enumerate(dF):
        b, good = buckled[i], ok[i]
        if not good.all() or b.all() or not b.any():
            continue
        first = int(np.argmax(b))
        if not b[first:].all():  # not monotone: no single boundary
            continue
        lo, hi = v0[first - 1], v0[first]
        out.append((f, math.sqrt(lo * hi), lo, hi))
    if not out:
        return (np.array([]),) * 4
    return tuple(np.array(c) for c in zip(*out))


def fit_power_law(x: np.ndarray, y: np.ndarray):
    """Least-squares fit of log y = log c + p log x (`numpy.polyfit`).

    **Returns:** `(p, p_stderr, c)`; the standard error is `nan` with fewer than 3 points.
    """
    lx, ly = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    if len(lx) < 2:
        return math.nan, math.nan, math.nan
    if len(lx) == 2:
        (p, logc), se = np.polyfit(lx, ly, 1), math.nan
    else:
        (p, logc), cov = np.polyfit(lx, ly, 1, cov=True)
        se = math.sqrt(cov[0, 0])
    return float(p), float(se), float(math.exp(logc))


def theory_boundary(rod: RodChannel, dF: np.ndarray, mode: int = 6) -> np.ndarray:
    """Single-mode theory (P6): v_cr = R f/√|k_m| [m/s] at F = F⁰_m* + ΔF."""
    import jax.numpy as jnp

    F0 = theory.reference_load(rod)
    k = theory.stiffness(rod, mode, F0 + jnp.asarray(dF))
    return np.asarray(rod.R * theory.velocity_intercept(k, theory.friction_amplitude(rod)))


def stability_map(
    mus=(0.3, 0.0),
    dF=np.geomspace(0.5, 64.0, 16),
    v0=np.geomspace(1e-3, 0.2, 16),
    model: str = "field",
    n: int | None = None,
    mode: int = 6,
    out: str | None = "out/map",
    progress: bool = True,
    t1: float | None = None,
    curve_rtol: float | None = 1e-3,
    chunk_size: int | None = None,
    fill: str | None = None,
) -> dict:
    """Classify the reference rod straight/buckled over the grid `dF` × `v0` for every μ in
    `mus` (sine mode-`mode` velocity perturbation), fit the boundary, and write `map.png`,
    `map.csv`, `map.json` and one resumable sweep folder per μ under `out`; each run to `t1` [s]
    (default: the model's `search_horizon`, 2 s, the 3D rod 0.4 s). For μ > 0 and the
    field or Galerkin model the boundary is also searched directly at every load of the grid
    ([`jaxrod.boundary.boundary_curve`][] at the map's n and dt, to `curve_rtol`; `None`: not)
    and drawn over the grid.

    Under `jax.distributed` each process runs its share of every map's chunks of `chunk_size`
    members ([`jaxrod.sweep`][]; default: the whole map in one chunk, up to 1024 members), all of
    them return the same summary, and process 0 alone writes the files and shows progress (the
    searched boundary is not split: every process searches it alike).

    `fill`: `"grid"` runs every cell; `"search"` finds each column's boundary by bisection over
    the grid's amplitudes and labels the cells it did not run from it ([`jaxrod.map_columns`][]:
    right where every column is monotone; map.csv's `ran` says which cells ran), each column
    starting from the boundary of the model's `map_guide` where it has one (the 3D rod: the field
    model's map, searched, under `out`/`sweep_mu<μ>_field`); default: the model's (`map_fill`: the
    3D rod searches, the others fill the grid).

    **Returns:** the summary (per μ: boundary points, fitted exponent ± standard error, the
    largest stable ΔF/F⁰_cr seen, counts), also written to `map.json`.
    """
    import jax

    main = jax.process_index() == 0
    progress = progress and main
    if t1 is None:  # the horizon a boundary search of this model runs to (2 s; the 3D rod 0.4 s)
        t1 = recipe(model).search_horizon
    fill = recipe(model).map_fill if fill is None else fill
    if fill not in ("grid", "search"):
        raise ValueError(f"fill = {fill!r} is invalid: expected 'grid' or 'search'.")
    dF = np.asarray(dF, float)
    v0 = np.asarray(v0, float)
    results = {}
    summary = {"model": name_of(model), "mode": mode, "t1": t1, "dF": dF.tolist(), "v0": v0.tolist(), "maps": {}}
    for mu in mus:
        path = None if out is None else os.path.join(out, f"sweep_mu{mu:g}")
        res = _map_sweep(float(mu), dF, v0, model, n, mode, t1, path, progress, chunk_size, fill)
        results[mu] = res
        summary["maps"][f"{mu:g}"] = _summarise(res, dF, v0, float(mu))
        if curve_rtol is not None and mu > 0 and recipe(model).search_method == "departure":
            summary["maps"][f"{mu:g}"].update(_searched(res, dF, float(mu), model, mode, t1, curve_rtol, progress))
    summary["n"] = results[mus[0]].meta["n"]
    summary["dt"] = results[mus[0]].meta["dt"]
    summary["schemes"] = results[mus[0]].meta["schemes"]
    if fill == "search":
        summary["fill"] = {"method": "search", "runs": {f"{mu:g}": int(r.outputs["ran"].sum()) for mu, r in results.items()},
                           "cells": {f"{mu:g}": len(r) for mu, r in results.items()}}
    if out is not None and main:
        os.makedirs(out, exist_ok=True)
        write_csv(os.path.join(out, "map.csv"), _map_rows(results))
        with open(os.path.join(out, "map.json"), "w") as fh:
            json.dump(summary, fh, indent=1)
        plot_maps(results, summary, os.path.join(out, "map.png"))
    return summary


def _map_sweep(mu, dF, v0, model, n, mode, t1, path, progress, chunk_size, fill="grid") -> SweepResult:
    """The map's sweep at one μ: one sweep per run of columns that the model runs with one scheme
    (`scheme_under` the sine perturbation at the column's load: the 3D rod's columns past the
    wall's wrinkling load run the explicit leapfrog, the others its implicit step), at one size
    (the model's default at the map's largest load), joined in column order; the later groups'
    folders are `path` + `_dF<first load>`. `meta["schemes"]`: each group's first and last load
    [N], scheme and step [s]."""
    cls = recipe(model)
    rod = RodChannel.reference(mu=mu)
    F0 = float(theory.reference_load(rod))
    pert = make_perturbation("sine", 1.0, mode)
    keys = [cls.scheme_under(pert, cls.build(rod, F0 + x, cls.min_size, mode)) for x in dF]  # a small probe per load
    starts = [j for j in range(len(dF)) if j == 0 or keys[j] != keys[j - 1]]
    if len(starts) > 1 and n is None:
        n = cls.default_size(rod, F0 + float(dF.max()), pert)
    guess = None
    if fill == "search" and cls.map_guide is not None:
        guess = _guess(cls.map_guide, mu, dF, v0, mode, None if path is None else f"{path}_{cls.map_guide}", progress,
                       chunk_size)
    parts, groups = [], []
    for a, b in zip(starts, starts[1:] + [len(dF)]):
        spec = SweepSpec(model=model, perturbation="sine", mode=mode, n=n, t1=t1)
        where = path if (a == 0 or path is None) else f"{path}_dF{dF[a]:g}"
        if fill == "search":  # μ as an input: the maps at every μ share one compiled program per scheme
            part = search_columns(spec, dF[a:b], v0, guess=None if guess is None else guess[a:b], fixed={"mu": mu},
                                  path=where, progress=progress, chunk_size=chunk_size)
        else:
            part = sweep(dataclasses.replace(spec, mu=mu), {"dF": dF[a:b], "amplitude": v0}, path=where,
                         progress=progress, chunk_size=chunk_size)
        parts.append(part)
        groups.append({"dF_first": float(dF[a]), "dF_last": float(dF[b - 1]), "scheme": part.meta["scheme"],
                       "dt": part.meta["dt"]})
    res = parts[0] if len(parts) == 1 else _join_columns(parts, (len(dF), len(v0)))
    res.meta["schemes"] = groups
    return res


def _guess(guide, mu, dF, v0, mode, path, progress, chunk_size) -> np.ndarray:
    """Per column of the grid, the first buckled cell (len(v0): none) of the `guide` model's map
    (a recipe's `map_guide`), its columns searched, at its default size and horizon: where a
    costlier model's column search starts (the 3D rod's E3 boundary lies near the field model's:
    docs/rod3d.md)."""
    if progress:
        print(f"  mu = {mu:g}: the {guide} model's map first, to start each column's search", flush=True)
    spec = SweepSpec(model=guide, perturbation="sine", mode=mode, t1=recipe(guide).search_horizon)
    b = search_columns(spec, dF, v0, fixed={"mu": mu}, path=path, progress=progress, chunk_size=chunk_size).grid("buckled")
    return np.where(b.any(axis=1), b.argmax(axis=1), len(v0))


def _join_columns(parts, shape) -> SweepResult:
    """The sweeps of consecutive column groups of one (ΔF × v₀) grid as one result: members in
    grid order, indexed as one sweep's."""
    inputs = {k: np.concatenate([p.inputs[k] for p in parts]) for k in parts[0].inputs}
    inputs["index"] = np.arange(len(inputs["index"]))
    outputs = {k: np.concatenate([p.outputs[k] for p in parts]) for k in parts[0].outputs}
    return SweepResult(inputs, outputs, shape, parts[0].names, {**parts[0].meta, "shape": list(shape)})


def _summarise(res: SweepResult, dF, v0, mu) -> dict:
    rod = RodChannel.reference(mu=mu)
    F0cr = float(theory.critical_load_continuous(rod))
    b = res.grid("buckled")
    ok = res.grid("result") == 0
    dF_b, v_b, lo, hi = grid_boundary(dF, v0, b, ok)
    p, se, c = fit_power_law(dF_b, v_b) if len(dF_b) >= 2 else (math.nan, math.nan, math.nan)
    stable = (~b) & ok
    cols_stable = stable.any(axis=1)
    largest = float(dF[cols_stable].max() / F0cr) if cols_stable.any() else None
    buckles_every_positive = bool(b[dF > 0].all(axis=None)) if (dF > 0).any() else None
    return {
        "mu": mu,
        "members": len(res),
        "buckled": int((b & ok).sum()),
        "stable": int(stable.sum()),
        "failed": int((~ok).sum()),
        "boundary_dF": dF_b.tolist(),
        "boundary_v0": v_b.tolist(),
        "boundary_v0_lo": np.asarray(lo).tolist(),
        "boundary_v0_hi": np.asarray(hi).tolist(),
        "exponent": p,
        "exponent_stderr": se,
        "prefactor": c,
        "largest_stable_dF_over_F0cr": largest,
        "buckles_for_every_dF_gt_0": buckles_every_positive,
        "F0cr_continuous": F0cr,
    }


def _searched(res: SweepResult, dF, mu, model, mode, t1, rtol, progress) -> dict:
    """The boundary searched at every load of the map, at the map's resolution."""
    from .boundary import boundary_curve

    rod = RodChannel.reference(mu=mu)
    r, _ = boundary_curve(rod, dF, model=model, n=res.meta["n"], dt=res.meta["dt"], mode=mode, bracket=(1e-5, 2.0),
                          rtol=rtol, t1=t1, sensitivities=(), progress=progress)
    ok = np.asarray(r.result) == 0
    v = np.asarray(r.root)
    p, se, _ = fit_power_law(dF[ok], v[ok]) if ok.sum() >= 2 else (math.nan, math.nan, math.nan)
    return {"curve_rtol": rtol, "curve_v0": [float(x) if o else None for x, o in zip(v, ok)],
            "curve_evaluations": np.asarray(r.evaluations).tolist(), "curve_exponent": p,
            "curve_exponent_stderr": se}


def _map_rows(results: dict) -> list[dict]:
    """One row per member of every μ's map: plain numbers (μ, ΔF [N], v₀ [m/s], labels, times
    [s], amplitudes [rad], result code)."""
    rows = []
    for mu, res in results.items():
        o, i = res.outputs, res.inputs
        for k in range(len(res)):
            rows.append(dict(mu=mu, dF=i["dF"][k], v0=i["amplitude"][k], buckled=o["buckled"][k],
                             t_buckle=o["t_buckle"][k], dominant_mode=o["dominant_mode"][k],
                             max_theta=o["max_theta"][k], stuck=o["stuck"][k], t_stop=o["t_stop"][k],
                             result=o["result"][k], **({"ran": o["ran"][k]} if "ran" in o else {})))
    return rows


# the figure's styling (sizes, widths, fonts, legend place) is reviewed on the figure: the
# `pragma: no mutate` lines hold only styling, so that mutation testing (tools/mutants.py)
# mutates what the figure shows (its data, labels and scales), which the tests check
_FIT_STYLE = {"ls": "-", "color": "tab:blue", "lw": 1.5}  # pragma: no mutate
_CURVE_STYLE = {"ls": "-", "color": "tab:purple", "lw": 2, "alpha": 0.8}  # pragma: no mutate


def plot_maps(results: dict, summary: dict, path: str | None = None):
    """One panel per μ: stable (circles) / buckled (crosses), P6 theory, fitted boundary.
    **Returns:** the `matplotlib.figure.Figure`; also written as a PNG to `path` when given."""

    mus = list(results)
    size = (6.2 * len(mus), 5.0)  # pragma: no mutate
    fig, axes = subplots(1, len(mus), figsize=size, squeeze=False)
    dF = np.asarray(summary["dF"])
    v0 = np.asarray(summary["v0"])
    fine = np.geomspace(dF.min(), dF.max(), 200)
    for ax, mu in zip(axes[0], mus):
        res = results[mu]
        s = summary["maps"][f"{mu:g}"]
        b = res.outputs["buckled"]
        ok = res.outputs["result"] == 0
        x, y = res.inputs["dF"], 1e3 * res.inputs["amplitude"]
        ax.scatter(x[~b & ok], y[~b & ok], s=22, facecolors="none", edgecolors="tab:green", label="stable (straight)")
        ax.scatter(x[b & ok], y[b & ok], s=22, marker="x", c="tab:red", label="buckled")
        if (~ok).any():
            ax.scatter(x[~ok], y[~ok], s=22, marker="s", c="k", label="failed run")
        if mu > 0:
            th = 1e3 * theory_boundary(RodChannel.reference(mu=mu), fine, summary["mode"])
            ax.plot(fine, th, "k--", lw=1.2, label="single-mode theory P6 (slope −1/2)")
            if len(s["boundary_dF"]) >= 2 and np.isfinite(s["exponent"]):
                fit = s["prefactor"] * fine ** s["exponent"]
                ax.plot(fine, 1e3 * fit, label=f"fitted boundary: v0 ∝ ΔF^({s['exponent']:.3f} ± {s['exponent_stderr']:.3f})",
                        **_FIT_STYLE)
                ax.plot(s["boundary_dF"], 1e3 * np.asarray(s["boundary_v0"]), "o", color="tab:blue", ms=3)
            if "curve_v0" in s:
                cv = np.array([np.nan if x is None else x for x in s["curve_v0"]])
                ax.plot(dF, 1e3 * cv, label=f"searched boundary (rtol {s['curve_rtol']:g}): v0* ∝ ΔF^({s['curve_exponent']:.3f})",
                        **_CURVE_STYLE)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(dF.min() / 1.15, dF.max() * 1.15)
        ax.set_ylim(1e3 * v0.min() / 1.2, 1e3 * v0.max() * 1.2)
        ax.set_xlabel("ΔF = F − F⁰₆ [N]")
        ax.set_ylabel("v₀ (sine mode-6 lateral speed) [mm/s]")
        title = f"μ = {mu:g}: {s['buckled']} buckled, {s['stable']} stable"
        if s["largest_stable_dF_over_F0cr"] is not None:
            title += f"\nstraight up to ΔF = {s['largest_stable_dF_over_F0cr']:.1f} F⁰cr"
        ax.set_title(title, fontsize=10)  # pragma: no mutate
        ax.legend(fontsize=8, loc="lower left")  # pragma: no mutate
    groups = summary.get("schemes") or [{"dt": summary["dt"]}]
    steps = f"dt = {groups[0]['dt']:.2e} s" + "".join(
        f", {g['scheme']} at {g['dt']:.2e} s from ΔF = {g['dF_first']:g} N" for g in groups[1:])
    fig.suptitle(f"Stability map, reference rod, {summary['model']} model (n = {summary['n']}, "
                 f"{steps}, horizon {summary['t1']:g} s)",
                 fontsize=11)  # pragma: no mutate
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=130)
    return fig
