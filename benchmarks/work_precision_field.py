"""Work–precision diagram of the field model: error against wall time for every way jaxrod
can integrate it (the single-mode model: `work_precision_single.py`).

Field model (P1), reference rod, μ = 0.3, ΔF = 5 N, sine mode-6 lateral velocity:

    - critical sine velocity v₀* found by bisection on the buckled label (runs of T1 = 0.5 s,
      stop when buckled (max|θ| ≥ 0.5 rad) or stuck), against a converged reference
      (projected Verlet, n = 511, dt = 0.2 of the step limit);
    - final shape θ(s, 0.2 s) after a 20 mm/s sine perturbation (below v₀*, so the rod stays
      straight-ish and sticks), against the same reference; n + 1 divides 512 so coarse nodes
      coincide with reference nodes.

    Methods: projected Verlet with the Coulomb law at n = 31…255 and dt = 0.8, 0.4, 0.1 of the
    step limit 2/ω_max; explicit Verlet on the tanh law (`ProjectedVerlet(dt, Tanh(ε))`, dt
    also bounded by ε/f, i.e. h·f/ε ≤ 1); `DiffraxSmooth` (Tsit5; Kvaerno5 for the shape only:
    its bisection costs minutes); `SplitLinearFriction` (the creeping splitting).

Times: the first call (compile + run) and the minimum over repeats of
`jax.block_until_ready(f(x))` after it, float64, on whatever `jax.devices()[0]` is.

    python benchmarks/work_precision_field.py [--quick] [--replot]

Writes benchmarks/results/work_precision_field.{csv,png} (the `--quick` run writes
`work_precision_field_quick.*` instead); `--replot` redraws the figure from the CSV.
"""

from __future__ import annotations

import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import diffrax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.boundary.roots import bisection  # noqa: E402

from _common import RESULTS as OUT, run_or_replot, load_rows, timed, write_csv  # noqa: E402

DF = 5.0  # N above F0_6
ROD = jr.RodChannel.reference(mu=0.3)
T1 = 0.5  # s, horizon of the buckled label (the package's boundary-search default)
T_SHAPE = 0.2  # s
V_SHAPE = 0.020  # m/s, sine mode-6 amplitude for the shape comparison
BRACKET = (1e-3, 0.2)  # m/s


def _limit(n):
    return 2.0 / float(jr.FieldModel.from_rod(ROD, n, dF=0.0).max_frequency())


def field_vcrit(n, integ, n_iter, repeats):
    """v₀* [m/s] by bisection on the buckled label; nan if the lower bracket end buckles."""
    model = jr.FieldModel.from_rod(ROD, n, dF=DF)
    opts = jr.RunOptions(save_state=False)

    def buckles(v0):
        q0, w0 = jr.SineVelocity(v0, 6).initial_state(model)
        return jr.simulate(model, integ, q0, w0, T1, n_save=3, options=opts, throw=False).buckled

    f = jax.jit(lambda lo, hi: bisection(buckles, lo, hi, rtol=0.0, max_iter=n_iter))
    lab = jax.jit(jax.vmap(buckles))(jnp.asarray(BRACKET))
    r, first, best = timed(f, *BRACKET, repeats=repeats)
    lo, hi = r.lo, r.hi
    if bool(lab[0]) or not bool(lab[1]):
        return float("nan"), first, best, f"bracket labels {np.asarray(lab).tolist()}"
    return float(jnp.sqrt(lo * hi)), first, best, ""


def field_shape(n, integ, repeats):
    model = jr.FieldModel.from_rod(ROD, n, dF=DF)

    def run():
        q0, w0 = jr.SineVelocity(V_SHAPE, 6).initial_state(model)
        sol = jr.simulate(model, integ, q0, w0, T_SHAPE, n_save=11, throw=False,
                          options=jr.RunOptions(save_state=False))
        return sol.q_final, sol.result, sol.buckled

    (q, res, b), first, best = timed(jax.jit(run), repeats=repeats)
    return np.asarray(q), int(res), bool(b), first, best


def run_field(quick: bool, info: dict):
    n_ref = 127 if quick else 511
    frac_ref = 0.4 if quick else 0.2
    n_iter = 22 if quick else 30
    reps = 1 if quick else 2
    f_node = float(0.3 * ROD.N / (ROD.rho * ROD.R))  # friction bound per node [rad/s²]
    mode = jr.SingleMode.from_rod(ROD, dF=DF)
    v_theory = float(ROD.R * jr.theory.velocity_intercept(mode.k, mode.f_d))  # m/s
    w_scale = v_theory / float(ROD.R)  # rad/s: ε' = ε / w_scale
    base = dict(info, batch=1, dF=DF, T1=T1)
    print(f"\n(b) field model, ΔF = {DF} N, μ = 0.3, sine mode 6, horizon {T1} s, batch 1, "
          f"{info['dtype']}, {info['device']}; friction bound per node f = {f_node:.1f} rad/s², "
          f"ε' = ε/(v_cr,P6/R), v_cr,P6/R = {w_scale:.3f} rad/s")

    t0 = time.perf_counter()
    L = _limit(n_ref)
    ref_int = jr.ProjectedVerlet(frac_ref * L)
    v_ref, first, best, note = field_vcrit(n_ref, ref_int, n_iter, 0)
    q_ref, _, _, _, _ = field_shape(n_ref, ref_int, 0)
    print(f"  reference n = {n_ref}, dt = {frac_ref} of the limit: v0* = {1e3 * v_ref:.4f} mm/s "
          f"(P6: {1e3 * v_theory:.4f}); {time.perf_counter() - t0:.1f} s")
    rows = [dict(base, method="reference (projected Verlet, Coulomb)", law="Coulomb", n=n_ref,
                 dt=frac_ref * L, dt_over_limit=frac_ref, v0_crit=v_ref, v0_ref=v_ref,
                 v0_theory=v_theory, v0_rel_error=0.0, shape_rel_error=0.0, first_call_s=first,
                 vcrit_run_s=best)]

    def shape_err(q, n):
        idx = (np.arange(1, n + 1) * (n_ref + 1)) // (n + 1) - 1
        return float(np.max(np.abs(q - q_ref[idx])) / np.max(np.abs(q_ref)))

    def one(method, law, n, integ, dt, frac, eps=None, do_vcrit=True, do_shape=True):
        row = dict(base, method=method, law=law, n=n, dt=dt, dt_over_limit=frac)
        if eps is not None:
            row.update(eps=eps, eps_rel=eps / w_scale, h_f_over_eps=dt * f_node / eps)
        if do_vcrit:
            v, first, best, note = field_vcrit(n, integ, n_iter, reps)
            row.update(v0_crit=v, v0_ref=v_ref, v0_theory=v_theory,
                       v0_rel_error=abs(v / v_ref - 1) if np.isfinite(v) else float("nan"),
                       first_call_s=first, vcrit_run_s=best, note=note)
        if do_shape:
            q, res, buck, first_s, best_s = field_shape(n, integ, reps)
            row.update(shape_rel_error=shape_err(q, n) if not buck else float("nan"),
                       shape_buckled=buck, shape_result=res, shape_first_call_s=first_s, shape_run_s=best_s)
        rows.append(row)
        msg = f"  {method:34s} n={n:4d} dt={dt:.2e} ({frac:.2f} lim)"
        if eps is not None:
            msg += f" ε'={eps / w_scale:.0e} hf/ε={dt * f_node / eps:.2f}"
        if do_vcrit:
            msg += (f"  v0*={1e3 * row['v0_crit']:8.4f} mm/s err={row['v0_rel_error']:8.2e} "
                    f"[{row['vcrit_run_s']:7.3f} s]{' ' + row['note'] if row['note'] else ''}")
        if do_shape:
            msg += (f"  shape err={row['shape_rel_error']:8.2e}{' (buckled)' if row['shape_buckled'] else ''} "
                    f"[{row['shape_run_s'] * 1e3:8.2f} ms]")
        print(msg, flush=True)

    ns = [31, 63] if quick else [31, 63, 127, 255]
    fracs = [0.4] if quick else [0.8, 0.4, 0.1]
    for n in ns:
        for frac in fracs:
            dt = frac * _limit(n)
            one("projected Verlet (Coulomb)", "Coulomb", n, jr.ProjectedVerlet(dt), dt, frac)
    tanh_ns = [31] if quick else [63, 127]
    for n in tanh_ns:
        for eps_rel in ([1e-1, 1e-2] if quick else [1e-1, 1e-2, 1e-3]):
            eps = eps_rel * w_scale
            dt = min(0.4 * _limit(n), eps / f_node)
            one("explicit Verlet (tanh)", "tanh", n, jr.ProjectedVerlet(dt, jr.Tanh(eps)), dt,
                dt / _limit(n), eps=eps)
    for n in ([31] if quick else [31, 63]):
        eps = 1e-2 * w_scale
        integ = jr.DiffraxSmooth(jr.Tanh(eps), diffrax.Tsit5(), rtol=1e-6, atol=1e-8, max_steps=200_000)
        one("DiffraxSmooth Tsit5 (tanh, rtol 1e-6)", "tanh", n, integ, float("nan"), float("nan"), eps=eps)
    if not quick:
        eps = 1e-2 * w_scale
        integ = jr.DiffraxSmooth(jr.Tanh(eps), diffrax.Kvaerno5(), rtol=1e-6, atol=1e-8, max_steps=200_000)
        one("DiffraxSmooth Kvaerno5 (tanh, rtol 1e-6)", "tanh", 31, integ, float("nan"), float("nan"),
            eps=eps, do_vcrit=False)
    for n in ([63] if quick else [63, 127]):
        for frac in ([0.4] if quick else [0.4, 0.1]):
            dt = frac * _limit(n)
            one("SplitLinearFriction (Coulomb)", "Coulomb", n, jr.SplitLinearFriction(dt), dt, frac)
    for r in rows:  # diffrax rows: dt is adaptive
        if "h_f_over_eps" in r and not np.isfinite(r.get("dt", 0.0)):
            r["h_f_over_eps"] = float("nan")

    tag = "_quick" if quick else ""
    write_csv(os.path.join(OUT, f"work_precision_field{tag}.csv"), rows, verbose=True)
    plot_field(rows, info, n_ref, os.path.join(OUT, f"work_precision_field{tag}.png"))
    return rows


def plot_field(rows, info, n_ref, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(14, 6))
    groups = {}
    for r in rows[1:]:
        key = r["method"] if "eps_rel" not in r else f"{r['method']}, ε'={r['eps_rel']:.0e}"
        if r["method"].startswith("projected") or r["method"].startswith("Split"):
            key = f"{r['method']}, dt = {r['dt_over_limit']:.1f} lim"
        groups.setdefault(key, []).append(r)
    markers = "os^vD<>ph*"
    for ax, (col, tcol, title) in zip(axes, (
            ("v0_rel_error", "vcrit_run_s", f"critical sine velocity (bisection, T1 = {T1} s)"),
            ("shape_rel_error", "shape_run_s", f"shape θ(s, {T_SHAPE} s) after {V_SHAPE * 1e3:.0f} mm/s"))):
        for i, (key, rs) in enumerate(groups.items()):
            rs = [r for r in rs if col in r and np.isfinite(r.get(col, np.nan)) and r[col] > 0]
            if not rs:
                continue
            rs = sorted(rs, key=lambda r: r["n"])
            ax.plot([r[tcol] for r in rs], [r[col] for r in rs], markers[i % len(markers)] + "-",
                    color=f"C{i % 10}", label=key + " (n = " + ",".join(str(r["n"]) for r in rs) + ")")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time [s] (min over repeats, after compilation)")
        ax.set_ylabel("relative error vs. reference")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6.5)
    fig.suptitle(f"field model, ΔF = {DF} N, μ = 0.3, reference n = {n_ref} — batch 1, "
                 f"{info['dtype']}, {info['device']}, jax {info['jax']} (shared machine: timings are noisy)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print(f"wrote {path}")


def replot(quick):
    p = os.path.join(OUT, f"work_precision_field{'_quick' if quick else ''}.csv")
    if os.path.exists(p):
        rows = load_rows(p)
        info = {k: rows[0][k] for k in ("device", "jax", "dtype")}
        plot_field(rows, info, int(rows[0]["n"]), p[:-4] + ".png")


def main():
    run_or_replot(__doc__.split("\n")[0], run_field, replot)


if __name__ == "__main__":
    main()
