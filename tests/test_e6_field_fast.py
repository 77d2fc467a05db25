"""E6 with the field model (modal spectra before and after buckling) at the test suite's `tiny`
setting, with its search and the 3D rod's parts replaced by recorders (they are tested in
tests/test_experiments_rod3d_fast.py): the cases it runs, what it records of each run, and the
files it writes."""

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
    for label, dF in zip(labels, (5.0, 40.0, 21.0)):
        r = res[label]
        assert r["n"] == 24 and r["dF"] == pytest.approx(dF)
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
