"""The stability map's numbers on inputs built by hand: the boundary read off a grid, the power-law
fit, the single-mode theory curve, the summary and CSV rows of a map, and what its figure shows.
Quick (no sweep compiles except one 2 × 2 single-mode map), so the mutation group
`stability_map` (tools/mutants.py) runs them for every mutant; `tests/test_cli.py::test_map_main_job`
checks a real field-model map end to end."""

import csv
import json
import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod import stability_map as sm
from jaxrod.sweeps import SweepResult

V0 = np.array([1e-3, 4e-3, 1.6e-2, 6.4e-2])


def test_grid_boundary_by_hand():
    """Per ΔF column: the geometric mean of the last stable and the first buckled v₀, only for
    a monotone column with both labels and no failed member."""
    dF = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    F, T = False, True
    buckled = np.array([[F, F, T, T],   # boundary between 4e-3 and 1.6e-2
                        [F, T, F, T],   # not monotone
                        [F, F, F, F],   # all stable
                        [T, T, T, T],   # all buckled
                        [F, F, F, T],   # a failed member in the column
                        [F, T, T, T]])  # boundary between 1e-3 and 4e-3
    ok = np.ones_like(buckled)
    ok[4, 2] = False
    dF_b, v_b, lo, hi = sm.grid_boundary(dF, V0, buckled, ok)
    np.testing.assert_array_equal(dF_b, [1.0, 6.0])
    np.testing.assert_allclose(v_b, [8e-3, 2e-3], rtol=1e-15)
    np.testing.assert_array_equal(lo, [4e-3, 1e-3])
    np.testing.assert_array_equal(hi, [1.6e-2, 4e-3])
    none = sm.grid_boundary(dF[1:5], V0, buckled[1:5], ok[1:5])
    assert len(none) == 4 and all(isinstance(c, np.ndarray) and c.size == 0 for c in none)


def test_fit_power_law_by_hand():
    # exact power law y = 3 x^−½: exponent, prefactor, zero standard error
    p, se, c = sm.fit_power_law([1.0, 4.0, 16.0, 64.0], [3.0, 1.5, 0.75, 0.375])
    assert p == pytest.approx(-0.5, abs=1e-14) and c == pytest.approx(3.0, rel=1e-14) and se < 1e-14
    # (1, 1), (2, 2), (4, 8) in logs: slope 3/2, intercept −(ln 2)/6, residuals (1, −2, 1)(ln 2)/6,
    # so the slope's standard error is √((ln²2/6)/1 / (2 ln²2)) = √(1/12)
    p, se, c = sm.fit_power_law(np.array([1, 2, 4]), np.array([1, 2, 8]))
    assert p == pytest.approx(1.5, rel=1e-14) and c == pytest.approx(2 ** (-1 / 6), rel=1e-14)
    assert se == pytest.approx(math.sqrt(1 / 12), rel=1e-12)
    # two points: the line through them, no standard error; fewer: nothing
    p, se, c = sm.fit_power_law([2.0, 8.0], [5.0, 2.5])
    assert p == pytest.approx(-0.5, rel=1e-14) and c == pytest.approx(5.0 * math.sqrt(2.0), rel=1e-14)
    assert math.isnan(se)
    for x, y in (([2.0], [5.0]), ([], [])):
        assert all(math.isnan(v) for v in sm.fit_power_law(x, y))


def _theory_by_hand(rod, dF):
    """P6 for mode 6 at F = F⁰₆ + ΔF: k₆ = −(6π/L)² ΔF/ρ and f = 4μN/(πρR) with N = ρg, so
    v = R f/√|k₆| = (4μg/π)(L/6π)√(ρ/ΔF)."""
    return 4 * float(rod.mu_d) * float(rod.g) / math.pi * float(rod.L) / (6 * math.pi) * np.sqrt(float(rod.rho) / np.asarray(dF))


def test_theory_boundary_is_the_single_mode_formula():
    rod = jr.RodChannel.reference(0.3)
    dF = np.array([0.5, 2.0, 8.0])
    np.testing.assert_allclose(sm.theory_boundary(rod, dF), _theory_by_hand(rod, dF), rtol=1e-12)
    np.testing.assert_allclose(sm.theory_boundary(rod, dF, mode=6), _theory_by_hand(rod, dF), rtol=1e-12)
    # another mode: its own stiffness at the same load, k₅ = (5π/L)²/ρ (F⁰₅ − F⁰₆ − ΔF)
    om5 = 5 * math.pi / float(rod.L)
    om6 = 6 * math.pi / float(rod.L)
    F05 = float(rod.EI) * om5**2 + float(rod.w) / (float(rod.R) * om5**2)
    F06 = float(rod.EI) * om6**2 + float(rod.w) / (float(rod.R) * om6**2)
    k5 = om5**2 / float(rod.rho) * (F05 - F06 - dF)
    f = 4 * 0.3 * float(rod.g) / (math.pi * float(rod.R))
    np.testing.assert_allclose(sm.theory_boundary(rod, dF, mode=5), float(rod.R) * f / np.sqrt(-k5), rtol=1e-12)


def _map(mu):
    """A 3 × 4 map (ΔF × v₀), C order. Labels per ΔF row (v₀ rising):
    ΔF = 1: - - B B;  ΔF = 2: - B B B;  ΔF = 4: B B B B, the second failed (code 1): 8 buckled,
    3 stable, 1 failed."""
    dF = np.array([1.0, 2.0, 4.0])
    F, T = False, True
    buckled = np.array([F, F, T, T, F, T, T, T, T, T, T, T])
    result = np.zeros(12, int)
    result[9] = 1
    inputs = {"dF": np.repeat(dF, 4), "amplitude": np.tile(V0, 3), "index": np.arange(12)}
    outputs = {"buckled": buckled, "t_buckle": np.where(buckled, 0.1, np.inf), "dominant_mode": np.full(12, 6),
               "max_theta": np.linspace(0.01, 0.12, 12), "final_theta": np.zeros(12), "stuck": ~buckled,
               "t_stop": np.where(buckled, np.nan, 0.2), "result": result, "steps": np.full(12, 100)}
    return dF, SweepResult(inputs, outputs, (3, 4), ("dF", "amplitude"), {"n": 32, "dt": 1e-5})


def test_summary_of_a_hand_map():
    dF, res = _map(0.3)
    s = sm._summarise(res, dF, V0, 0.3)
    F0cr = 2 * math.sqrt(float(jr.RodChannel.reference(0.3).w * jr.RodChannel.reference(0.3).EI
                                 / jr.RodChannel.reference(0.3).R))
    assert s["mu"] == 0.3 and s["members"] == 12 and s["buckled"] == 8 and s["stable"] == 3 and s["failed"] == 1
    assert s["boundary_dF"] == [1.0, 2.0]
    np.testing.assert_allclose(s["boundary_v0"], [8e-3, 2e-3], rtol=1e-15)
    assert s["boundary_v0_lo"] == [4e-3, 1e-3] and s["boundary_v0_hi"] == [1.6e-2, 4e-3]
    # two boundary points: the exponent of the line through them, (ln 2e-3 − ln 8e-3)/ln 2 = −2
    assert s["exponent"] == pytest.approx(-2.0, rel=1e-12) and math.isnan(s["exponent_stderr"])
    assert s["prefactor"] == pytest.approx(8e-3, rel=1e-12)
    assert s["largest_stable_dF_over_F0cr"] == pytest.approx(2.0 / F0cr, rel=1e-12)
    assert s["F0cr_continuous"] == pytest.approx(F0cr, rel=1e-12)
    assert s["buckles_for_every_dF_gt_0"] is False
    # a frictionless-like map: everything buckles, no stable column, no boundary
    allb = SweepResult(res.inputs, {**res.outputs, "buckled": np.ones(12, bool), "result": np.zeros(12, int)},
                       res.shape, res.names, res.meta)
    s = sm._summarise(allb, dF, V0, 0.0)
    assert s["buckles_for_every_dF_gt_0"] is True and s["largest_stable_dF_over_F0cr"] is None
    assert s["stable"] == 0 and s["buckled"] == 12 and s["boundary_dF"] == [] and math.isnan(s["exponent"])
    # loads at or below the reference: no positive ΔF to judge
    s = sm._summarise(allb, np.array([-1.0, 0.0, 0.0]), V0, 0.0)
    assert s["buckles_for_every_dF_gt_0"] is None


def test_map_rows_are_the_members_numbers():
    dF, res = _map(0.3)
    rows = sm._map_rows({0.3: res, 0.0: res})
    assert len(rows) == 24
    assert list(rows[0]) == ["mu", "dF", "v0", "buckled", "t_buckle", "dominant_mode", "max_theta", "stuck",
                             "t_stop", "result"]
    r = rows[9]  # ΔF = 4, v₀ = 4e-3: the failed member
    assert (r["mu"], r["dF"], r["v0"], r["buckled"], r["result"]) == (0.3, 4.0, 4e-3, True, 1)
    assert r["t_buckle"] == 0.1 and r["dominant_mode"] == 6 and r["max_theta"] == pytest.approx(0.1)
    assert rows[1]["stuck"] and rows[1]["t_stop"] == 0.2
    assert rows[12]["mu"] == 0.0 and rows[12]["dF"] == 1.0 and rows[12]["v0"] == 1e-3


def test_plot_shows_the_members_theory_fit_and_searched_curve(tmp_path):
    dF, res = _map(0.3)
    s = sm._summarise(res, dF, V0, 0.3)
    s["curve_v0"], s["curve_rtol"], s["curve_exponent"] = [7e-3, None, 1e-3], 1e-3, -1.5
    free = sm._summarise(res, dF, V0, 0.0)
    summary = {"model": "field", "mode": 6, "t1": 2.0, "n": 32, "dt": 1e-5, "dF": dF.tolist(), "v0": V0.tolist(),
               "maps": {"0.3": s, "0": free}}
    path = tmp_path / "map.png"
    fig = sm.plot_maps({0.3: res, 0.0: res}, summary, str(path))
    assert path.stat().st_size > 10_000
    assert len(fig.axes) == 2
    ax = fig.axes[0]
    stable, buckled, failed = ax.collections
    np.testing.assert_allclose(stable.get_offsets(), [(1, 1.0), (1, 4.0), (2, 1.0)], rtol=1e-12)
    offs = np.asarray(buckled.get_offsets())  # the failed member (labelled buckled) is not among them
    assert len(offs) == 8 and (4.0, 4.0) not in {tuple(o) for o in offs}
    np.testing.assert_allclose(failed.get_offsets(), [(4.0, 4.0)])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:3] == ["stable (straight)", "buckled", "failed run"]
    assert "single-mode theory P6 (slope −1/2)" in labels
    assert "fitted boundary: v0 ∝ ΔF^(-2.000 ± nan)" in labels
    assert "searched boundary (rtol 0.001): v0* ∝ ΔF^(-1.500)" in labels
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    theory = lines["single-mode theory P6 (slope −1/2)"]
    x, y = theory.get_data()
    np.testing.assert_allclose(x, np.geomspace(1.0, 4.0, 200), rtol=1e-12)
    np.testing.assert_allclose(y, 1e3 * _theory_by_hand(jr.RodChannel.reference(0.3), x), rtol=1e-10)
    x, y = lines["fitted boundary: v0 ∝ ΔF^(-2.000 ± nan)"].get_data()
    np.testing.assert_allclose(y, 1e3 * 8e-3 * x**-2.0, rtol=1e-10)
    pts = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    assert len(pts) == 1
    np.testing.assert_allclose(np.transpose(pts[0].get_data()), [(1.0, 8.0), (2.0, 2.0)], rtol=1e-12)
    x, y = lines["searched boundary (rtol 0.001): v0* ∝ ΔF^(-1.500)"].get_data()
    np.testing.assert_array_equal(x, dF)
    np.testing.assert_allclose(y, [7.0, np.nan, 1.0], rtol=1e-12)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    np.testing.assert_allclose(ax.get_xlim(), (1.0 / 1.15, 4.0 * 1.15), rtol=1e-12)
    np.testing.assert_allclose(ax.get_ylim(), (1.0 / 1.2, 64.0 * 1.2), rtol=1e-12)
    assert ax.get_xlabel() == "ΔF = F − F⁰₆ [N]" and ax.get_ylabel() == "v₀ (sine mode-6 lateral speed) [mm/s]"
    F0cr = s["F0cr_continuous"]
    assert ax.get_title() == f"μ = 0.3: 8 buckled, 3 stable\nstraight up to ΔF = {2.0 / F0cr:.1f} F⁰cr"
    # the frictionless panel: no theory, fit or searched curve
    assert fig.axes[1].get_lines() == [] and fig.axes[1].get_title().startswith("μ = 0: ")
    assert fig._suptitle.get_text() == ("Stability map, reference rod, field model (n = 32, dt = 1.00e-05 s, "
                                       "horizon 2 s)")


def test_a_small_single_mode_map_end_to_end(tmp_path, monkeypatch):
    """2 × 2 map of the single-mode model (cheap to compile): labels against the single-mode
    theory's stable zone, and the files it writes (the figure is handed to `plot_maps`, whose
    drawing the test above checks)."""
    rod = jr.RodChannel.reference(0.3)
    dF, v0 = [1.0, 16.0], [2e-3, 0.1]
    drawn = []
    monkeypatch.setattr(sm, "plot_maps", lambda results, summary, path: drawn.append((results, summary, path)))
    s = sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model="mode", out=str(tmp_path), progress=False, t1=0.5)
    assert len(drawn) == 1 and drawn[0][1] is s and drawn[0][2] == str(tmp_path / "map.png")
    assert list(drawn[0][0]) == [0.3] and drawn[0][0][0.3].grid("buckled").tolist() == [[False, True], [False, True]]
    # P6 at ΔF = 1, 16: v_cr = 64 and 16 mm/s, so 2 mm/s stays and 100 mm/s buckles at both loads
    assert list(_theory_by_hand(rod, dF) * 1e3) == pytest.approx([63.67, 15.92], rel=1e-3)
    m = s["maps"]["0.3"]
    assert (m["members"], m["buckled"], m["stable"], m["failed"]) == (4, 2, 2, 0)
    assert m["boundary_dF"] == dF and m["boundary_v0"] == pytest.approx([math.sqrt(2e-3 * 0.1)] * 2, rel=1e-12)
    assert "curve_v0" not in m  # no searched curve for the single-mode model
    assert s["model"] == "mode" and s["mode"] == 6 and s["t1"] == 0.5 and s["dF"] == dF and s["v0"] == v0
    assert s["n"] is None and 0 < s["dt"] < 1e-3  # the single mode has no nodes
    assert json.loads((tmp_path / "map.json").read_text()) == json.loads(json.dumps(s))
    with open(tmp_path / "map.csv") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [(float(r["dF"]), float(r["v0"]), r["buckled"]) for r in rows] == [
        (1.0, 2e-3, "0"), (1.0, 0.1, "1"), (16.0, 2e-3, "0"), (16.0, 0.1, "1")]
    assert (tmp_path / "sweep_mu0.3" / "sweep.json").exists()


def test_searched_boundary_fits_the_roots_that_converged(monkeypatch):
    """`_searched` hands the map's resolution to `boundary_curve` (here a stand-in returning
    chosen roots) and reports each load's root (None where the search failed), the runs used,
    and the exponent fitted to the converged roots only."""
    import jaxrod.boundary as bd

    calls = []

    def fake(rod, dFs, **kw):
        calls.append((float(rod.mu_d), np.asarray(dFs), kw))
        r = bd.RootResult(root=np.array([8e-3, 5.0, 2e-3, 1e-3]), lo=np.zeros(4), hi=np.zeros(4), value=np.zeros(4),
                          derivative=np.zeros(4), evaluations=np.array([5, 9, 6, 7]), result=np.array([0, 2, 0, 0]))
        return r, {}

    monkeypatch.setattr(bd, "boundary_curve", fake)
    dF = np.array([1.0, 2.0, 4.0, 16.0])
    res = SweepResult({"index": np.arange(4)}, {"result": np.zeros(4, int)}, (4,), ("dF",), {"n": 48, "dt": 2e-5})
    out = sm._searched(res, dF, 0.25, "galerkin", 5, 1.5, 1e-4, False)
    assert len(calls) == 1
    mu, dFs, kw = calls[0]
    assert mu == 0.25 and list(dFs) == list(dF)
    assert kw == dict(model="galerkin", n=48, dt=2e-5, mode=5, bracket=(1e-5, 2.0), rtol=1e-4, t1=1.5,
                      sensitivities=(), progress=False)
    assert out["curve_rtol"] == 1e-4 and out["curve_v0"] == [8e-3, None, 2e-3, 1e-3]
    assert out["curve_evaluations"] == [5, 9, 6, 7]
    # the converged roots (1, 8e-3), (4, 2e-3), (16, 1e-3): slope of ln v on ln ΔF by hand
    lx, ly = np.log([1.0, 4.0, 16.0]), np.log([8e-3, 2e-3, 1e-3])
    slope = np.sum((lx - lx.mean()) * (ly - ly.mean())) / np.sum((lx - lx.mean()) ** 2)
    assert out["curve_exponent"] == pytest.approx(slope, rel=1e-12) and out["curve_exponent_stderr"] > 0
    # fewer than two converged roots: no exponent
    monkeypatch.setattr(bd, "boundary_curve", lambda rod, dFs, **kw: (bd.RootResult(
        root=np.array([8e-3, 5.0]), lo=np.zeros(2), hi=np.zeros(2), value=np.zeros(2), derivative=np.zeros(2),
        evaluations=np.array([5, 9]), result=np.array([0, 1])), {}))
    out = sm._searched(res, dF[:2], 0.25, "field", 6, 2.0, 1e-3, False)
    assert out["curve_v0"] == [8e-3, None] and math.isnan(out["curve_exponent"]) and math.isnan(out["curve_exponent_stderr"])


def test_the_figure_draws_the_maps_own_mode_and_no_failed_entry_when_none_failed(tmp_path):
    """What a reader of `map.png` reads off it: the theory curve of the map's own mode (7 here,
    not 6), the searched curve's label, and no "failed run" markers or legend entry when every run
    succeeded. (Sizes, colours and line widths are styling, marked `pragma: no mutate` in the
    source, and not pinned here.)"""
    dF, res = _map(0.3)
    s = sm._summarise(res, dF, V0, 0.3)
    s["curve_v0"], s["curve_rtol"], s["curve_exponent"] = [7e-3, None, 1e-3], 1e-3, -1.5
    summary = {"model": "field", "mode": 7, "t1": 2.0, "n": 32, "dt": 1e-5, "dF": dF.tolist(), "v0": V0.tolist(),
               "maps": {"0.3": s}}
    fig = sm.plot_maps({0.3: res}, summary)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    x, y = lines["single-mode theory P6 (slope −1/2)"].get_data()
    np.testing.assert_allclose(y, 1e3 * sm.theory_boundary(jr.RodChannel.reference(0.3), x, 7), rtol=1e-12)
    assert not np.allclose(y, 1e3 * _theory_by_hand(jr.RodChannel.reference(0.3), x))  # mode 7, not 6
    assert "searched boundary (rtol 0.001): v0* ∝ ΔF^(-1.500)" in lines
    # every run succeeded: no failed-run markers and no legend entry for them
    ok = _all_succeeded(res)
    fig = sm.plot_maps({0.3: ok}, {**summary, "maps": {"0.3": sm._summarise(ok, dF, V0, 0.3)}})
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "failed run" not in labels and len(fig.axes[0].collections) == 2


def _all_succeeded(res):
    """The hand map with its failed member counted as a successful buckled run."""
    out = dict(res.outputs)
    out["result"] = np.zeros_like(out["result"])
    return SweepResult(dict(res.inputs), out, res.shape, res.names, res.meta)


def test_two_converged_roots_are_enough_for_the_searched_exponent(monkeypatch):
    """Two converged roots of the searched boundary fix its exponent: the slope through them."""
    import jaxrod.boundary as bd

    monkeypatch.setattr(bd, "boundary_curve", lambda rod, dFs, **kw: (bd.RootResult(
        root=np.array([8e-3, 2e-3, 1.0]), lo=np.zeros(3), hi=np.zeros(3), value=np.zeros(3), derivative=np.zeros(3),
        evaluations=np.array([5, 6, 9]), result=np.array([0, 0, 1])), {}))
    res = SweepResult({"index": np.arange(3)}, {"result": np.zeros(3, int)}, (3,), ("dF",), {"n": 48, "dt": 2e-5})
    out = sm._searched(res, np.array([1.0, 4.0, 16.0]), 0.3, "field", 6, 2.0, 1e-3, False)
    assert out["curve_exponent"] == pytest.approx(math.log(2e-3 / 8e-3) / math.log(4.0), rel=1e-12)


def test_a_galerkin_map_searches_its_boundary_with_its_own_settings(monkeypatch):
    """For the Galerkin (or field) model and μ > 0 the map searches its boundary (here a
    stand-in for `_searched`) with the map's μ, model, mode, horizon, tolerance and progress,
    on the sweep it ran with the map's n, mode and μ; μ = 0 is not searched; without `out`
    nothing is written."""
    calls = []

    def searched(res, dF, mu, model, mode, t1, rtol, progress):
        calls.append((res, list(dF), mu, model, mode, t1, rtol, progress))
        return {"curve_v0": [1e-2, 1e-3]}

    monkeypatch.setattr(sm, "_searched", searched)
    s = sm.stability_map(mus=(0.25, 0.0), dF=[1.0, 16.0], v0=[2e-3, 0.1], model="galerkin", n=8, mode=5,
                         out=None, progress=False, t1=0.25, curve_rtol=1e-2, chunk_size=3)
    assert len(calls) == 1
    res, dF, mu, model, mode, t1, rtol, progress = calls[0]
    assert (dF, mu, model, mode, t1, rtol, progress) == ([1.0, 16.0], 0.25, "galerkin", 5, 0.25, 1e-2, False)
    spec = res.meta["spec"]
    assert (spec["model"], spec["mu"], spec["mode"], spec["n"], spec["t1"]) == ("galerkin", 0.25, 5, 8, 0.25)
    assert spec["perturbation"] == "sine"
    assert s["n"] == 8 and s["maps"]["0.25"]["curve_v0"] == [1e-2, 1e-3] and "curve_v0" not in s["maps"]["0"]


def test_a_map_writes_to_out_map_by_default(tmp_path, monkeypatch):
    """Without `out` the files go to out/map under the working folder (as `jaxrod map`), never
    into the committed results/."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sm, "plot_maps", lambda results, summary, path: None)
    sm.stability_map(mus=(0.3,), dF=[1.0], v0=[0.1], model="mode", progress=False, t1=0.2)
    assert (tmp_path / "out" / "map" / "map.json").exists() and (tmp_path / "out" / "map" / "map.csv").exists()


def test_buckles_for_every_positive_load_looks_at_every_positive_load():
    """The flag reads every column with ΔF > 0: one stable member at ΔF = 0.5 N clears it."""
    dF = np.array([0.5, 2.0])
    inputs = {"dF": np.repeat(dF, 2), "amplitude": np.tile([1e-3, 1e-2], 2), "index": np.arange(4)}
    outputs = {"buckled": np.array([False, True, True, True]), "result": np.zeros(4, int)}
    res = SweepResult(inputs, outputs, (2, 2), ("dF", "amplitude"), {"n": 32, "dt": 1e-5})
    assert sm._summarise(res, dF, np.array([1e-3, 1e-2]), 0.3)["buckles_for_every_dF_gt_0"] is False
    res.outputs["buckled"][0] = True
    assert sm._summarise(res, dF, np.array([1e-3, 1e-2]), 0.3)["buckles_for_every_dF_gt_0"] is True


def test_a_map_runs_to_its_models_search_horizon_unless_given_one(monkeypatch):
    """`stability_map` without `t1` sweeps each model to its `search_horizon` (the field model 2 s,
    the 3D rod 0.4 s), and a given `t1` as given; the field model fills its grid, the 3D rod
    searches its columns (`map_fill`)."""
    import pytest

    from jaxrod import map_columns as mc
    from jaxrod import stability_map as sm

    seen = []

    class Stop(Exception):
        pass

    def fake(fill):
        def fake_sweep(spec, grid, **kw):
            seen.append((spec.model, spec.t1, fill, kw.get("combine", "grid")))
            raise Stop
        return fake_sweep

    monkeypatch.setattr(sm, "sweep", fake("grid"))
    monkeypatch.setattr(mc, "sweep", fake("search"))
    guided = []
    monkeypatch.setattr(sm, "_guess", lambda guide, mu, dF, v0, *a: guided.append((guide, mu)) or np.zeros(len(dF), int))
    for model, t1 in (("field", None), ("rod3d", None), ("rod3d", 1.0)):
        with pytest.raises(Stop):
            sm.stability_map((0.3,), model=model, out=None, progress=False, t1=t1)
    with pytest.raises(Stop):
        sm.stability_map((0.3,), model="rod3d", out=None, progress=False, fill="grid")
    assert seen == [("field", 2.0, "grid", "grid"), ("rod3d", 0.4, "search", "zip"), ("rod3d", 1.0, "search", "zip"),
                    ("rod3d", 0.4, "grid", "grid")]
    assert guided == [("field", 0.3)] * 2  # the 3D rod's searched maps start from the field model's; the filled one does not


def test_rod3d_map_runs_the_columns_past_the_wrinkling_load_with_the_explicit_scheme(monkeypatch, tmp_path):
    """A 3D map whose loads straddle the wall's wrinkling load (F⁰₆ + 48.7 N for the reference
    rod) runs two sweeps at one size: the columns below with the implicit step, those past it
    with the explicit leapfrog (their own folder), joined in grid order; a single-scheme map is
    one sweep in its usual folder."""
    from jaxrod import stability_map as sm
    from jaxrod.sweeps import SweepResult

    calls = []

    def fake_sweep(spec, grid, path=None, **kw):
        dF, v0 = np.asarray(grid["dF"]), np.asarray(grid["amplitude"])
        calls.append((spec.n, dF.tolist(), path))
        k = len(dF) * len(v0)
        scheme = "leapfrog" if dF[0] > 49 else "implicit"
        ins = {"dF": np.repeat(dF, len(v0)), "amplitude": np.tile(v0, len(dF)), "index": np.arange(k)}
        outs = {"buckled": ins["dF"] > 45, "result": np.zeros(k, int)}
        return SweepResult(ins, outs, (len(dF), len(v0)), ("dF", "amplitude"),
                           {"n": spec.n, "dt": 5e-5 if scheme == "implicit" else 7e-7, "scheme": scheme})

    monkeypatch.setattr(sm, "sweep", fake_sweep)
    monkeypatch.setattr(sm, "_summarise", lambda res, dF, v0, mu: {})
    out = str(tmp_path / "m")
    dF, v0 = np.array([20.0, 40.0, 49.6, 64.0]), np.array([0.01, 0.1])
    res = sm._map_sweep(0.3, dF, v0, "rod3d", None, 6, 0.4, out, False, None)
    n = sm.recipe("rod3d").default_size(jr.RodChannel.reference(0.3), 1.3080612552531 + 64.0,
                                             sm.make_perturbation("sine", 1.0, 6))
    assert calls == [(n, [20.0, 40.0], out), (n, [49.6, 64.0], out + "_dF49.6")]
    assert res.shape == (4, 2) and res.inputs["index"].tolist() == list(range(8))
    assert res.grid("buckled")[:, 0].tolist() == [False, False, True, True]
    assert res.inputs["dF"].tolist() == [20.0, 20.0, 40.0, 40.0, 49.6, 49.6, 64.0, 64.0]
    assert [(g["dF_first"], g["dF_last"], g["scheme"]) for g in res.meta["schemes"]] == [
        (20.0, 40.0, "implicit"), (49.6, 64.0, "leapfrog")]
    calls.clear()
    res = sm._map_sweep(0.3, dF[:2], v0, "rod3d", 30, 6, 0.4, out, False, None)
    assert calls == [(30, [20.0, 40.0], out)] and len(res.meta["schemes"]) == 1


def test_a_rod3d_sweep_past_the_wrinkling_load_runs_the_explicit_scheme_at_its_step():
    """The sweep's scheme is resolved with its step, at its largest load: a 3D sweep reaching past
    the wrinkling load runs the explicit leapfrog (at the explicit step), one below it the
    implicit step at its own (before, such a sweep ran the implicit scheme at the explicit step)."""
    from jaxrod.sweeps import SweepSpec
    from jaxrod.sweeps.member import _static_resolution

    spec = SweepSpec(model="rod3d", n=12, t1=0.04)
    below = _static_resolution(spec, {"dF": np.array([5.0, 40.0])})
    past = _static_resolution(spec, {"dF": np.array([5.0, 60.0])})
    assert below[3] == "implicit" and past[3] == "leapfrog"
    assert past[1] < below[1]
    field = _static_resolution(SweepSpec(model="field", n=32, t1=0.04), {"dF": np.array([60.0])})
    assert field[3] == "verlet"


def test_the_map_command_reports_each_schemes_step_and_a_boundary_without_a_searched_curve(monkeypatch, capsys):
    """`jaxrod map` prints each column group's scheme and step, the fitted boundary of a map that
    has one even without a searched curve (the 3D rod's), and "no boundary crossing" only when no
    column has one."""
    from jaxrod import stability_map as sm
    from jaxrod.cli import main

    def fake(mus, dF, v0, model, n, mode, out, **kw):
        m = dict(mu=0.3, buckled=3, stable=5, failed=0, exponent=-0.7, exponent_stderr=0.02, boundary_dF=[1.0, 2.0],
                 largest_stable_dF_over_F0cr=1.5)
        return dict(n=12, dt=5e-5, maps={"0.3": m, "0.2": dict(m, exponent=float("nan"), boundary_dF=[])},
                    schemes=[dict(dF_first=1.0, dF_last=2.0, scheme="implicit", dt=5e-5),
                             dict(dF_first=64.0, dF_last=64.0, scheme="leapfrog", dt=7.4e-7)])

    monkeypatch.setattr(sm, "stability_map", fake)
    assert main(["map", "--model", "rod3d", "--quiet", "--out", "/tmp/jaxrod-unused"]) == 0
    out = capsys.readouterr().out
    assert "n = 12, implicit at 5.000e-05 s for dF 1-2 N, leapfrog at 7.400e-07 s for dF 64-64 N" in out
    assert "p = -0.700 +/- 0.020 (theory -1/2), from 2 columns" in out
    assert out.count("no boundary crossing inside the grid") == 1
