"""A stability map's columns searched by bisection (`jaxrod.map_columns`): the bisection's rules on
a stand-in sweep, and a small single-mode map searched against the same map filled."""

import csv
import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod import map_columns as mc
from jaxrod import stability_map as sm


def _stand_in(boundary, fail=()):
    """A sweep whose member at (dF, v0) buckles iff v0 >= boundary[dF], fails at the (dF, v0) in
    `fail`; it records the members of each call."""
    calls, fixed = [], []

    def fake(spec, inputs, combine, path, progress, chunk_size):
        assert combine == "zip"
        dF, v0 = np.asarray(inputs["dF"]), np.asarray(inputs["amplitude"])
        calls.append((spec, list(zip(dF.tolist(), v0.tolist())), path, chunk_size))
        fixed.append({k: v for k, v in inputs.items() if k not in ("dF", "amplitude")})
        b = np.array([v >= boundary[d] for d, v in zip(dF, v0)])
        res = np.array([1 if (d, v) in fail else 0 for d, v in zip(dF, v0)])
        t = np.where(b, 0.1, math.inf)
        out = dict(buckled=b, t_buckle=t, dominant_mode=np.full(len(b), 6), max_theta=np.where(b, 0.3, 0.01),
                   final_theta=np.where(b, 0.3, 0.0), stuck=~b, t_stop=np.where(b, 0.1, 0.4), result=res)
        return jr.SweepResult({"dF": dF, "amplitude": v0, "index": np.arange(len(b))}, out, (len(b),),
                              ("dF", "amplitude"), {"n": spec.n, "dt": spec.dt, "shape": [len(b)]})

    fake.fixed = fixed
    return fake, calls


@pytest.fixture
def _resolution(monkeypatch):
    """The grid's resolution, as `jaxrod.sweeps.resolved` would give it (12 segments, 1e-4 s),
    recorded with the inputs it was asked for."""
    asked = []

    def fake(spec, inputs, combine="grid"):
        asked.append({k: np.asarray(v).tolist() for k, v in inputs.items()})
        return jr.SweepSpec(**{**spec.__dict__, "n": 12, "dt": 1e-4})

    monkeypatch.setattr(mc, "resolved", fake)
    return asked


def test_each_column_is_bisected_and_the_rest_labelled_from_its_boundary(monkeypatch, _resolution):
    """Three columns of 8 amplitudes (1..8) with boundaries at 3.5 (the first buckled cell 4: index
    3), 0 (all buckle) and 100 (none does): bisection between −1 and 8 (amplitudes 4, 2, 3 for the
    first; 4, 2, 1 for the second; 4, 6, 7, 8 for the third) labels every cell as the full grid
    would, in 4 rounds of at most 3 runs (10 runs for 24 cells); every round runs at the whole
    grid's size and step, in chunks of 3 (the loads: one compiled program for every round); the
    cells that ran keep their runs' numbers, the others NaN times, mode −1, not stuck, result 0."""
    fake, calls = _stand_in({1.0: 3.5, 2.0: 0.0, 3.0: 100.0})
    monkeypatch.setattr(mc, "sweep", fake)
    v0 = np.arange(1.0, 9.0)
    res = mc.search_columns(jr.SweepSpec(model="mode"), [1.0, 2.0, 3.0], v0, path="p", progress=False)
    assert res.shape == (3, 8) and res.names == ("dF", "amplitude")
    assert res.grid("buckled").tolist() == [[v >= 3.5 for v in v0], [True] * 8, [False] * 8]
    assert [m for _, m, _, _ in calls] == [[(1.0, 4.0), (2.0, 4.0), (3.0, 4.0)], [(1.0, 2.0), (2.0, 2.0), (3.0, 6.0)],
                                           [(1.0, 3.0), (2.0, 1.0), (3.0, 7.0)], [(3.0, 8.0)]]
    assert [p for _, _, p, _ in calls] == ["p_round0", "p_round1", "p_round2", "p_round3"]
    assert all((s.n, s.dt, c) == (12, 1e-4, 3) for s, _, _, c in calls)
    assert _resolution == [{"dF": [1.0, 2.0, 3.0], "amplitude": v0.tolist()}]
    ran = res.grid("ran")
    assert ran.sum() == 10 and res.meta["runs"] == 10 and res.meta["rounds"] == 4 and res.meta["fill"] == "search"
    assert ran[0].tolist() == [False, True, True, True, False, False, False, False]
    assert np.all(np.isnan(res.grid("t_buckle")[~ran])) and np.all(res.grid("dominant_mode")[~ran] == -1)
    assert not res.grid("stuck")[~ran].any() and np.all(res.grid("result") == 0)
    assert res.grid("t_stop")[0, 2] == 0.4 and res.grid("t_stop")[0, 3] == 0.1  # the runs' own numbers
    assert res.inputs["amplitude"].tolist() == list(v0) * 3 and res.inputs["index"].tolist() == list(range(24))


def test_a_guessed_boundary_takes_two_runs_a_column_and_any_guess_labels_every_cell_right(monkeypatch, _resolution):
    """From the exact guess: the two cells either side of the guessed boundary in one round (2
    runs; 1 where the whole column buckles or none of it does), in chunks of twice the column
    count. From every guess 0..8 for every boundary 0..8 (8 amplitudes): the labels of the full
    grid; one round and at most 2 runs from the exact guess. A guess out of [0, 8] or of another
    length is refused."""
    v0 = np.arange(1.0, 9.0)
    fake, calls = _stand_in({1.0: 3.5, 2.0: 0.0, 3.0: 100.0})
    monkeypatch.setattr(mc, "sweep", fake)
    res = mc.search_columns(jr.SweepSpec(model="mode"), [1.0, 2.0, 3.0], v0, guess=[3, 0, 8], fixed={"mu": 0.05},
                            progress=False)
    assert _resolution == [{"dF": [1.0, 2.0, 3.0], "amplitude": v0.tolist(), "mu": 0.05}]
    assert [m for _, m, _, _ in calls] == [[(1.0, 3.0), (2.0, 1.0), (3.0, 8.0), (1.0, 4.0)]]  # first cells, then second
    assert [c for _, _, _, c in calls] == [6] and fake.fixed == [{"mu": 0.05}]  # μ reaches every run as an input
    assert res.grid("buckled").tolist() == [[v >= 3.5 for v in v0], [True] * 8, [False] * 8]
    for first in range(9):  # the first buckled cell
        for g in range(9):
            fake, calls = _stand_in({1.0: first + 0.5})
            monkeypatch.setattr(mc, "sweep", fake)
            res = mc.search_columns(jr.SweepSpec(model="mode"), [1.0], v0, guess=[g], progress=False)
            assert res.grid("buckled")[0].tolist() == [j >= first for j in range(8)], (first, g)
            runs = int(res.grid("ran").sum())
            assert runs <= (2 if g == first else 8) and (g != first or first in (0, 8) or runs == 2), (first, g, runs)
            assert g != first or len(calls) == 1, (first, g)
    for bad in ([9, 0], [0]):
        with pytest.raises(ValueError, match=r"guess = \[.*\] is invalid: expected one index in \[0, 8\] per load"):
            mc.search_columns(jr.SweepSpec(model="mode"), [1.0, 2.0], v0, guess=bad, progress=False)


def test_a_column_with_a_failed_run_is_run_whole_and_bad_amplitudes_are_refused(monkeypatch, _resolution):
    fake, calls = _stand_in({1.0: 3.5, 2.0: 3.5}, fail={(2.0, 3.0)})
    monkeypatch.setattr(mc, "sweep", fake)
    res = mc.search_columns(jr.SweepSpec(model="mode"), [1.0, 2.0], np.arange(1.0, 9.0), progress=False)
    assert res.grid("ran")[1].all() and res.grid("result")[1].tolist() == [0, 0, 1, 0, 0, 0, 0, 0]
    assert res.grid("ran")[0].sum() == 3 and calls[-1][1] == [(2.0, v) for v in (1.0, 5.0, 6.0, 7.0, 8.0)]
    assert res.grid("buckled")[1].tolist() == [False, False, False, True, True, True, True, True]
    with pytest.raises(ValueError, match=r"v0 = \[2.0, 1.0\] is invalid"):
        mc.search_columns(jr.SweepSpec(model="mode"), [1.0], [2.0, 1.0], progress=False)


def test_a_searched_single_mode_map_labels_every_cell_as_the_filled_map(tmp_path):
    """The single mode's map at μ = 0.3 over 3 loads × 9 amplitudes, searched and filled: the same
    labels in every cell and the same fitted boundary, from 10 runs instead of 27; map.csv says
    which cells ran; map.json the fill and its runs."""
    dF, v0 = [1.0, 4.0, 16.0], np.geomspace(2e-3, 0.2, 9).tolist()
    full = sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model="mode", out=str(tmp_path / "grid"), progress=False,
                            t1=0.5, fill="grid")
    found = sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model="mode", out=str(tmp_path / "search"), progress=False,
                             t1=0.5, fill="search")
    a, b = full["maps"]["0.3"], found["maps"]["0.3"]
    assert 0 < a["stable"] < 27 and (a["buckled"], a["stable"]) == (b["buckled"], b["stable"])
    assert a["boundary_v0"] == b["boundary_v0"] and a["exponent"] == b["exponent"]
    assert "fill" not in full and found["fill"] == {"method": "search", "runs": {"0.3": 10}, "cells": {"0.3": 27}}
    rows = {tmp: list(csv.DictReader(line for line in open(tmp_path / tmp / "map.csv") if not line.startswith("#")))
            for tmp in ("grid", "search")}
    assert [r["buckled"] for r in rows["grid"]] == [r["buckled"] for r in rows["search"]]
    assert "ran" not in rows["grid"][0] and sum(r["ran"] == "1" for r in rows["search"]) == 10
    with pytest.raises(ValueError, match="fill = 'cells' is invalid"):
        sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model="mode", out=None, progress=False, fill="cells")


def test_the_map_command_searches_columns_on_request(tmp_path, capsys):
    """`jaxrod map --fill search` on the single mode: the line saying how many cells ran, and
    map.csv's `ran` column; `--fill` outside grid/search is refused by argparse, one line."""
    from jaxrod.cli import main

    out = tmp_path / "m"
    assert main(["map", "--model", "mode", "--mu", "0.3", "--dF", "1,16", "--v0", "0.002:0.2:5", "--t1", "0.5",
                 "--fill", "search", "--out", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    rows = list(csv.DictReader(line for line in open(out / "map.csv") if not line.startswith("#")))
    ran = sum(r["ran"] == "1" for r in rows)
    assert f"column search: mu = 0.3: {ran} of 10 cells run" in text and 0 < ran < 10
    with pytest.raises(SystemExit):
        main(["map", "--fill", "cells"])
    assert "argument --fill: invalid choice: 'cells'" in capsys.readouterr().err


def test_the_committed_3d_map_searched_has_the_full_maps_labels_and_the_readme_its_time():
    """`results/paper/e3/map_rod3d_n500_search/map.csv` (the 3D map as `jaxrod map --model rod3d
    --n 500` makes it, columns searched) against the map that ran every cell
    (`map_rod3d_n500.csv`): the same label in each of the 960 cells, the cells it ran as many as
    `benchmarks/results/rod3d_map_search.json` says, and README's time that file's."""
    import json
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]

    def rows(path):
        with open(path) as fh:
            return {(round(float(r["mu"]), 6), round(float(r["dF"]), 9), round(float(r["v0"]), 12)): r
                    for r in csv.DictReader(line for line in fh if not line.startswith("#"))}

    found = rows(root / "results/paper/e3/map_rod3d_n500_search/map.csv")
    full = rows(root / "results/paper/e3/map_rod3d_n500.csv")
    assert len(found) == len(full) == 960 and found.keys() == full.keys()
    assert all(found[k]["buckled"] == full[k]["buckled"] for k in full)
    record = json.loads((root / "benchmarks/results/rod3d_map_search.json").read_text())
    assert sum(r["ran"] == "1" for r in found.values()) == sum(record["runs"].values()) == record["ran"]
    minutes, seconds = divmod(round(record["cold_wall_s"]), 60)
    assert f"| {minutes} min {seconds} s cold" in (root / "README.md").read_text()


def test_a_map_guided_by_another_models_map_labels_every_cell_as_the_filled_map(tmp_path):
    """A recipe with a `map_guide` (the single mode guided by the field model's map, searched at
    its own size and horizon): the searched map, every column starting at the guide's boundary,
    has the filled map's label in every cell, from at most two runs a column where the guide is
    right, and writes the guide's map beside its own (`sweep_mu0.3_field_round0`); map.json names
    the recipe (it held the object, which JSON cannot write)."""
    from typing import ClassVar

    from jaxrod.models.single_mode import SingleModeRecipe

    class Guided(SingleModeRecipe):
        map_guide: ClassVar[str | None] = "field"

    dF, v0 = [1.0, 4.0, 16.0], np.geomspace(2e-3, 0.2, 9).tolist()
    full = sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model="mode", out=str(tmp_path / "grid"), progress=False,
                            t1=0.5, fill="grid")
    found = sm.stability_map(mus=(0.3,), dF=dF, v0=v0, model=Guided(), out=str(tmp_path / "search"), progress=False,
                             t1=0.5, fill="search", curve_rtol=None)
    a, b = full["maps"]["0.3"], found["maps"]["0.3"]
    assert (a["buckled"], a["stable"]) == (b["buckled"], b["stable"]) and a["boundary_v0"] == b["boundary_v0"]
    assert found["fill"]["runs"]["0.3"] <= 10  # the plain bisection's count on this grid (the test above)
    assert (tmp_path / "search" / "sweep_mu0.3_field_round0").is_dir()
    assert found["model"] == "Guided"  # an unregistered recipe is named by its class in map.json
