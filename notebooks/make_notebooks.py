"""Writes the research notebooks 01-06 (run: python notebooks/make_notebooks.py [--execute]).

Each notebook has a size switch: with JAXROD_NB_SMALL=1 (what the test suite sets) it runs in
seconds; otherwise at a resolution worth looking at (on a shared 2-core CPU: 8-30 s each, but
29 min for 04's 64 random-velocity searches at 499+ nodes). Figures are shown
inline: the package's plotting functions return `matplotlib.figure.Figure` objects, which a
cell shows by returning them, and the cells' own pyplot figures show through the inline
backend. With `--execute` each notebook is also run top to bottom (in a temporary folder, at
the size the switch says) and saved with its outputs, which the documentation site renders
without running anything.
"""

import argparse
import os
import tempfile
import time

import nbformat as nbf

HEAD = '''%matplotlib inline
import os
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np
import matplotlib.pyplot as plt
import jaxrod as jr

SMALL = os.environ.get("JAXROD_NB_SMALL", "0") == "1"   # the size switch
rod = jr.RodChannel.reference(mu=0.3)                     # the reference paper's nitinol rod'''

NOTEBOOKS = {
    "01_quick_start": [
        ("md", "# 01 Quick start\nTheory numbers, one simulation and one small stability map for the reference rod."),
        ("code", HEAD),
        ("md", "## Theory (docs/physics.md P3-P7)"),
        ("code", '''m = int(jr.theory.critical_mode(rod))
print("F0cr (continuous) =", float(jr.theory.critical_load_continuous(rod)), "N; critical mode", m,
      "with F0_m =", float(jr.theory.frictionless_load(rod, m)), "N")
mode = jr.SingleMode.from_rod(rod, dF=5.0)
v_cr = float(rod.R * jr.theory.velocity_intercept(mode.k, mode.f_d))
print(f"critical lateral speed of mode {m} at dF = 5 N: {1e3 * v_cr:.2f} mm/s")
assert m == 6'''),
        ("md", "## One simulation of the field model"),
        ("code", '''scene = jr.scene.Scene(rod, 5.0, jr.SineVelocity(0.03, 6.0), "field", n=32 if SMALL else 128)
sol = scene.run(t1=0.2 if SMALL else 2.0, n_save=401)
print("buckled:", bool(sol.buckled), "at t =", float(sol.t_buckle), "s; energy balance error",
      float(sol.energy_balance_error()))
ts, amp = np.asarray(sol.ts), np.asarray(sol.amplitude)
ran = ts <= float(sol.t_stop)   # the run stops when the rod buckles or sticks
plt.plot(ts[ran], amp[ran]); plt.xlabel("t [s]"); plt.ylabel("max |theta| [rad]"); plt.yscale("log")'''),
        ("md", "The package's picture of a run (what `jaxrod simulate --plot` writes): θ(s, t) and the modal power spectrum. "
               "`plot_simulation` returns a `matplotlib.figure.Figure`; returning it from the cell shows it."),
        ("code", '''from jaxrod.figures import plot_simulation

fig = plot_simulation(scene, sol)
fig'''),
        ("md", "## A small stability map (E3)"),
        ("code", '''k = 5 if SMALL else 12
res = jr.sweep(jr.SweepSpec(model="field", n=32 if SMALL else 128, t1=0.5 if SMALL else 2.0),
               {"dF": np.geomspace(1, 40, k), "amplitude": np.geomspace(2e-3, 0.1, k)}, progress=False)
print(res.summary())
b = res.grid("buckled")
plt.figure(); plt.pcolormesh(np.geomspace(1, 40, k), 1e3 * np.geomspace(2e-3, 0.1, k), b.T, shading="nearest")
plt.xscale("log"); plt.yscale("log"); plt.xlabel("dF [N]"); plt.ylabel("v0 [mm/s]");'''),
    ],
    "02_stable_zone": [
        ("md", "# 02 The stable zone and the phase plane\nThe single-mode oscillator A'' + kA + f sgn(A') = 0 under load (k < 0): the analytic zone against a vmapped projected-Verlet classification."),
        ("code", HEAD),
        ("code", '''k, f = -4.0, 2.0
A_b, V_b = jr.theory.stable_zone_boundary(k, f, n=200, extent=10)
N = 20 if SMALL else 60
A, V = np.meshgrid(np.linspace(-1.5, 1.5, N), np.linspace(-3, 3, N))
model = jr.SingleMode(k, f, f)
run = jax.vmap(lambda a, v: jr.simulate(model, jr.ProjectedVerlet(3e-3), a, v, 15.0, n_save=2, throw=False).stuck[-1])
stable = np.asarray(run(A.ravel(), V.ravel())).reshape(A.shape)
zone = np.asarray(jr.theory.in_stable_zone(A, V, k, f))
print("agreement with the analytic zone:", (stable == zone).mean())
plt.fill(A_b, V_b, alpha=0.3); plt.scatter(A[stable], V[stable], s=4, c="g"); plt.scatter(A[~stable], V[~stable], s=4, c="r")
plt.xlim(-1.5, 1.5); plt.ylim(-3, 3); plt.xlabel("A"); plt.ylabel("dA/dt")
assert (stable == zone).mean() > 0.95'''),
        ("code", '''for v0 in (0.9, 1.1):  # just inside / outside the velocity intercept f/sqrt|k| = 1
    sol = jr.simulate(model, jr.Exact(), 0.0, v0, 6.0, n_save=600)
    plt.plot(sol.q, sol.v, label=f"v0 = {v0}")
plt.legend(); plt.xlim(-1.5, 3);'''),
    ],
    "03_stability_maps": [
        ("md", "# 03 Stability maps (E3)\nStraight or buckled over (dF, v0), with and without friction, and the fitted boundary."),
        ("code", HEAD),
        ("code", '''n_dF, n_v = (5, 6) if SMALL else (16, 20)
summary = jr.stability_map.stability_map(mus=(0.3, 0.0), dF=np.geomspace(0.5, 64, n_dF), v0=np.geomspace(1e-3, 0.2, n_v),
                                         n=32 if SMALL else None, out="nb03_map", progress=False, t1=0.5 if SMALL else 2.0)
fric = summary["maps"]["0.3"]
print("boundary exponent:", fric["exponent"], "+/-", fric["exponent_stderr"], "(theory -0.5)")
print("largest stable dF/F0cr:", fric["largest_stable_dF_over_F0cr"])
assert summary["maps"]["0"]["stable"] == 0'''),
        ("md", "The map as a figure: the sweeps were kept in `nb03_map/` (resumable), and `plot_maps` draws them (the `map.png` of `jaxrod map`)."),
        ("code", '''results = {mu: jr.SweepResult.load(f"nb03_map/sweep_mu{mu:g}") for mu in (0.3, 0.0)}
fig = jr.stability_map.plot_maps(results, summary)
fig'''),
    ],
    "04_friction_power_laws": [
        ("md", "# 04 Friction power laws (E4)\nThe critical load above F0_6 against mu, by root search, for a sine and a random velocity perturbation."),
        ("code", HEAD),
        ("code", '''mus = np.geomspace(0.05, 1.0, 3 if SMALL else 8)
n = 24 if SMALL else None
sine, _ = jr.boundary.critical_load_curve(mus, 15e-3, perturbation="sine", n=n, bracket=(1e-3, 300.0))
rand, _ = jr.boundary.critical_load_curve(mus, 15e-3, perturbation="random-velocity", realizations=2 if SMALL else 8,
                                          n=n, bracket=(1e-3, 300.0))
# a search whose bracket holds no root returns NaN beside its result code: average the others
print("searches without a root in the bracket:", int((np.asarray(rand.result) != 0).sum()), "of", rand.result.size)
F_sine = np.asarray(sine.root)[:, 0]
F_rand = np.nanmean(np.asarray(rand.root), axis=1)
p1 = jr.stability_map.fit_power_law(mus, F_sine)[0]
p2 = jr.stability_map.fit_power_law(mus, F_rand)[0]
print(f"sine: dF* ~ mu^{p1:.2f} (single-mode theory 2); random velocity: mu^{p2:.2f}")
plt.loglog(mus, F_sine, "o-", label="sine 15 mm/s"); plt.loglog(mus, F_rand, "s-", label="random velocity 15 mm/s")
p7 = [float(jr.theory.critical_load_velocity(rod.with_friction(m), 6, 15e-3 / rod.R) - jr.theory.frictionless_load(rod, 6)) for m in mus]
plt.loglog(mus, p7, "k--", label="P7"); plt.legend(); plt.xlabel("mu"); plt.ylabel("dF* [N]")
assert np.isfinite(p1) and np.isfinite(p2)'''),
    ],
    "05_mode_selection": [
        ("md", "# 05 Mode selection (E5)\nWhich mode buckles: the P6 intercepts of modes 2-10 against the load, and the dominant mode of random-perturbation runs."),
        ("code", HEAD),
        ("code", '''F = np.linspace(1.0, 20.0, 200)
f = float(jr.theory.friction_amplitude(rod))
for m in (2, 4, 6, 8, 10):
    k = np.asarray(jr.theory.stiffness(rod, m, F))
    plt.semilogy(F, np.where(k < 0, 1e3 * float(rod.R) * f / np.sqrt(np.abs(k)), np.nan), label=f"mode {m}")
plt.legend(); plt.xlabel("F [N]"); plt.ylabel("R Adot_cr [mm/s]");'''),
        ("code", '''R = 3 if SMALL else 16
res = jr.sweep(jr.SweepSpec(model="field", n=32 if SMALL else 128, perturbation="random-velocity", t1=0.5 if SMALL else 2.0),
               {"mu": [0.1, 0.5], "dF": [10.0], "amplitude": [0.05], "realization": np.arange(R)}, progress=False)
modes = res.grid("dominant_mode")[:, 0, 0, :]
buck = res.grid("buckled")[:, 0, 0, :]
for mu, m, b in zip((0.1, 0.5), modes, buck):
    print(f"mu = {mu}: buckled {b.sum()}/{len(b)}, dominant modes {sorted(m[b].tolist())}")'''),
    ],
    "06_boundary_search": [
        ("md", "# 06 Boundary search and sensitivities\nThe critical velocity by safeguarded Newton, its sensitivities by the implicit function theorem, and the worst-case perturbation."),
        ("code", HEAD),
        ("code", '''res, sens = jr.boundary.critical_velocity(rod, 5.0, model="mode", bracket=(5e-3, 0.1))
F = jr.theory.frictionless_load(rod, 6) + 5.0
p6 = float(rod.R * jr.theory.velocity_intercept(jr.theory.stiffness(rod, 6, F), jr.theory.friction_amplitude(rod)))
print("single mode: v0* =", float(res.root), "P6 =", p6, "evaluations", int(res.evaluations))
print("dv0*/dmu =", float(sens["mu"]), "(analytic", p6 / 0.3, ")")
assert abs(float(res.root) / p6 - 1) < 1e-6'''),
        ("code", '''res, sens = jr.boundary.critical_velocity(rod, 5.0, model="field", n=32 if SMALL else 128, bracket=(2e-3, 0.2), rtol=1e-6)
print("field model: v0* =", float(res.root), "m/s in", int(res.evaluations), "evaluations; dv0*/dmu =", float(sens["mu"]))'''),
        ("code", '''wc = jr.worst_case.worst_case_velocity(rod, 5.0, n=24 if SMALL else 32, steps=4 if SMALL else 30, n_random=4 if SMALL else 16)
print("worst-case RMS speed", wc["norm_worst"], "vs sine mode 6", wc["norm_sine"], "; dominant mode", wc["dominant_mode"])
plt.bar(np.arange(1, len(wc["spectrum"]) + 1), wc["spectrum"]); plt.xlabel("mode"); plt.ylabel("power")
assert wc["norm_worst"] <= wc["norm_sine"]'''),
    ],
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="notebooks to write (default: all), e.g. 01_quick_start")
    ap.add_argument("--execute", action="store_true",
                    help="run each notebook and save it with its outputs (JAXROD_NB_SMALL=1: the small setting)")
    args = ap.parse_args(argv)
    unknown = set(args.names) - set(NOTEBOOKS)
    if unknown:
        ap.error(f"unknown notebook(s) {sorted(unknown)}; expected some of {list(NOTEBOOKS)}")
    here = os.path.dirname(os.path.abspath(__file__))
    for name in args.names or NOTEBOOKS:
        nb = nbf.v4.new_notebook()
        nb.cells = [nbf.v4.new_markdown_cell(src) if kind == "md" else nbf.v4.new_code_cell(src)
                    for kind, src in NOTEBOOKS[name]]
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        if args.execute:
            import nbclient

            start = time.perf_counter()
            with tempfile.TemporaryDirectory() as tmp:  # files the notebook writes (nb03_map/) stay out of the tree
                nbclient.NotebookClient(nb, timeout=3600, kernel_name="python3", record_timing=False,
                                        resources={"metadata": {"path": tmp}}).execute()
            print(f"{name}: executed in {time.perf_counter() - start:.0f} s")
        nbf.write(nb, os.path.join(here, f"{name}.ipynb"))


if __name__ == "__main__":
    main()
