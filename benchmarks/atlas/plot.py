"""The failure atlas figure: two panels per entry (one for `steplimit`, `float32` and
`broadband`), drawn from the data each entry returns."""

from __future__ import annotations

import jax
import numpy as np


def plot(outs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 3, figsize=(16, 18))
    ax = iter(axes.ravel())
    if "chatter" in outs:
        o = outs["chatter"]
        a1 = next(ax)
        for (name, dt), (ts, v) in o["traces"].items():
            if dt == 1e-4:
                a1.plot(1e3 * ts, v, lw=0.6, label=f"{name}, dt = {dt:g} s")
        a1.axvline(1e3 * o["t_stick"], color="k", ls=":", lw=1, label="exact stick")
        a1.set_xlim(1e3 * o["t_stick"] - 5, 1e3 * o["t_stick"] + 15)
        a1.set_ylim(-0.3, 0.3)
        a1.set(xlabel="t [ms]", ylabel="Ȧ [rad/s]", title="1. explicit sgn: chatter after the stick")
        a1.legend(fontsize=7)
        a2 = next(ax)
        ts, cls = o["cls"]
        for name, w in cls.items():
            a2.plot(ts[1:], 100 * w[1:], "o-", label=name)
        a2.set(xlabel="horizon [s]", ylabel="labels ≠ exact [%]", title="1. false classification vs horizon (dt = 1e-4 s)")
        a2.legend(fontsize=7)
    if "creep" in outs:
        o = outs["creep"]
        a3 = next(ax)
        for eps, (ts, d) in o["curves"].items():
            ok = np.isfinite(d) & (d > 0)
            a3.loglog(ts[ok], np.minimum(d[ok], 1e3), label=f"ε' = {eps:g}")
        a3.axhline(1.5, color="k", ls=":", lw=1)
        a3.set(xlabel="t [s]", ylabel="|A − A₀| / a", title="2. tanh creep from the stick line (Kvaerno5)")
        a3.legend(fontsize=7)
        a4 = next(ax)
        epss, vs = o["vs"]
        for H, r in vs.items():
            a4.loglog(epss, np.maximum(np.abs(np.asarray(r) - 1), 1e-12), "o-", label=f"λT = {H:g}")
        a4.set(xlabel="ε' = ε / Ȧ_cr", ylabel="|v₀*/P6 − 1|", title="2. tanh boundary error vs ε and horizon")
        a4.legend(fontsize=7)
    if "gradient" in outs:
        o = outs["gradient"]
        a5 = next(ax)
        x, d_ex = o["exact"]
        for k in [k for k in o if k != "exact"]:
            xx, g, fd = o[k]
            if k in (0.1, 1.0, 3.0, 4.5, 5.0, 10.0, 30.0):
                a5.plot(xx, np.clip(g / d_ex, -4, 6), ".-", lw=0.8, label=f"jax.grad, h·f/ε = {k:g}")
        a5.axhline(1.0, color="k", lw=2, label="exact (sharp law)")
        a5.set_ylim(-4.2, 6.2)
        a5.set(xlabel="Ȧ₀ / Ȧ_cr", ylabel="grad / exact derivative (clipped to [−4, 6])",
               title="3. gradients of explicit tanh steps")
        a5.legend(fontsize=6)
        a6 = next(ax)
        ks = sorted(k for k in o if k != "exact")
        rel = []
        for k in ks:
            xx, g, fd = o[k]
            rel.append(np.max(np.abs(g - fd) / np.maximum(np.abs(fd), 1e-300)))
        a6.loglog(ks, np.maximum(rel, 1e-16), "o-", label="max |grad − FD| / |FD|")
        rel_ex = [np.max(np.abs(o[k][1] - d_ex) / np.abs(d_ex)) for k in ks]
        a6.loglog(ks, np.maximum(rel_ex, 1e-16), "s-", label="max |grad − exact sharp-law derivative| / |exact|")
        a6.axvline(4, color="k", ls=":", lw=1)
        a6.set(xlabel="h·f/ε", ylabel="relative", title="3. gradient error vs h·f/ε")
        a6.legend(fontsize=7)
    if "split" in outs:
        o = outs["split"]
        a7 = next(ax)
        for dF, (ts, d) in o["curves"].items():
            ok = d > 0
            a7.loglog(ts[ok], d[ok], label=f"split, ΔF = {dF:g} N")
        a7.axhline(1.5, color="k", ls=":", lw=1)
        a7.set(xlabel="t [s]", ylabel="|A − A₀| / a", title="4. SplitLinearFriction: stuck state creeps (Verlet: 0)")
        a7.legend(fontsize=7)
        a8 = next(ax)
        for dF, ts, pv, sp in o["fields"]:
            a8.semilogy(ts, pv, "-", label=f"ProjectedVerlet, ΔF = {dF:g} N")
            a8.semilogy(ts, sp, "--", label=f"SplitLinearFriction, ΔF = {dF:g} N")
        a8.set(xlabel="t [s]", ylabel="max|θ| [rad]", title="4. field n = 63, half the critical sine velocity")
        a8.legend(fontsize=7)
    if "steplimit" in outs:
        o = outs["steplimit"]
        a9 = next(ax)
        for key in [k for k in o if k != "limit"]:
            amp = o[key]
            a9.semilogy(np.where(np.isfinite(amp) & (amp < 1e250), amp, np.nan),
                        "--" if key[1] == 0 else "-", label=f"dt = {key[0]:g}·limit, μ = {key[1]:g}")
        a9.set_ylim(1e-4, 1e250)
        a9.set(xlabel="step", ylabel="max|θ| [rad]", title="5. raw Verlet loop past 2/ω_max (field n = 63)")
        a9.legend(fontsize=7)
    if "float32" in outs:
        o = outs["float32"]
        a10 = next(ax)
        same = o["l64"] == o["l32"]
        a10.scatter(o["dF"][same & o["l64"]], 1e3 * o["v0"][same & o["l64"]], c="C3", s=14, label="buckled (both)")
        a10.scatter(o["dF"][same & ~o["l64"]], 1e3 * o["v0"][same & ~o["l64"]], c="C0", s=14, label="straight (both)")
        a10.scatter(o["dF"][~same], 1e3 * o["v0"][~same], c="k", marker="x", s=60, label="float32 ≠ float64")
        a10.set_yscale("log")
        a10.set(xlabel="ΔF [N]", ylabel="v₀ [mm/s]", title="6. float32 vs float64 map labels (field n = 63)")
        a10.legend(fontsize=7)
    if "broadband" in outs:
        rows = outs["broadband"]["rows"]
        a11 = next(ax)
        rb = [r for r in rows if r["perturbation"].startswith("random")]
        i = np.arange(len(rb))
        a11.bar(i - 0.25, [r["field_dF_crit"] for r in rb], 0.25, label="field model ΔF*")
        a11.bar(i, [r["single_mode6_dF_crit"] for r in rb], 0.25, label="single mode 6 (projected)")
        a11.bar(i + 0.25, [r["min_over_modes_dF_crit"] for r in rb], 0.25, label="min of P7 over modes")
        a11.set_yscale("log")
        a11.set(xlabel="realization", ylabel="ΔF* [N]", title="7. random velocity ±15 mm/s, μ = 0.3")
        a11.legend(fontsize=7)
    for a in ax:
        a.axis("off")
    fig.suptitle(f"jaxrod failure atlas — reference rod, μ = 0.3, {jax.devices()[0].platform}, jax {jax.__version__}")
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")
