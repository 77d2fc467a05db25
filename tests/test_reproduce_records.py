"""What `jaxrod reproduce` records around each experiment, with the experiments replaced by stubs
(the experiments themselves are tested in their own files): which runner each name reaches, the
segments passed to the 3D parts, and the entries merged into results.json."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from jaxrod import reproduce as rp


def _stub(calls, name):
    def run(out, quick, progress, **kw):
        calls.append((name, out, quick, progress, kw))
        return {"value": name}
    return run


def test_all_runs_the_paper_experiments_in_order_and_records_each_with_its_settings(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(rp, "_runners", lambda: {k: _stub(calls, k) for k in rp.EXPERIMENTS})
    (tmp_path / "results.json").write_text(json.dumps({"earlier": {"value": 1}}))
    res = rp.reproduce("all", out=str(tmp_path), quick="tiny", progress=False)
    assert [c[0] for c in calls] == list(rp.PAPER)  # lock-up only by name
    assert all(c[1] == str(tmp_path / c[0]) and c[2] == "tiny" and c[3] is False for c in calls)
    on_disk = json.loads((tmp_path / "results.json").read_text())
    assert on_disk == res and set(on_disk) == {"earlier", *rp.PAPER}
    for name in rp.PAPER:
        entry = on_disk[name]
        assert entry["value"] == name and entry["quick"] == "tiny" and entry["seconds"] >= 0
        assert isinstance(entry["jax"], str) and entry["devices"] >= 1


def test_3d_parts_get_the_segments_asked_for_and_are_recorded_under_their_own_names(tmp_path, monkeypatch):
    from jaxrod.experiments.e3 import rod3d as e3
    from jaxrod.experiments.e4 import rod3d as e4
    from jaxrod.experiments.e5 import rod3d as e5
    from jaxrod.experiments.e6 import rod3d as e6

    calls = []
    for mod, attr, name in ((e3, "e3", "e3"), (e4, "e4", "e4"), (e5, "e5", "e5"), (e6, "e6c", "e6")):
        monkeypatch.setattr(mod, attr, _stub(calls, name))
    res = rp.reproduce(["e5", "e3"], out=str(tmp_path), quick=True, progress=False, model="rod3d", n=12)
    assert [(c[0], c[4]) for c in calls] == [("e5", {"n": 12}), ("e3", {"n": 12})]
    assert set(res) == {"e5_rod3d", "e3_rod3d"} and res["e5_rod3d"]["value"] == "e5"
    assert res["e3_rod3d"]["quick"] is True


@pytest.mark.parametrize("kw, match", [
    (dict(which="e2", model="rod3d"), r"unknown experiment\(s\) \['e2'\] for model 'rod3d': expected \('e3', 'e4', "
                                      r"'e5', 'e6'\)\.$"),
    (dict(which="e9"), r"unknown experiment\(s\) \['e9'\] for model 'field': .* or 'all'\.$"),
    (dict(which="e3", model="rod3d", n=3), r"^n = 3 is invalid: expected an int >= 4"),
    (dict(which="e3", model="beam"), r"^model = 'beam' is invalid: expected one of \('field', 'rod3d'\)\.$"),
])
def test_bad_requests_are_one_line_errors_naming_what_is_allowed(tmp_path, kw, match):
    with pytest.raises(ValueError, match=match):
        rp.reproduce(out=str(tmp_path), progress=False, **kw)
    assert not (tmp_path / "results.json").exists()


def test_an_experiments_numpy_numbers_are_written_as_plain_json_and_progress_is_told(tmp_path, monkeypatch, capsys):
    """NumPy scalars and arrays in an experiment's result are written as JSON numbers and lists
    (anything else as its text); with progress each experiment says when it starts and ends."""
    class Thing:
        def __str__(self):
            return "a thing"

    monkeypatch.setattr(rp, "_runners", lambda: {"e2": lambda out, quick, progress: {
        "x": np.float64(1.5), "i": np.int64(2), "a": np.arange(3), "m": np.eye(2, dtype=np.float32), "t": Thing()}})
    clock = iter([10.0, 12.26])
    monkeypatch.setattr(rp, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    rp.reproduce("e2", out=str(tmp_path), quick=True, progress=True)
    e2 = json.loads((tmp_path / "results.json").read_text())["e2"]
    assert {k: e2[k] for k in "xiamt"} == {"x": 1.5, "i": 2, "a": [0, 1, 2], "m": [[1.0, 0.0], [0.0, 1.0]],
                                         "t": "a thing"}
    assert e2["seconds"] == 2.3 and e2["quick"] is True
    assert capsys.readouterr().out.splitlines() == ["[e2] running (quick) ...", "[e2] done in 2.3 s"]
