"""`jaxrod simulate --model rod3d`: the 3D rod from the command line."""

import json

import numpy as np
import pytest

from jaxrod.cli import main


@pytest.mark.slow  # 23-30 s of 3D compilation; the default suite keeps a quicker check
def test_simulate_rod3d_displacement_control_reports_the_peak_reaction(capsys):
    assert main(["simulate", "--model", "rod3d", "--control", "displacement", "--speed", "2e-3",
                 "--n", "8", "--t1", "0.05", "--n-save", "51", "--amplitude", "0.01", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "rod3d" and out["control"] == "displacement" and out["n_segments"] == 8
    # linear response before buckling: reaction ≈ EA·displacement/L at the peak, to 10 %
    EA, L = 77e9 * 3.14159265 * 1.5e-3**2 / 4, 3.0
    assert out["peak_reaction"] == pytest.approx(EA * out["end_displacement_at_peak"] / L, rel=0.1)
    assert out["result"] == "successful"


@pytest.mark.slow  # a compiled 3D run (~10 s); the forcing phase itself: tests/test_rod3d_random_position.py
def test_simulate_rod3d_takes_the_random_perturbations(capsys):
    """Every perturbation of the paper on the 3D rod: a random position pulse of 2 N/m moves the
    rod (max θ > 0) and is reported as such."""
    code = main(["simulate", "--model", "rod3d", "--control", "load", "--perturbation", "random-position",
                 "--amplitude", "2", "--n", "8", "--t1", "0.005", "--json", "--quiet"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["perturbation"] == "random-position" and out["max_theta"] > 0


@pytest.mark.slow  # two 3D runs of 60 segments (about 1 min each on the 2-core CPU)
@pytest.mark.parametrize("amplitude,buckled", [(0.035, True), (0.005, False)])
def test_simulate_rod3d_with_held_ends_gives_the_reduced_models_verdict(capsys, amplitude, buckled):
    """The paper's Fig 6A case (μ = 0.3, ΔF = 5 N, 35 mm/s) buckles, as in the paper and the field
    model (v₀* = 26.8 mm/s); 5 mm/s stays straight. With the ends held a buckled rod settles near
    the held-end amplitude (0.38 rad here), so the 0.5 rad threshold missed it (max θ 0.477)."""
    assert main(["simulate", "--model", "rod3d", "--dF", "5", "--amplitude", str(amplitude), "--t1", "0.3",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["control"] == "force" and out["buckle_threshold"] < 0.5
    assert out["buckled"] is buckled
    if not buckled:
        assert out["max_theta"] < 0.2 * out["buckle_threshold"]


@pytest.mark.slow  # 10 label runs of the 3D rod over a 2-s horizon (~100 s), then two plain runs
def test_boundary_of_the_3d_rod_on_the_command_line_splits_plain_runs(capsys):
    """`jaxrod boundary --model rod3d` (label bisection to 5 %): plain 3D runs of the same scene
    (`Scene(kind="rod3d")`, 8 segments) 10 % below its v₀* stay straight and 10 % above buckle."""
    import jaxrod as jr

    code = main(["boundary", "--model", "rod3d", "--n", "8", "--dF", "5", "--rtol", "0.05", "--json", "--quiet"])
    out = json.loads(capsys.readouterr().out)[0]
    assert code == 0 and out["result"] == "converged"
    rod = jr.RodChannel.reference(0.3)
    for share, buckled in ((0.9, False), (1.1, True)):
        sol = jr.scene.Scene(rod, 5.0, jr.SineVelocity(share * out["v0_star"], 6.0), "rod3d", n=8).run(
            t1=2.0, save_state=False)
        assert bool(sol.buckled) == buckled, share


@pytest.mark.slow  # two rounds of a vmapped 3D grid and a field search (~1 min)
def test_crosscheck_critical_velocity_brackets_the_3d_boundary():
    """`experiments.rod3d.crosscheck_critical_velocity` (reproduce e6's cross-check): its 3D
    bracket is ordered, monotonic in v₀, and confirmed by plain runs at its two ends (the lower
    stays straight, the upper buckles); the field model's v₀* it reports is the search's."""
    import jaxrod as jr
    from jaxrod.experiments.rod3d import crosscheck_critical_velocity
    from jaxrod.rod3d import Rod3D, sine_velocity, step_limit
    from jaxrod.experiments.rod3d import run

    (r,) = crosscheck_critical_velocity([5.0], n=12, t1=0.4, grid=5, rounds=2, progress=False)
    lo, hi = r["rod3d_bracket"]
    assert r["monotonic"] and 0 < lo < hi and r["rod3d"] == pytest.approx((lo * hi) ** 0.5)
    rod = jr.RodChannel.reference(0.3)
    field, _ = jr.boundary.critical_velocity(rod, 5.0, model="field", rtol=1e-4, sensitivities=())
    assert r["field"] == pytest.approx(float(field.root), rel=1e-12)
    F = float(jr.theory.reference_load(rod)) + 5.0
    model = Rod3D(rod, 12, control="load", end_load=F)
    for v0, buckled in ((lo, False), (hi, True)):
        q0, w0 = model.initial_state(F, lateral_velocity=sine_velocity(model, v0))
        sol = run(model, q0, w0, 0.4, 11, 0.5 * step_limit(model, q0))
        assert bool(sol.buckled) == buckled, v0


@pytest.mark.slow  # a forward-mode 3D search and a bisection, 12 segments (~2 min)
def test_departure_search_of_the_3d_rod_lands_in_the_bisection_bracket():
    """The departure rate on the 3D rod's node positions (opt-in, `method="departure"`) finds
    a root inside the label bracket of bisection of the same runs."""
    import jaxrod as jr

    rod = jr.RodChannel.reference(0.3)
    kw = dict(model="rod3d", n=12, rtol=1e-2, sensitivities=())
    dep, _ = jr.boundary.critical_velocity(rod, 5.0, method="departure", **kw)
    bis, _ = jr.boundary.critical_velocity(rod, 5.0, method="bisection", **kw)
    assert int(dep.result) == 0 and int(bis.result) == 0
    assert float(bis.lo) <= float(dep.root) <= float(bis.hi)
    # 12 runs each (measured; 30 for the departure search while its float32 friction pass
    # overflowed the tangents near the root: `Rod3D.for_tangents`)
    assert int(dep.evaluations) <= int(bis.evaluations)


@pytest.mark.slow  # 12 segments: a bisection and two forward-mode runs (~1 min)
def test_departure_rate_of_the_3d_rod_is_finite_next_to_its_boundary():
    """Just above v₀* (ΔF = 5 N, μ = 0.3, 12 segments; v₀* bisected here with the scene's own
    scheme, to 1e-5) the run's tangent stays finite (it was NaN from step 928: 1/|g|⁴ of a
    vanishing slip impulse in the float32 friction pass), and u grows linearly in v₀ − v₀*:
    extrapolated to u = 0 from two points it lands back in the bisection bracket (to 1e-3)."""
    import jax

    import jaxrod as jr
    from jaxrod.boundary.search import _resolution, _scene

    rod = jr.RodChannel.reference(0.3)
    bis, _ = jr.boundary.critical_velocity(rod, 5.0, model="rod3d", n=12, method="bisection", rtol=1e-5,
                                           sensitivities=())
    assert int(bis.result) == 0
    v_star = float(bis.hi)  # the smallest buckled amplitude
    n, dt = _resolution(rod, 5.0, "rod3d", 12, 6, None)
    rate = jax.jit(lambda x: jr.boundary.departure_rate(
        lambda v: _scene(rod, 5.0, v, "rod3d", n, 6, dt, "sine", jax.random.key(0)), x))
    x1, x2 = v_star * (1 + 4e-4), v_star * (1 + 2e-3)
    (b1, u1), (b2, u2) = rate(x1), rate(x2)
    assert bool(b1) and bool(b2) and np.isfinite(float(u1)) and 0 < float(u1) < float(u2)
    lam = (float(u2) - float(u1)) / (x2 - x1)
    assert abs((x1 - float(u1) / lam) / v_star - 1) < 1e-3
