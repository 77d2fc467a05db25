"""The field model's parts of E4 and E6 with their searches (and E6's 3D parts) replaced by
recorders or exact laws, E6's runs at the test suite's `tiny` setting: the cases each runs, what
it records and fits, and the files it writes. The 3D parts are tested in
tests/test_experiments_rod3d_fast.py."""

import csv
import importlib

import numpy as np
import pytest

import jaxrod
from jaxrod.experiments import rod3d as exp3d

e6m = importlib.import_module("jaxrod.experiments.e6.field")


class _Root:
    def __init__(self, root):
        self.root = root


@pytest.fixture
def e6_tiny(tmp_path, monkeypatch):
    calls = {}

    def search(rod, amplitude, **kw):
        calls["search"] = (float(rod.mu_s), amplitude, kw)
        return _Root(20.0), None

    monkeypatch.setattr(jaxrod.boundary, "critical_load", search)
    monkeypatch.setattr(exp3d, "e6_full", lambda out, quick, progress: {"full": quick})
    monkeypatch.setattr(exp3d, "crosscheck_critical_velocity",
                        lambda dFs, n, progress, friction_at="surface": {"dFs": tuple(dFs), "at": friction_at})
    monkeypatch.setattr(exp3d, "rolling_check", lambda dF, n: pytest.fail("tiny has no loads to check"))
    res = e6m.e6(str(tmp_path), "tiny", False)
    return res, calls, tmp_path


def test_e6_runs_the_papers_three_cases_and_records_each_runs_spectra(e6_tiny):
    res, calls, out = e6_tiny
    mu, amplitude, kw = calls["search"]
    assert (mu, amplitude, kw["perturbation"], kw["n"], kw["t1"], kw["rtol"]) == (0.9, 2.0, "random-position", 24, 0.3, 1e-4)
    assert res["random_position_mu0.9_dF_star"] == 20.0
    labels = ["sine mode 6, μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s", "random position, μ = 0.9, ΔF = 40 N",
              "random position, μ = 0.9, ΔF = 1.05 ΔF* = 21.0 N"]
    assert [k for k in res if k in labels] == labels
    for label, mu, dF in zip(labels, (0.3, 0.9, 0.9), (5.0, 40.0, 21.0)):
        r = res[label]
        assert r["n"] == 24 and r["mu"] == mu and r["dF"] == pytest.approx(dF)
        assert 1 <= r["dominant_mode_before"] <= 24 and 0 < r["dominant_power_after"] <= 1
    assert res[labels[0]]["dominant_mode_before"] == 6  # the sine velocity is mode 6 alone at first
    assert res["full_model"] == {"full": "tiny"}
    assert res["crosscheck_critical_velocity"] == {"dFs": (), "at": "surface"}
    assert res["crosscheck_critical_velocity_axis_friction"] == {"dFs": (), "at": "axis"}
    assert "rolling_check" not in res
    rows = list(csv.DictReader(open(out / "e6_spectra.csv")))
    assert len(rows) == 3 * 24 and [r["mode"] for r in rows[:3]] == ["1", "2", "3"]
    for label in labels:
        mine = [r for r in rows if r["case"] == label]
        assert np.sum([float(r["power_before"]) for r in mine]) == pytest.approx(1.0, rel=1e-9)
        assert max(mine, key=lambda r: float(r["power_after"]))["mode"] == str(res[label]["dominant_mode_after"])
    assert (out / "e6_spectra.png").stat().st_size > 0


def test_e4_tabulates_each_case_against_its_law_and_draws_them(tmp_path, monkeypatch):
    """E4 (field) with its searches replaced by an exact law δF* = 10·μ^e per case (exponent 2 for
    the sine cases, 1 otherwise): the fitted exponents, the single-mode P7 beside the sine cases,
    the means and spread over the realizations, the CSV and the figure."""
    from jaxrod import theory
    from jaxrod.params import RodChannel

    e4m = importlib.import_module("jaxrod.experiments.e4.field")
    seen = []

    class Curve:
        def __init__(self, root):
            self.root, self.result, self.evaluations = root, np.zeros(root.shape, int), np.full(root.shape, 7)

    def curve(mus, amp, perturbation, realizations, **kw):
        seen.append((perturbation, amp, realizations, kw["seed"], kw["n"]))
        e = 2.0 if perturbation == "sine" else 1.0
        base = 10.0 * np.asarray(mus)[:, None] ** e
        return Curve(base * (1 + 0.1 * np.arange(realizations))[None, :]), None

    monkeypatch.setattr(jaxrod.boundary, "critical_load_curve", curve)
    monkeypatch.setattr(e4m, "_frictionless_dF", lambda s, amp, kind: (0.5, 0))
    monkeypatch.setattr(e4m, "_independent_modes", lambda mus, amp, reals, seed: np.full(len(mus), 3.0))
    res = e4m.e4(str(tmp_path), "tiny", False)
    mus = np.array([0.1, 0.4, 1.0])
    assert [s[0] for s in seen] == ["sine", "sine", "random-velocity", "random-position"]
    assert [s[2] for s in seen] == [1, 1, 2, 2] and {s[3] for s in seen} == {4} and {s[4] for s in seen} == {24}
    sine = res["sine 15 mm/s"]
    assert sine["exponent"] == pytest.approx(2.0, abs=1e-9) and sine["dF_star_std"] == [0.0, 0.0, 0.0]
    rod = RodChannel.reference()
    F0 = float(theory.reference_load(rod))
    p7 = [float(theory.critical_load_velocity(rod.with_friction(m), 6, 15e-3 / rod.R)) - F0 for m in mus]
    np.testing.assert_allclose(sine["single_mode_P7"], p7, rtol=1e-12)
    np.testing.assert_allclose(sine["field_over_P7"], 10.0 * mus**2 / np.array(p7), rtol=1e-12)
    rv = res["random velocity ±15 mm/s"]
    assert rv["exponent"] == pytest.approx(1.0, abs=1e-9) and rv["independent_modes_P7"] == [3.0, 3.0, 3.0]
    np.testing.assert_allclose(rv["dF_star"], 10.0 * mus * 1.05, rtol=1e-12)  # the mean of 1.0 and 1.1
    np.testing.assert_allclose(rv["dF_star_std"], 10.0 * mus * 0.1 / np.sqrt(2), rtol=1e-9)  # ddof 1
    assert res["random position (forces ±2 N/m for 1 ms)"]["frictionless_dF_star"] == 0.5
    # every search's evaluations are counted: 7 per realization and μ
    assert [res[k]["evaluations_total"] for k in ("sine 15 mm/s", "random velocity ±15 mm/s")] == [7 * 3, 7 * 3 * 2]
    assert all(0.0 <= res[k]["seconds"] < 60.0 for k in res if isinstance(res[k], dict) and "exponent" in res[k])
    rows = list(csv.DictReader(open(tmp_path / "e4_critical_load.csv")))
    assert len(rows) == 4 * 3 and rows[0]["case"] == "sine 7.5 mm/s" and float(rows[0]["mu"]) == 0.1
    assert (tmp_path / "e4_critical_load.png").stat().st_size > 0


def test_e3_records_the_maps_resolution_exponent_and_frictionless_verdict(tmp_path, monkeypatch):
    """E3 (field) with the map replaced by a recorder: the grid it asks for (the setting's loads and
    velocities, μ = 0.3 and 0, mode 6, 2 s) and the entries it takes from the map's summary."""
    import jaxrod.stability_map as sm
    from jaxrod.experiments.e3 import field as e3m

    asked = {}

    def stability_map(mus, dFs, v0s, model, n, mode, out, progress, t1):
        asked.update(mus=mus, dFs=np.asarray(dFs), v0s=np.asarray(v0s), model=model, n=n, mode=mode, out=out, t1=t1)
        return {"n": 24, "dt": 1e-5, "maps": {
            "0.3": {"exponent": -0.52, "exponent_stderr": 0.03, "largest_stable_dF_over_F0cr": 12.0},
            "0": {"buckles_for_every_dF_gt_0": True, "stable": 0}}}

    monkeypatch.setattr(sm, "stability_map", stability_map)
    res = e3m.e3(str(tmp_path), "tiny", False)
    assert asked["mus"] == (0.3, 0.0) and asked["model"] == "field" and asked["n"] == 24 and asked["mode"] == 6
    np.testing.assert_allclose(asked["dFs"], np.geomspace(0.5, 64.0, 4), rtol=1e-12)
    np.testing.assert_allclose(asked["v0s"], np.geomspace(1e-3, 0.2, 5), rtol=1e-12)
    assert asked["t1"] == 2.0 and asked["out"] == str(tmp_path)
    assert res == {"model": "field", "n": 24, "dt": 1e-5, "boundary_exponent": -0.52,
                   "boundary_exponent_stderr": 0.03, "boundary_exponent_theory": -0.5,
                   "largest_stable_dF_over_F0cr": 12.0, "frictionless_buckles_for_every_dF_gt_0": True,
                   "frictionless_stable_points": 0}


def test_e4s_independent_modes_bound_uses_each_realizations_own_noise():
    """The random velocity's critical load if each mode buckled alone from its own modal velocity:
    realization r at the i-th μ draws its noise from the key the searches use for it,
    fold_in(key(seed), i·realizations + r), and the bound is P7's least ΔF over modes 1..499,
    averaged over the realizations."""
    import jax
    import jax.numpy as jnp

    from jaxrod import theory
    from jaxrod.params import RodChannel
    from jaxrod.perturbations import GRID, scene_noise_modes

    e4m = importlib.import_module("jaxrod.experiments.e4.field")
    got = e4m._independent_modes(np.array([0.2, 0.5]), 15e-3, 2, seed=4)
    rod = RodChannel.reference(mu=0.5)
    m = jnp.arange(1, GRID)
    per = [float(jnp.min(theory.critical_load_velocity(
        rod, m, jnp.abs(scene_noise_modes(jax.random.fold_in(jax.random.key(4), 2 + r), 15e-3)) / rod.R)))
        - float(theory.reference_load(rod)) for r in range(2)]
    assert got.shape == (2,) and got[1] == pytest.approx(np.mean(per), rel=1e-12)
    assert per[0] != per[1] and got[0] != got[1]


def test_e4_without_a_set_resolution_takes_each_perturbations_default_from_the_scene(tmp_path, monkeypatch):
    """With `n` unset (the full setting) each case's searches run at the scene's default size for
    its perturbation: 499 nodes for the random velocity (every mode of the 500-segment noise grid)."""
    from jaxrod.experiments._settings import _settings
    from jaxrod.params import RodChannel
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    e4m = importlib.import_module("jaxrod.experiments.e4.field")
    seen = {}

    class Curve:
        def __init__(self, root):
            self.root, self.result, self.evaluations = root, np.zeros(root.shape, int), np.ones(root.shape, int)

    def curve(mus, amp, perturbation, realizations, **kw):
        seen.setdefault(perturbation, set()).add(kw["n"])
        return Curve(np.ones((len(mus), realizations))), None

    monkeypatch.setattr(e4m, "_settings", lambda quick: {**_settings("tiny"), "n": None})
    monkeypatch.setattr(jaxrod.boundary, "critical_load_curve", curve)
    monkeypatch.setattr(e4m, "_frictionless_dF", lambda s, amp, kind: (0.5, 0))
    monkeypatch.setattr(e4m, "_independent_modes", lambda mus, amp, reals, seed: np.full(len(mus), 3.0))
    e4m.e4(str(tmp_path), "tiny", False)
    assert seen["random-velocity"] == {499}
    rod = RodChannel.reference()
    assert seen["sine"] == {Scene(rod, 300.0, make_perturbation("sine", 15e-3), "field").size()}
    assert seen["random-position"] == {Scene(rod, 300.0, make_perturbation("random-position", 2.0), "field").size()}


def test_e6_checks_rolling_at_each_setting_with_loads_to_check(tmp_path, monkeypatch):
    """Where the setting lists 3D loads (quick and full), E6 also runs the rolling check (a rod the
    field model calls stuck, friction at the surface and at the axis) and records what it returns."""
    monkeypatch.setattr(jaxrod.boundary, "critical_load", lambda rod, amplitude, **kw: (_Root(20.0), None))
    monkeypatch.setattr(exp3d, "e6_full", lambda out, quick, progress: {})
    monkeypatch.setattr(exp3d, "crosscheck_critical_velocity",
                        lambda dFs, n, progress, friction_at="surface": {"progress": progress})
    monkeypatch.setitem(exp3d.SIZES, "tiny", {**exp3d.SIZES["tiny"], "dFs": (5.0, 10.0), "n_cross": 8})
    monkeypatch.setattr(exp3d, "rolling_check", lambda dF, n: {"dF": dF, "n": n})
    res = e6m.e6(str(tmp_path), "tiny", True)
    assert res["rolling_check"] == {"dF": 20.0, "n": 8}
    assert res["crosscheck_critical_velocity"] == {"progress": True}  # the 3D cross-check reports as it goes


def test_e6_takes_the_spectrum_before_at_the_first_save_the_perturbation_has_moved(e6_tiny):
    """The spectrum "before" is that of the first saved state that is not the straight rod: the
    first save for a random position (displaced from the start), the second for a sine velocity
    (the rod starts straight and moving). Each case records its run's verdict, buckling time and
    energy balance."""
    from jaxrod.modal import modal_spectrum
    from jaxrod.params import RodChannel
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    import jax

    res, _, out = e6_tiny
    rows = list(csv.DictReader(open(out / "e6_spectra.csv")))
    cases = [("sine mode 6, μ = 0.3, ΔF = 5 N, v₀ = 35 mm/s", 0.3, 5.0, make_perturbation("sine", 35e-3, 6), 1),
             ("random position, μ = 0.9, ΔF = 40 N", 0.9, 40.0,
              make_perturbation("random-position", 2.0, 6, jax.random.key(6)), 0)]
    for label, mu, dF, pert, first in cases:
        sol = Scene(RodChannel.reference(mu=mu), dF, pert, "field", 24).run(t1=0.5, n_save=501)
        q = np.asarray(sol.q)
        r = res[label]  # the run's verdict and its energy balance, as the run reports them
        assert r["buckled"] == bool(sol.buckled) and r["t_buckle"] == pytest.approx(float(sol.t_buckle), nan_ok=True)
        assert r["energy_balance_error"] == pytest.approx(float(sol.energy_balance_error()), rel=1e-9, abs=1e-15)
        assert not np.any(q[:first] != 0) and np.any(q[first] != 0)
        want = np.asarray(modal_spectrum(q[first], 24))
        got = [float(row["power_before"]) for row in rows if row["case"] == label]
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-15)
