"""E3's 3D boundary search around a synthetic label (the 3D rod replaced by a known boundary
v*(ΔF) = c·ΔF^−½, the field model's search by a guess 3 % off it): the brackets, the fitted
exponent, the runs file and its replay, and what the result records. The real 3D label is
tested in tests/test_e3_rod3d.py."""

import csv
import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod import boundary
from jaxrod.experiments.e3 import rod3d as e3

C = 0.1  # v* = C·ΔF^−½ [m/s]


def _true(dF):
    return C / math.sqrt(dF)


class Calls(list):
    """The labels asked for, (ΔF, v₀) in order; `built`: the arguments each label was made with."""

    def __init__(self):
        super().__init__()
        self.built = []


@pytest.fixture
def synthetic(monkeypatch):
    calls = Calls()

    def label_3d(rod, n, dt, t1, friction_at="surface", ends="pinned", sink=e3.SINK, scheme="implicit"):
        calls.built.append(dict(mu=float(rod.mu_s), n=n, dt=dt, t1=t1, friction_at=friction_at, ends=ends, sink=sink,
                                scheme=scheme))

        def buckled(dF, v0):
            calls.append((float(dF), float(v0)))
            return 1.0 if float(v0) > _true(float(dF)) else 0.0
        return buckled

    class Root:
        def __init__(self, root):
            self.root = root

    monkeypatch.setattr(e3, "label_3d", label_3d)
    monkeypatch.setattr(boundary, "critical_velocity", lambda rod, dF, **kw: (Root(1.03 * _true(dF)), None))
    return calls


def test_boundary_3d_brackets_a_known_boundary_and_fits_its_exponent(tmp_path, synthetic):
    runs = tmp_path / "runs.csv"
    res = e3.boundary_3d([20.0, 5.0, 80.0], n=8, mu=0.2, rtol=0.01, width=0.04, runs_csv=str(runs), ends="clamped",
                         dt=1e-5, progress=False)
    assert [p["dF"] for p in res["points"]] == [5.0, 20.0, 80.0]  # sorted
    first = synthetic[:2]  # the first bracket: the field's value times 1 ∓ width
    assert first == [(5.0, pytest.approx(1.03 * _true(5.0) * 0.96, rel=1e-12)),
                     (5.0, pytest.approx(1.03 * _true(5.0) * 1.04, rel=1e-12))]
    for p in res["points"]:
        lo, hi = p["bracket"]
        assert lo < _true(p["dF"]) < hi and hi / lo - 1 <= 0.01
        assert p["rod3d"] == pytest.approx(math.sqrt(lo * hi), rel=1e-12)
        assert p["field"] == pytest.approx(1.03 * _true(p["dF"]), rel=1e-12)
    assert res["exponent_rod3d"] == pytest.approx(-0.5, abs=0.01)
    assert res["exponent_field"] == pytest.approx(-0.5, abs=1e-9)
    assert res["exponent_theory"] == -0.5
    # one label for every load, made with the search's settings
    assert synthetic.built == [dict(mu=pytest.approx(0.2, rel=1e-6), n=8, dt=1e-5, t1=0.4, friction_at="surface",
                                    ends="clamped", sink=e3.SINK, scheme="implicit")]
    assert {k: res[k] for k in ("n_segments", "mu", "ends", "friction_at", "rtol", "dt", "t1", "scheme", "sink")} == dict(
        n_segments=8, mu=0.2, ends="clamped", friction_at="surface", rtol=0.01, dt=1e-5, t1=0.4, scheme="implicit",
        sink=e3.SINK)
    # F⁰ of the rod at μ (the load the ΔF are measured from), for a reader of the file
    assert res["F0"] == pytest.approx(float(jr.theory.reference_load(jr.RodChannel.reference(mu=0.2))), rel=1e-12)
    rows = list(csv.DictReader(open(runs)))
    assert len(rows) == len(synthetic) == sum(p["runs"] for p in res["points"])
    assert {(r["n_segments"], r["mu"], r["ends"], r["scheme"]) for r in rows} == {("8", "0.2", "clamped", "implicit")}
    assert all(r["buckled"] == str(int(float(r["v0"]) > _true(float(r["dF"])))) for r in rows)


def test_boundary_3d_replays_finished_runs_of_the_same_settings_only(tmp_path, synthetic):
    runs = str(tmp_path / "runs.csv")
    kw = dict(n=8, rtol=0.02, runs_csv=runs, dt=1e-5, progress=False)
    first = e3.boundary_3d([10.0], **kw)
    n_first = len(synthetic)
    again = e3.boundary_3d([10.0], **kw)
    assert len(synthetic) == n_first  # every label read back from the file
    assert again["points"][0]["bracket"] == first["points"][0]["bracket"]
    assert again["points"][0]["runs"] == first["points"][0]["runs"] > 0  # the labels it used, new or not
    assert again["points"][0]["seconds_new_runs"] == 0.0 <= first["points"][0]["seconds_new_runs"]
    assert first["points"][0]["seconds_new_runs"] <= first["points"][0]["seconds"]
    e3.boundary_3d([10.0], ends="clamped", **kw)  # other ends: other runs
    assert len(synthetic) == 2 * n_first
    assert np.isfinite(first["points"][0]["rod3d"])


def test_write_boundary_writes_the_result_whole_and_one_plain_row_per_load(tmp_path, synthetic):
    import json

    res = e3.boundary_3d([5.0, 20.0], n=8, rtol=0.01, dt=1e-5, progress=False)
    stem = str(tmp_path / "b")
    e3.write_boundary(res, stem)
    assert json.loads(open(stem + ".json").read()) == json.loads(json.dumps(res))
    rows = list(csv.DictReader(open(stem + ".csv")))
    assert [float(r["dF"]) for r in rows] == [5.0, 20.0]
    for r, p in zip(rows, res["points"]):
        assert float(r["rod3d_mm_s"]) == pytest.approx(1e3 * p["rod3d"], rel=1e-9)
        assert float(r["bracket_lo_mm_s"]) == pytest.approx(1e3 * p["bracket"][0], rel=1e-9)
        assert float(r["bracket_hi_mm_s"]) == pytest.approx(1e3 * p["bracket"][1], rel=1e-9)
        assert float(r["difference_percent"]) == pytest.approx(100 * (p["rod3d"] / p["field"] - 1), rel=1e-9)
        assert (r["n_segments"], r["runs"]) == ("8", str(p["runs"]))
        assert (float(r["mu"]), float(r["t1"]), float(r["dt"])) == (res["mu"], res["t1"], res["dt"])
        assert float(r["field_mm_s"]) == pytest.approx(1e3 * p["field"], rel=1e-9)
    assert (tmp_path / "b.png").stat().st_size > 0


def test_write_boundary_writes_a_failed_load_with_no_bracket(tmp_path, synthetic):
    """A load whose search found no bracket (`bracket` None, v₀* NaN) is written as a row with
    empty-valued bracket columns (NaN), beside the loads that have one."""
    res = e3.boundary_3d([5.0, 20.0], n=8, rtol=0.01, dt=1e-5, progress=False)
    res["points"][1].update(bracket=None, rod3d=math.nan)
    stem = str(tmp_path / "b")
    e3.write_boundary(res, stem)
    rows = list(csv.DictReader(open(stem + ".csv")))
    assert float(rows[0]["bracket_hi_mm_s"]) == pytest.approx(1e3 * res["points"][0]["bracket"][1], rel=1e-9)
    assert all(math.isnan(float(rows[1][k])) for k in ("bracket_lo_mm_s", "bracket_hi_mm_s", "rod3d_mm_s"))
    assert float(rows[1]["dF"]) == 20.0


def test_e3_searches_the_settings_loads_and_writes_the_boundary_under_its_scheme(tmp_path, monkeypatch):
    """`e3` (3D part) at an explicit segment count: the boundary search gets the setting's loads,
    tolerance and horizon and the runs file under `out`; the boundary is written under a name
    holding n and the scheme; the summary reports the exponents beside the paper's and counts
    the runs and the bracketed points."""
    from jaxrod.experiments.paper3d import SIZES

    seen = {}
    res = dict(scheme="implicit", exponent_rod3d=-0.48, exponent_rod3d_stderr=0.02, exponent_field=-0.51,
               exponent_field_stderr=0.01, points=[dict(runs=5, bracket=[0.1, 0.11]), dict(runs=7, bracket=None)])

    def boundary_3d(loads, **kw):
        seen["search"] = (list(loads), kw)
        return res

    monkeypatch.setattr(e3, "boundary_3d", boundary_3d)
    monkeypatch.setattr(e3, "write_boundary", lambda r, stem: seen.update(written=(r, stem)))
    got = e3.e3(str(tmp_path), "tiny", False, n=9)
    S = SIZES["tiny"]
    assert seen["search"] == (list(S["loads"]), dict(n=9, rtol=S["rtol"], t1=S["t1_e3"],
                                                     runs_csv=str(tmp_path / "rod3d_runs.csv"), progress=False))
    assert seen["written"] == (res, str(tmp_path / "rod3d_boundary_n9_implicit"))
    assert got == dict(n=9, loads=list(S["loads"]), exponent_rod3d=-0.48, exponent_rod3d_stderr=0.02,
                       exponent_field=-0.51, exponent_field_stderr=0.01, exponent_paper=e3.PAPER_E3_EXPONENT,
                       runs=[5, 7], converged=1)


def test_boundary_3d_reports_each_load_with_its_3d_and_field_values(tmp_path, synthetic, capsys):
    """With progress, one line per run and one per load: the 3D value (the bracket's geometric mean),
    the field model's, and how far the first is from the second, in per cent."""
    res = e3.boundary_3d([10.0], n=8, rtol=0.02, runs_csv=str(tmp_path / "runs.csv"), dt=1e-5, progress=True)
    p = res["points"][0]
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == p["runs"] + 1 and all(line.startswith("  ΔF = 10 N, v0 = ") for line in lines[:-1])
    assert lines[-1] == (f"ΔF = 10 N: 3D {1e3 * p['rod3d']:.3f} mm/s, field {1e3 * p['field']:.3f} mm/s "
                         f"({100 * (p['rod3d'] / p['field'] - 1):+.1f} %)")
    assert -3.0 < 100 * (p["rod3d"] / p["field"] - 1) < -1.0  # the field's guess is 3 % above the true boundary
