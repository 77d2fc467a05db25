"""The committed lock-up curve (`results/lockup/`, `jaxrod reproduce lockup`) against what the
README and docs/physics.md §8 say of it: every bracket called bracketed is within 3 % and rests
on a steady stage at or below the bound and one above it (or a lock); the soft-string columns are
`chain`'s values at the bound, recomputed here; and the README's lock-up figures are the files'."""

import csv
import json
import math
import pathlib

import jax
import pytest

from jaxrod.lockup import chain
from jaxrod.lockup.push import push_rod, units

ROOT = pathlib.Path(__file__).parent.parent
DATA = ROOT / "results" / "lockup"

jax.config.update("jax_enable_x64", True)


def _rows(name):
    with open(DATA / name) as fh:
        return list(csv.DictReader(fh))


def test_every_bracket_rests_on_steady_stages_on_either_side_of_the_bound():
    stages = _rows("stages.csv")
    for row in _rows("curve.csv"):
        if row["status"] != "bracketed" or row["kind"] != "run" or row["protocol"] != "staircase":
            continue  # the other protocols' stages are in stage_protocols.json (the test below)
        lo, hi = float(row["lo"]), float(row["hi"])
        assert 0 < hi - lo <= 0.03 * hi, row
        far = row["quantity"] == "F_far_max"
        mine = [s for s in stages if s["n_segments"] == row["n_segments"] and s["push_speed"] == row["push_speed"]
                and s["varies"] == ("far_load" if far else "mu")
                and (not far or s["muL_over_ell"] == row["muL_over_ell"])]
        f_c = float(row["entry_force_bound"])
        below = [s for s in mine if math.isclose(float(s["parameter"]), lo) and s["status"] == "sliding"]
        above = [s for s in mine if math.isclose(float(s["parameter"]), hi)]
        assert below and float(below[-1]["f_in"]) <= f_c, row
        assert above and (above[-1]["status"] == "locked" or float(above[-1]["f_in"]) > f_c), row


def test_the_soft_string_columns_are_the_chain_at_the_bound():
    summary = json.loads((DATA / "curve.json").read_text())
    for row in _rows("curve.csv"):
        if row["quantity"] != "F_far_max" or row["protocol"] != "staircase":
            continue
        rod = push_rod(float(row["L_over_ell"]), summary["r_over_ell"], 1.0)
        F0, ell = units(rod)
        X, f_c = float(row["muL_over_ell"]), float(row["entry_force_bound"])
        mu = X * ell / float(rod.L)
        for onset in ("chen", "wu_juvkam_wold"):
            for law in ("with_weight", "without_weight"):
                got = float(chain.far_force(f_c * F0, rod.L, rod.EI, rod.rho * rod.g, rod.R, mu,
                                            helical_onset=onset, helical_law=law)) / F0
                assert float(row[f"soft_{onset}/{law}_at_fc"]) == pytest.approx(got, rel=1e-9, abs=1e-12)


def test_the_readme_quotes_the_files():
    readme = (ROOT / "README.md").read_text()
    base = [r for r in _rows("curve.csv") if r["quantity"] == "muL_lock" and r["segments_per_wave"] == "16"
            and r["push_speed"] == "0.01"]
    lo, hi = float(base[0]["lo"]), float(base[0]["hi"])
    assert f"{lo:.3f}–{hi:.3f}" in readme
    summary = json.loads((DATA / "curve.json").read_text())
    assert f"{summary['wall_s_this_call'] / 60:.1f} min" in readme


def test_the_converged_rows_are_the_rule_applied_to_the_run_rows_and_the_readme_quotes_them():
    """Each `kind = converged` row of the committed curve.csv is what
    `jaxrod.experiments.lockup.converged` gives from the file's own run rows (every point of the
    setting but μL/ℓ = 4 has one), and the README's converged figures are the file's."""
    from jaxrod.experiments import lockup as lx

    def typed(row):
        out = dict(row)
        for k in ("muL_over_ell", "push_speed", "lo", "hi", "crossing", "crossing_error"):
            out[k] = float(row[k])
        out["segments_per_wave"] = int(row["segments_per_wave"])
        return out

    rows = _rows("curve.csv")
    runs = [typed(r) for r in rows if r["kind"] == "run" and r["protocol"] != "single_step"]
    committed = [r for r in rows if r["kind"] == "converged"]
    again = lx.converged(runs, lx.SETTINGS[False])
    assert [(r["quantity"], r["muL_over_ell"]) for r in committed] == [
        ("F_far_max", "0.5"), ("F_far_max", "1.0"), ("F_far_max", "1.5"), ("F_far_max", "2.0"), ("F_far_max", "3.0"),
        ("muL_lock", "nan")]
    for row, mine in zip(committed, again):
        assert row["segments_pair"] == mine["segments_pair"]
        for k in ("quasi_static", "error_bar", "d_segments", "d_half_speed", "d_quarter_speed", "lo", "hi",
                  "bracket_lo", "bracket_hi", "d_path_lo", "d_path_hi", "path_protocols"):
            assert float(row[k]) == pytest.approx(mine[k], rel=1e-12), (row["muL_over_ell"], k)
        assert (row["converged_segments"], row["converged_speed"]) == (
            str(int(mine["converged_segments"])), str(int(mine["converged_speed"])))
    readme = (ROOT / "README.md").read_text()
    ok = [r for r in committed if r["converged_segments"] == "1" and r["converged_speed"] == "1"]
    assert ok == committed  # every point converged in segments and in speed
    assert [r["segments_pair"] for r in committed] == ["64/32", "32/16", "32/16", "32/16", "32/16 at v/4", "32/16"]
    three = committed[4]  # judged at its own speed (2.5 mm/s); the faster pairs' largest change kept
    assert float(three["d_segments_faster"]) == pytest.approx(0.6996 / 0.7198 - 1, abs=1e-3)
    assert f"at 2.5 mm/s {100 * float(three['d_segments']):.1f} %): it is judged at 2.5 mm/s".replace("-", "−") in readme
    for r in ok:
        assert f"{float(r['quasi_static']):.3f} ± {float(r['error_bar']):.3f}" in readme


def test_every_run_rows_crossing_is_read_from_its_own_stages():
    """The `crossing` and `crossing_error` of each staircase run row of curve.csv are
    `jaxrod.lockup.staircase.crossing` of that run's stages in stages.csv (the same lane, segments
    and speed), and the crossing lies inside the run's bracket where it is closed."""
    from jaxrod.lockup.staircase import crossing

    stages = _rows("stages.csv")
    runs = [r for r in _rows("curve.csv") if r["kind"] == "run" and r["protocol"] == "staircase"]
    read = 0
    for row in runs:
        far = row["quantity"] == "F_far_max"
        mine = [dict(s, parameter=float(s["parameter"]), f_in=float(s["f_in"])) for s in stages
                if s["n_segments"] == row["n_segments"] and s["push_speed"] == row["push_speed"]
                and s["varies"] == ("far_load" if far else "mu") and (not far or s["muL_over_ell"] == row["muL_over_ell"])]
        got = crossing(mine, float(row["entry_force_bound"]))
        if got is None:
            assert row["crossing"] == "nan", row
            continue
        read += 1
        assert (float(row["crossing"]), float(row["crossing_error"])) == (pytest.approx(got[0], rel=1e-12),
                                                                          pytest.approx(got[1], rel=1e-9, abs=1e-15))
        if row["status"] == "bracketed":
            assert float(row["lo"]) <= got[0] <= float(row["hi"]), row
    assert read == len(runs) - 1  # all but μL/ℓ = 4, past the lock-up length


def test_a_single_step_to_the_far_load_slides_at_a_higher_entry_force_than_the_staircase():
    """`results/lockup/path/`: the base staircase's far loads at μL/ℓ = 1, reached from the straight
    rod in one step, slide (the verdict) at entry forces 26–29 % above the staircase's steady
    stage at the same far load, as docs/physics.md §8 and the README say."""
    stages = {round(float(s["parameter"]), 4): float(s["f_in"]) for s in _rows("stages.csv")
              if s["muL_over_ell"] == "1.0" and s["varies"] == "far_load" and s["n_segments"] == "37"
              and s["push_speed"] == "0.01" and s["status"] == "sliding"}
    rises = []
    for far in (2.7709, 2.8458):
        d = json.loads((DATA / "path" / f"single_step_muL1_far{far:.4f}" / "lockup.json").read_text())
        assert d["verdict"]["status"] == "sliding" and d["mu_L_over_ell"] == pytest.approx(1.0)
        assert d["far_load_over_F0"] == pytest.approx(far, abs=1e-4)
        rises.append(d["verdict"]["force"][1] / stages[far] - 1)
    assert [f"+{100 * r:.0f} %" for r in rises] == ["+26 %", "+29 %"]
    # at μL/ℓ = 2 (its lane: L = 2ℓ, μ = 1, 37 segments) the band is a few per cent
    stages2 = {round(float(s["parameter"]), 4): float(s["f_in"]) for s in _rows("stages.csv")
               if s["muL_over_ell"] == "2.0" and s["varies"] == "far_load" and s["n_segments"] == "37"
               and s["push_speed"] == "0.01" and s["status"] == "sliding"}
    for far, text in ((1.3310, "−0.3 %"), (1.5883, "+4.0 %")):
        d = json.loads((DATA / "path" / f"single_step_muL2_far{far:.4f}" / "lockup.json").read_text())
        assert d["verdict"]["status"] == "sliding" and d["n_segments"] == 37 and d["mu"] == 1.0
        change = 100 * (d["verdict"]["force"][1] / stages2[far] - 1)
        assert f"{change:+.1f} %".replace("-", "−") == text
    assert "(+26 % and +29 %" in (ROOT / "docs" / "physics.md").read_text()
    assert "by +29 % at μL/ℓ = 1 when the far load comes in one step" in (ROOT / "README.md").read_text()


def test_every_point_of_the_curve_has_its_single_step_row():
    """`curve.csv` holds a `single_step` row at every point of the full setting (μL/ℓ = 0.5, 1, 1.5,
    2, 3 and the lock-up length), read from its run's `lockup.json` (`jaxrod.experiments.lockup_path`):
    its entry force against the staircase's at the same parameter — −0.8 % at 0.5 and 1.5, +0.8 %
    at 3, +0.1 % at the lock-up length, −0.3 / +4.0 % at 2, +26 / +29 % at 1 — and on which side
    of that parameter the protocol puts the quantity (a steady slide at ≤ f_c: `lo`, else `hi`)."""
    rows = [r for r in _rows("curve.csv") if r["protocol"] == "single_step"]
    assert {(r["quantity"], r["muL_over_ell"]) for r in rows} == {
        ("F_far_max", x) for x in ("0.5", "1.0", "1.5", "2.0", "3.0")} | {("muL_lock", "nan")}
    ratios = {}
    for r in rows:
        d = json.loads((DATA / r["source"]).read_text())
        force = d["verdict"]["force"][1]
        assert float(r["entry_force"]) == force and r["status"] == d["verdict"]["status"]
        steady = d["verdict"]["status"] == "sliding" and force <= 6.0
        assert (r["lo"] != "nan", r["hi"] != "nan") == (steady, not steady)
        assert float(r["single_step_over_staircase"]) == pytest.approx(force / float(r["staircase_entry_force"]))
        ratios.setdefault(r["muL_over_ell"], []).append(f"{100 * (float(r['single_step_over_staircase']) - 1):+.1f}")
    assert {k: sorted(v) for k, v in ratios.items()} == {
        "0.5": ["-0.8"], "1.0": ["+26.3", "+29.2"], "1.5": ["-0.8"], "2.0": ["+4.0", "-0.3"], "3.0": ["+0.8"],
        "nan": ["+0.1"]}


def test_the_other_protocols_rows_are_the_study_files_lanes():
    """Each `curve.csv` row of another stage protocol is a lane of `stage_protocols.json` (its
    bracket, status and stage count as written there, its crossing recomputed from the lane's
    steady stages), every point of the curve has such rows, and each converged row's path band
    spans its protocols' crossings against the base run's."""
    from jaxrod.experiments.lockup_path import PROTOCOLS
    from jaxrod.lockup.staircase import crossing

    study = json.loads((DATA / "stage_protocols.json").read_text())
    rows = _rows("curve.csv")
    mine = [r for r in rows if r["protocol"] in PROTOCOLS.values()]
    assert {(r["quantity"], r["muL_over_ell"]) for r in mine} == {(r["quantity"], r["muL_over_ell"])
                                                                  for r in rows if r["kind"] == "converged"}
    for r in mine:
        key = r["source"].split(":", 1)[1]
        point = "lock" if r["quantity"] == "muL_lock" else float(r["muL_over_ell"])
        (lane,) = [ln for ln in study[key]["lanes"] if ln["point"] == point]
        assert PROTOCOLS[study[key]["protocol"]] == r["protocol"] and (r["status"], int(r["stages"])) == (
            lane["status"], lane["stages"])
        got = crossing([dict(parameter=p, f_in=f, status="sliding") for p, f in lane["steady"]], 6.0)
        assert (r["crossing"] == "nan") == (got is None)
        if got is not None:
            assert float(r["crossing"]) == pytest.approx(got[0], rel=1e-12)
    for c in (r for r in rows if r["kind"] == "converged"):
        base = [r for r in rows if r["kind"] == "run" and r["protocol"] == "staircase" and r["quantity"] == c["quantity"]
                and r["muL_over_ell"] == c["muL_over_ell"] and r["segments_per_wave"] == "16" and r["push_speed"] == "0.01"]
        d = [float(r["crossing"]) / float(base[0]["crossing"]) - 1 for r in mine if r["quantity"] == c["quantity"]
             and r["muL_over_ell"] == c["muL_over_ell"] and r["crossing"] != "nan"]
        assert int(c["path_protocols"]) == len(d)
        assert (float(c["d_path_lo"]), float(c["d_path_hi"])) == (pytest.approx(min([0.0, *d])),
                                                                  pytest.approx(max([0.0, *d])))
