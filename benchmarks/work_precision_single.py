"""Work–precision diagram of the single-mode model: error against wall time for every way
jaxrod can integrate it (the field model: `work_precision_field.py`).

Single-mode model (P4), reference rod at ΔF = 5 N above F⁰₆, a batch of members with
    μ spread over [0.1, 1] (λ = √|k| does not depend on μ, so every member has the same time
    scale and the same static horizon):

    - trajectory error: max over the batch and over 11 save times in [0, 5/λ] of
      |A − A_exact|/a (a = f/|k|, the half-width of the stick line), against `jaxrod.Exact`;
      each member starts at A = 0 with Ȧ₀ = c·Ȧ_cr, c spread over [0.3, 0.95] (slips, then
      sticks);
    - critical-velocity error: max over the batch of |Ȧ₀* − Ȧ_cr|/Ȧ_cr against P6, Ȧ₀* the root
      of the indicator A(T)/a − 1 at T = 10/λ found by the package's safeguarded Newton
      iteration (`jaxrod.boundary.safeguarded_newton`, forward-mode derivatives through the
      integrator) from the bracket [Ȧ_cr/2.7, 3.6 Ȧ_cr].

    Methods: projected Verlet (Coulomb prox), symplectic Euler with the explicit sign law,
    the tanh law f·tanh(Ȧ/ε) through diffrax Tsit5 (explicit) and Kvaerno5 (implicit) at several
    tolerances (`DiffraxSmooth`), an event-driven diffrax reference (Tsit5 per slip phase with a
    root-found stop event, host-side stick test) and the exact solution. ε is given in units of
    Ȧ_cr = λa, so ε' = ε/Ȧ_cr is the same relative smoothing for every member.

Times: the first call (compile + run) and the minimum over repeats of
`jax.block_until_ready(f(x))` after it, float64, on whatever `jax.devices()[0]` is.

    python benchmarks/work_precision_single.py [--quick] [--replot]

Writes benchmarks/results/work_precision_single_mode.{csv,png} (the `--quick` run writes
`work_precision_single_mode_quick.*` instead); `--replot` redraws the figure from the CSV and
prints the summary.
"""

from __future__ import annotations

import math
import os

import jax

jax.config.update("jax_enable_x64", True)
import diffrax  # noqa: E402
import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import optimistix as optx  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.boundary import safeguarded_newton, single_mode_indicator  # noqa: E402

from _common import RESULTS as OUT, run_or_replot, load_rows, timed, write_csv  # noqa: E402

DF = 5.0  # N above F0_6
TARGET = 1e-6  # the critical-velocity target


def single_mode(mu):
    return jr.SingleMode.from_rod(jr.RodChannel.reference(mu=mu), dF=DF)


def _event_driven(A0, v0, k, f_s, f_d, ts, rtol, atol):
    """Event-driven reference (as tests/reference.py): Tsit5 within each slip phase, a diffrax
    Event root-finds Ȧ = 0, the stick test and the next direction are decided on the host."""
    A_out = np.full(ts.shape, np.nan)
    t, A, v, T = 0.0, float(A0), float(v0), float(ts[-1])
    while t < T:
        if v == 0.0:
            if abs(k * A) <= f_s:
                A_out[ts >= t] = A
                break
            sigma = -np.sign(k * A)
        else:
            sigma = np.sign(v)
        args = (jnp.asarray(k), jnp.asarray(float(sigma)), jnp.asarray(f_d))
        sol = _phase(jnp.asarray(t), jnp.asarray(T), jnp.array([A, v]), args, rtol, atol)
        t_end = float(sol.ts[-1])
        for i in np.flatnonzero((ts >= t) & (ts <= t_end)):
            A_out[i] = float(sol.evaluate(ts[i])[0])
        if t_end >= T and not bool(sol.event_mask):
            break
        t, A, v = t_end, float(sol.ys[-1][0]), 0.0
    return A_out


def _rhs(t, y, args):
    k, sigma, f_d = args
    return jnp.stack([y[1], -k * y[0] - sigma * f_d])


@eqx.filter_jit
def _phase(t0, t1, y0, args, rtol, atol):
    event = diffrax.Event(lambda t, y, args, **kw: args[1] * y[1],
                          optx.Newton(rtol=1e-11, atol=1e-13), direction=False)
    return diffrax.diffeqsolve(
        diffrax.ODETerm(_rhs), diffrax.Tsit5(), t0=t0, t1=t1, dt0=t1 * 1e-3, y0=y0, args=args,
        saveat=diffrax.SaveAt(t1=True, dense=True),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        event=event, max_steps=1_000_000,
    )


def run_single_mode(quick: bool, info: dict):
    B = 4 if quick else 8
    mus = jnp.linspace(0.1, 1.0, B)
    cs = jnp.linspace(0.3, 0.95, B)
    m0 = single_mode(0.3)
    lam = float(jnp.sqrt(-m0.k))
    T_traj, T_root = 5.0 / lam, 10.0 / lam
    n_save = 11
    reps = 2 if quick else 3
    base = dict(info, batch=B, dF=DF)
    rows = []
    print(f"\n(a) single mode, ΔF = {DF} N, λ = {lam:.2f} 1/s, batch {B} (μ ∈ [0.1, 1]), "
          f"{info['dtype']}, {info['device']}, jax {info['jax']}")

    # ---- exact reference trajectories
    def traj_of(integ_of, eps_arg=False):
        def one(mu, c, eps):
            md = single_mode(mu)
            vc = md.f_d / lam
            sol = jr.simulate(md, integ_of(eps * vc), 0.0, c * vc, T_traj, n_save=n_save, throw=False)
            return sol.q, sol.result
        return jax.jit(jax.vmap(one, (0, 0, None)))

    a = np.asarray(jax.vmap(lambda mu: single_mode(mu).f_d / (-single_mode(mu).k))(mus))
    exact = traj_of(lambda e: jr.Exact())
    (q_ex, res_ex), first, best = timed(exact, mus, cs, 0.0, repeats=reps)
    q_ex = np.asarray(q_ex)
    assert np.all(np.asarray(res_ex) == 0)

    def traj_err(q):
        return float(np.max(np.abs(np.asarray(q) - q_ex) / a[:, None]))

    rows.append(dict(base, part="trajectory", method="exact", solver="closed form", param="",
                     error=0.0, first_call_s=first, run_s=best, ok=True))
    print(f"  exact: {best * 1e3:.3f} ms (first call {first:.2f} s)")

    ldts = [0.1 / 2**i for i in (range(0, 10, 3) if quick else range(10))]
    for name, cls in (("projected Verlet", jr.ProjectedVerlet), ("symplectic Euler (sgn)", jr.SymplecticEuler)):
        for ldt in (ldts if name.startswith("proj") or not quick else ldts[::2]):
            f = traj_of(lambda e, ldt=ldt, cls=cls: cls(ldt / lam))
            (q, res), first, best = timed(f, mus, cs, 0.0, repeats=reps)
            err = traj_err(q)
            rows.append(dict(base, part="trajectory", method=name, solver="fixed step",
                             param=f"lambda*dt={ldt:.3g}", lam_dt=ldt, error=err, first_call_s=first,
                             run_s=best, ok=bool(np.all(np.asarray(res) == 0))))
            print(f"  {name:24s} λdt={ldt:8.2e}  err={err:9.2e}  {best * 1e3:9.3f} ms")

    epss = [1e-2, 1e-4] if quick else [1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
    rtols = [1e-6] if quick else [1e-4, 1e-6, 1e-8, 1e-10]
    solvers = {"Tsit5": diffrax.Tsit5(), "Kvaerno5": diffrax.Kvaerno5()}
    for sname, solver in solvers.items():
        for rt in rtols:
            # ε is a dynamic leaf: one compilation per (solver, rtol)
            f = traj_of(lambda e, solver=solver, rt=rt: jr.DiffraxSmooth(
                jr.Tanh(e), solver, rtol=rt, atol=rt * 1e-3, dt0=1e-5, max_steps=2_000_000))
            for eps in epss:
                (q, res), first, best = timed(f, mus, cs, eps, repeats=reps)
                ok = bool(np.all(np.asarray(res) == 0))
                err = traj_err(q) if ok else float("nan")
                rows.append(dict(base, part="trajectory", method=f"tanh + {sname}", solver=sname,
                                 param=f"eps'={eps:g}, rtol={rt:g}", eps_rel=eps, rtol=rt, error=err,
                                 first_call_s=first, run_s=best, ok=ok))
                print(f"  tanh {sname:8s} ε'={eps:7.0e} rtol={rt:7.0e}  err={err:9.2e}  "
                      f"{best * 1e3:9.3f} ms{'' if ok else '  (FAILED: ' + str(np.asarray(res)) + ')'}")

    ts = np.linspace(0.0, T_traj, n_save)
    ms = [single_mode(float(mu)) for mu in np.asarray(mus)]
    for rt in ([1e-8] if quick else [1e-6, 1e-8, 1e-10, 1e-12]):
        def ed(rt=rt):
            return np.stack([
                _event_driven(0.0, float(c) * float(m.f_d) / lam, float(m.k), float(m.f_s),
                              float(m.f_d), ts, rt, rt * 1e-3)
                for m, c in zip(ms, np.asarray(cs))])
        q, first, best = timed(ed, repeats=reps)
        err = traj_err(q)
        rows.append(dict(base, part="trajectory", method="event-driven diffrax", solver="Tsit5 + Event",
                         param=f"rtol={rt:g}", rtol=rt, error=err, first_call_s=first, run_s=best, ok=True))
        print(f"  event-driven rtol={rt:7.0e}  err={err:9.2e}  {best * 1e3:9.3f} ms (host loop)")

    # ---- critical velocity
    def root_of(integ_of, exact_indicator=False):
        def one(mu, eps):
            md = single_mode(mu)
            a_ = md.f_d / (-md.k)
            vc = md.f_d / lam

            def g(x):
                if exact_indicator:
                    return single_mode_indicator(x * vc, md.k, md.f_s, md.f_d, horizon=10.0)
                sol = jr.simulate(md, integ_of(eps * vc), 0.0, x * vc, T_root, n_save=2, throw=False)
                return sol.q_final / a_ - 1.0

            r = safeguarded_newton(g, 1 / 2.7, 3.6, rtol=1e-10, max_iter=40)
            return r.root, r.evaluations, r.result
        return jax.jit(jax.vmap(one, (0, None)))

    def record_root(out, first, best, **kw):
        root, ev, res = (np.asarray(x) for x in out)
        ok = bool(np.all(res == 0))
        err = float(np.max(np.abs(root - 1.0))) if ok else float("nan")
        row = dict(base, part="critical_velocity", error=err, first_call_s=first, run_s=best,
                   evaluations=float(np.mean(ev)), run_s_per_evaluation=best / float(np.mean(ev)), ok=ok, **kw)
        rows.append(row)
        return row

    out, first, best = timed(root_of(None, exact_indicator=True), mus, 0.0, repeats=reps)
    r = record_root(out, first, best, method="exact", solver="closed form", param="")
    print(f"  v0*: exact  err={r['error']:.2e}  {best * 1e3:.3f} ms  ({r['evaluations']:.1f} evaluations)")
    for ldt in ldts:
        out, first, best = timed(root_of(lambda e, ldt=ldt: jr.ProjectedVerlet(ldt / lam)), mus, 0.0, repeats=reps)
        r = record_root(out, first, best, method="projected Verlet", solver="fixed step",
                        param=f"lambda*dt={ldt:.3g}", lam_dt=ldt)
        print(f"  v0*: projected Verlet λdt={ldt:8.2e}  err={r['error']:9.2e}  {best * 1e3:9.3f} ms "
              f"({r['evaluations']:.1f} evaluations)")
    for sname, solver in solvers.items():
        for rt in rtols:
            f = root_of(lambda e, solver=solver, rt=rt: jr.DiffraxSmooth(
                jr.Tanh(e), solver, rtol=rt, atol=rt * 1e-3, dt0=1e-5, max_steps=2_000_000,
                adjoint=diffrax.ForwardMode()))
            for eps in epss:
                out, first, best = timed(f, mus, eps, repeats=reps)
                r = record_root(out, first, best, method=f"tanh + {sname}", solver=sname,
                                param=f"eps'={eps:g}, rtol={rt:g}", eps_rel=eps, rtol=rt)
                print(f"  v0*: tanh {sname:8s} ε'={eps:7.0e} rtol={rt:7.0e}  err={r['error']:9.2e}  "
                      f"{best * 1e3:9.3f} ms ({r['evaluations']:.1f} evaluations)")

    summary = single_mode_summary(rows)
    tag = "_quick" if quick else ""
    write_csv(os.path.join(OUT, f"work_precision_single_mode{tag}.csv"), rows, verbose=True)
    plot_single_mode(rows, summary, info, B, os.path.join(OUT, f"work_precision_single_mode{tag}.png"))
    return rows, summary


def pareto_cost_at(rs, target):
    """Wall time at which a family of configurations reaches `target` error: log–log
    interpolation along its Pareto front (time ascending, error descending); nan if never."""
    pts = sorted((r["run_s"], r["error"]) for r in rs if np.isfinite(r["error"]))
    front, best = [], math.inf
    for t, e in pts:
        if e < best:
            front.append((t, e))
            best = e
    if not front or front[-1][1] > target:
        return float("nan")
    if front[0][1] <= target:
        return front[0][0]
    for (t1, e1), (t2, e2) in zip(front, front[1:]):
        if e1 > target >= e2:
            w = (math.log(e1) - math.log(target)) / (math.log(e1) - math.log(max(e2, 1e-300)))
            return math.exp(math.log(t1) + w * (math.log(t2) - math.log(t1)))
    return float("nan")


def single_mode_summary(rows):
    crit = [r for r in rows if r["part"] == "critical_velocity" and r["ok"]]
    pv = [r for r in crit if r["method"] == "projected Verlet" and r["error"] <= TARGET]
    th = [r for r in crit if r["method"].startswith("tanh") and r["error"] <= TARGET]
    s = {}
    print(f"\n  critical velocity to {TARGET:g}:")
    if pv:
        b = min(pv, key=lambda r: r["run_s"])
        s["verlet"] = b
        print(f"    cheapest projected Verlet: {b['param']}: err {b['error']:.2e}, {b['run_s'] * 1e3:.2f} ms, "
              f"{b['run_s_per_evaluation'] * 1e3:.3f} ms/evaluation")
    if th:
        b = min(th, key=lambda r: r["run_s"])
        s["tanh"] = b
        print(f"    cheapest diffrax + tanh:   {b['method']} {b['param']}: err {b['error']:.2e}, "
              f"{b['run_s'] * 1e3:.2f} ms, {b['run_s_per_evaluation'] * 1e3:.3f} ms/evaluation")
    else:
        tanh_all = [r for r in crit if r["method"].startswith("tanh")]
        if tanh_all:
            b = min(tanh_all, key=lambda r: r["error"])
            s["tanh_plateau"] = b
            print(f"    no diffrax + tanh configuration reaches {TARGET:g}; best: {b['method']} "
                  f"{b['param']} at {b['error']:.2e}")
    if pv and th:
        s["ratio_solve"] = s["tanh"]["run_s"] / s["verlet"]["run_s"]
        s["ratio_per_evaluation"] = s["tanh"]["run_s_per_evaluation"] / s["verlet"]["run_s_per_evaluation"]
        met = s["ratio_solve"] >= 100
        print(f"    ratio tanh/Verlet (cheapest measured configurations): {s['ratio_solve']:.1f}x per solve, "
              f"{s['ratio_per_evaluation']:.1f}x per model evaluation -> target '>= 100x cheaper' "
              f"{'MET' if met else 'NOT MET'}")
    t_pv = pareto_cost_at([r for r in crit if r["method"] == "projected Verlet"], TARGET)
    t_th = pareto_cost_at([r for r in crit if r["method"].startswith("tanh")], TARGET)
    s["interp_verlet_s"], s["interp_tanh_s"] = t_pv, t_th
    s["ratio_interp"] = t_th / t_pv
    print(f"    interpolated along each Pareto front to exactly {TARGET:g}: Verlet {t_pv * 1e3:.2f} ms, "
          f"tanh {t_th * 1e3:.2f} ms, ratio {s['ratio_interp']:.1f}x")
    for part in ("trajectory", "critical_velocity"):
        for fam, sel in (("projected Verlet", lambda r: r["method"] == "projected Verlet"),
                         ("symplectic Euler", lambda r: r["method"].startswith("symplectic")),
                         ("diffrax + tanh", lambda r: r["method"].startswith("tanh")),
                         ("event-driven", lambda r: r["method"].startswith("event"))):
            rs = [r for r in rows if r["part"] == part and r["ok"] and sel(r)]
            if rs:
                b = min(rs, key=lambda r: r["error"])
                print(f"    {part:17s} {fam:17s} smallest error {b['error']:.2e} ({b['param']}, "
                      f"{b['run_s'] * 1e3:.2f} ms)")
    return s


def plot_single_mode(rows, summary, info, B, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(15, 7.5))
    rtol_colors = {1e-4: "#9ecae1", 1e-6: "#4292c6", 1e-8: "#08519c", 1e-10: "#08306b"}
    floor = 1e-17
    for ax, part in zip(axes, ("trajectory", "critical_velocity")):
        sel = [r for r in rows if r["part"] == part and r["ok"] and np.isfinite(r["error"])]
        groups = {}
        for r in sel:  # one curve per method; for tanh one per (solver, rtol) with ε along it
            key = r["method"] if not r["method"].startswith("tanh") else f"{r['method']}, rtol {r['rtol']:g}"
            groups.setdefault(key, []).append(r)
        for key, rs in groups.items():
            if key.startswith("tanh"):
                rs = sorted(rs, key=lambda r: -r["eps_rel"])
            elif key.startswith("event"):
                rs = sorted(rs, key=lambda r: -r["rtol"])
            elif key != "exact":
                rs = sorted(rs, key=lambda r: -r["lam_dt"])
            t = [r["run_s"] for r in rs]
            e = [max(r["error"], floor) for r in rs]
            if key == "exact":
                ax.plot(t, e, "k*", ms=14, label="exact (closed form; error 0 drawn at 1e-17)")
            elif key == "projected Verlet":
                ax.plot(t, e, "o-", color="C3", lw=2.5, label=key + " (λdt = 0.1 → 2e-4)")
            elif key.startswith("symplectic"):
                ax.plot(t, e, "s-", color="C1", label=key + " (λdt = 0.1 → 2e-4)")
            elif key.startswith("event"):
                ax.plot(t, e, "D-", color="C2", label=key + " (rtol 1e-6 → 1e-12; host loop)")
            else:
                style = "^--" if "Tsit5" in key else "v:"
                ax.plot(t, e, style, color=rtol_colors.get(rs[0]["rtol"], "gray"), ms=5,
                        label=key + " (ε' = 1e-1 → 1e-5)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"wall time per batch of {B} [s] (min over repeats, after compilation)")
        if part == "trajectory":
            ax.set_ylabel("max |A − A_exact| / a over saves and batch")
            ax.set_title("trajectory to t = 5/λ (slip, then stick)")
        else:
            ax.axhline(TARGET, color="gray", lw=1)
            ax.set_ylabel("max |Ȧ₀* − Ȧ_cr| / Ȧ_cr (P6)")
            ax.set_title("critical velocity (safeguarded Newton, horizon 10/λ)")
            txt = []
            if "ratio_solve" in summary:
                txt.append(f"to {TARGET:g} (cheapest measured): tanh/Verlet = {summary['ratio_solve']:.1f}× per "
                           f"solve, {summary['ratio_per_evaluation']:.1f}× per evaluation")
            if np.isfinite(summary.get("ratio_interp", np.nan)):
                txt.append(f"interpolated on the Pareto fronts at {TARGET:g}: {summary['ratio_interp']:.1f}×")
            if txt:
                ax.text(0.02, 0.98, "\n".join(txt), transform=ax.transAxes, fontsize=9, va="top",
                        bbox=dict(fc="white", ec="gray"))
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8)
    fig.suptitle(f"single-mode model, ΔF = {DF} N — batch {B}, {info['dtype']}, {info['device']}, "
                 f"jax {info['jax']} (shared machine: timings are noisy, compare side by side)")
    fig.tight_layout(rect=(0, 0.17, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"wrote {path}")


def replot(quick):
    p = os.path.join(OUT, f"work_precision_single_mode{'_quick' if quick else ''}.csv")
    if os.path.exists(p):
        rows = load_rows(p)
        info = {k: rows[0][k] for k in ("device", "jax", "dtype")}
        plot_single_mode(rows, single_mode_summary(rows), info, int(rows[0]["batch"]), p[:-4] + ".png")


def main():
    run_or_replot(__doc__.split("\n")[0], run_single_mode, replot, "redraw the figure from the CSV, print the summary")


if __name__ == "__main__":
    main()
