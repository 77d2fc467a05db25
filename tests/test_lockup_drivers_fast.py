"""The lock-up drivers in the default suite: the experiment (`jaxrod.experiments.lockup`: its
jobs, the closed forms beside the rod, the files it writes, the onsets, one tiny run end to
end), the vmapped injection (`jaxrod.lockup.push.inject_lanes`) and the staircase
(`jaxrod.lockup.staircase`) on a straight rod of L = ℓ whose steady entry force is known in
closed form, and the edges of `verdict`, `helix_against_laws` and the closed forms' messages.

Every simulated run here is the same compiled program (10 segments, two lanes, 0.2 s per part
or stage, 11 saves, damping 20/s, the implicit scheme's own step): the first test to run pays
for the compilation and the others reuse it."""

from __future__ import annotations

import csv
import json
import math
import os

import jax
import numpy as np
import pytest

from jaxrod.experiments import lockup as lx
from jaxrod.lockup import closed_forms as cf
from jaxrod.lockup.laws import helix_against_laws
from jaxrod.lockup.push import inject_lanes, push_rod, units
from jaxrod.lockup.staircase import BELOW_START, BRACKETED, _next, staircase
from jaxrod.lockup.verdict import SLIDING, Criterion, verdict

jax.config.update("jax_enable_x64", True)

ROD = push_rod(1.0, 0.02, 1.0)  # L = ℓ, so a lane's μ is its μL/ℓ
F0, ELL = units(ROD)
N, SPEED, DAMPING = 10, 0.01, 20.0
DRAG = DAMPING * float(ROD.rho) * float(ROD.L) * SPEED / F0  # the damping's drag c·m·v [F₀]
VARIANTS = ("chen/with_weight", "chen/without_weight", "wu_juvkam_wold/with_weight", "wu_juvkam_wold/without_weight")
FH = 2 * (2 * math.sqrt(2) - 1)  # Wu & Juvkam-Wold's helical onset [F₀]


def _per_X(dt):
    """The steady entry force of a straight rod per unit μL/ℓ [F₀] (tests/test_lockup_push.py): the soft
    string without the held entry node's half segment, plus the implicit scheme's βh²(EA/l̂)μ_d g."""
    l0 = float(ROD.L) / N
    return (1 - 0.5 / N) + 0.25 * dt * dt * float(ROD.g) * float(ROD.EA) / l0 / F0 * ELL / float(ROD.L)


def _soft_by_hand(X, f_c):
    """The soft-string columns at μL/ℓ = X for an entry force bound f_c < 2 F₀ (the rod stays straight:
    F_far = f_c − X, μL_lock = f_c), by hand (tests/test_lockup_closed_forms.py): unbounded, 2 cot(X/2)
    with the weight term and 4/X without it; the lock-up lengths 2 arctan(1/√2) + 2√2, 3√2,
    2(π/2 − arctan(f_h/2)) + f_h and 4/f_h + f_h."""
    far_max = {"with_weight": 2 / math.tan(X / 2), "without_weight": 4 / X}
    lock = {"chen/with_weight": 2 * math.atan(1 / math.sqrt(2)) + 2 * math.sqrt(2),
            "chen/without_weight": 3 * math.sqrt(2),
            "wu_juvkam_wold/with_weight": 2 * (math.pi / 2 - math.atan(FH / 2)) + FH,
            "wu_juvkam_wold/without_weight": 4 / FH + FH}
    return {k: dict(far_at_fc=f_c - X, far_max=far_max[k.split("/")[1]], lock_at_fc=f_c, lock=lock[k])
            for k in VARIANTS}


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------------------------
# jaxrod.experiments.lockup: the jobs, the closed forms, the files, the onsets


def test_the_closed_forms_beside_a_lane_are_the_soft_strings_in_units_of_F0_and_ell():
    """Below 2 F₀ every variant keeps the rod straight: F_far(f_c) = f_c − X and μL_lock(f_c)/ℓ = f_c;
    unbounded, the values worked out by hand. At f_c = 6 F₀ each bounded value lies below its limit."""
    got = lx._closed(ROD, 0.5, 1.5)
    assert sorted(got) == sorted(VARIANTS)
    for k, want in _soft_by_hand(0.5, 1.5).items():
        for name, value in want.items():
            assert got[k][name] == pytest.approx(value, rel=1e-9), (k, name)
    # the same case on a rod three times as long (μ a third): only μL/ℓ matters
    long = lx._closed(push_rod(3.0, 0.02, 1.0), 0.5, 1.5)
    for k in VARIANTS:
        assert long[k] == pytest.approx(got[k], rel=1e-9)
    for k, v in lx._closed(ROD, 0.5, 6.0).items():
        assert 0 < v["far_at_fc"] < v["far_max"] and 0 < v["lock_at_fc"] < v["lock"], k
    # Chen's onset with the weight term: the helix from 6 F₀ loses 2(arctan 3 − arctan(f/2)) over X = 0.5
    assert lx._closed(ROD, 0.5, 6.0)["chen/with_weight"]["far_at_fc"] == pytest.approx(
        2 * math.tan(math.atan(3.0) - 0.25), rel=1e-9)


def test_the_jobs_are_each_group_at_the_base_run_and_its_converge_lanes_at_the_others():
    jobs = list(lx._jobs(lx.SETTINGS[False], "out"))
    p = lambda name: os.path.join("out", "jobs", name)  # noqa: E731
    assert jobs == [
        ((2.0, (0.5, 1.0, 1.5, 2.0), None), (16, 10e-3), p("L2_w16_v10.json")),
        ((2.0, (1.0, 2.0), None), (32, 10e-3), p("L2_w32_v10.json")),
        ((2.0, (1.0, 2.0), None), (16, 5e-3), p("L2_w16_v5.json")),
        ((4.0, (3.0, 4.0), "auto"), (16, 10e-3), p("L4_w16_v10.json")),
        ((4.0, (), "auto"), (32, 10e-3), p("L4_w32_v10.json")),
        ((4.0, (), "auto"), (16, 5e-3), p("L4_w16_v5.json")),
    ]
    # without "lock" in converge a group with no converge lane is not run again; without converge
    # every lane runs at every setting
    S = dict(groups=((1.5, (0.5,), 0.7), (3.0, (2.0,), None)), runs=((8, 0.02), (12, 0.02)), converge=(2.0,))
    assert [(g, run) for g, run, _ in lx._jobs(S, "o")] == [
        ((1.5, (0.5,), 0.7), (8, 0.02)), ((3.0, (2.0,), None), (8, 0.02)), ((3.0, (2.0,), None), (12, 0.02))]
    S.pop("converge")
    assert [(g, run) for g, run, _ in lx._jobs(S, "o")] == [
        ((1.5, (0.5,), 0.7), (8, 0.02)), ((1.5, (0.5,), 0.7), (12, 0.02)), ((3.0, (2.0,), None), (8, 0.02)),
        ((3.0, (2.0,), None), (12, 0.02))]


def _stage(stage, parameter, status, f_in, sinusoidal=0.0, helical=0.0, per_turn=50.0, angle=1.0):
    return dict(stage=stage, parameter=parameter, status=status, f_in=f_in, segments_per_turn=per_turn,
                helix_angle=angle, helical=helical, sinusoidal=sinusoidal, reason="hand-made")


def test_the_onsets_bracket_the_steady_stages_per_setting():
    """Only sliding stages count; per (segments per wave, speed), in order of segments then falling
    speed: the sinusoidal onset lies between the largest force without a buckle (sinusoidal +
    helical extent 0) and the smallest with one, the helical onset likewise on the helical extent;
    a force without one above the smallest with one is counted as inconsistent."""
    lane_a = dict(stages=[_stage(0, 1.0, SLIDING, 1.8), _stage(1, 1.1, SLIDING, 2.3, sinusoidal=0.5),
                          _stage(2, 1.2, SLIDING, 3.1, sinusoidal=0.2, helical=0.4),
                          _stage(3, 1.3, "transient", 1.0, sinusoidal=0.3, helical=0.3)])
    lane_b = dict(stages=[_stage(0, 0.5, SLIDING, 2.6), _stage(1, 0.6, SLIDING, 2.9, helical=0.2),
                          _stage(2, 0.7, SLIDING, 2.3)])  # at the smallest buckled force, not above it
    slow = dict(stages=[_stage(0, 1.0, SLIDING, 2.05, sinusoidal=0.1), _stage(1, 1.1, "locked", 9.0)])
    coarse = dict(stages=[_stage(0, 1.0, "transient", 2.5, helical=1.0)])
    results = [dict(per_wave=16, speed=0.005, lanes=[slow]), dict(per_wave=32, speed=0.01, lanes=[coarse]),
               dict(per_wave=16, speed=0.01, lanes=[lane_a]), dict(per_wave=16, speed=0.01, lanes=[lane_b])]
    rows = lx._onsets(results)
    assert [(r["segments_per_wave"], r["push_speed"]) for r in rows] == [(16, 0.01), (16, 0.005), (32, 0.01)]
    fast, half, none = rows
    assert fast == dict(segments_per_wave=16, push_speed=0.01, steady_stages=6,
                        sinusoidal_onset_lo=2.6, sinusoidal_onset_hi=2.3, sinusoidal_inconsistent=1,
                        helical_onset_lo=2.6, helical_onset_hi=2.9, helical_inconsistent=0)
    assert half["steady_stages"] == 1 and half["sinusoidal_onset_hi"] == 2.05
    assert math.isnan(half["sinusoidal_onset_lo"]) and half["helical_onset_lo"] == 2.05
    assert math.isnan(half["helical_onset_hi"]) and half["helical_inconsistent"] == 0
    assert none["steady_stages"] == 0
    assert all(math.isnan(none[k]) for k in ("sinusoidal_onset_lo", "sinusoidal_onset_hi", "helical_onset_lo",
                                             "helical_onset_hi"))


def _hand_results(n=4):
    """One job's JSON by hand on ROD: a far-load lane at X = 0.5 (three stages, the last transient;
    one steady profile) and the lock-up lane (one transient stage, no profile)."""
    l0 = float(ROD.L) / n
    profile = dict(parameter=2.0, f_in=2.5, mu=0.5, theta=[0.0, 0.01, -0.02, 0.01, 0.0], wall_force=[0.3] * (n + 1),
                   axial_force=[0.4, 0.45, 0.5, 0.55])
    far = dict(status="bracketed", lo=2.0, hi=2.06, X=0.5, vary_mu=False, start=2.0, profiles=[profile],
               stages=[_stage(0, 2.0, SLIDING, 2.5, per_turn=40.0, angle=1.0),
                       _stage(1, 2.06, SLIDING, 2.7, sinusoidal=0.2, per_turn=20.0, angle=2.0),
                       _stage(2, 2.1, "transient", 2.9, per_turn=5.0, angle=9.0)])
    lock = dict(status="open", lo=0.5, hi=None, X=0.5, vary_mu=True, start=0.0, profiles=[],
                stages=[_stage(0, 0.5, "transient", 0.6, per_turn=3.0, angle=20.0)])
    return [dict(L_over_ell=1.0, per_wave=8, speed=0.01, n=n, dt=5e-5, f_c=1.5, F0=F0, ell=ELL, l0=l0,
                 r=float(ROD.R), EI=float(ROD.EI), w=float(ROD.rho * ROD.g), mu_of_X=1.0, wall_s=3.5,
                 lanes=[far, lock])]


def test_the_files_carry_every_lane_stage_and_profile_with_the_soft_string_beside_them(tmp_path):
    results = _hand_results()
    S = dict(lx.SETTINGS["tiny"], f_c=1.5)
    summary = lx._write(str(tmp_path), S, results, 7.0)
    soft = _soft_by_hand(0.5, 1.5)
    far_cols = [f"soft_{k}_at_fc" for k in VARIANTS] + [f"soft_{k}_unbounded" for k in VARIANTS]
    curve = _rows(tmp_path / "curve.csv")
    assert list(curve[0]) == ["muL_over_ell", "n_segments", "push_speed", "F_far_max_lo", "F_far_max_hi", "status",
                              "entry_force_bound", "segments_per_wave", "L_over_ell", "stages",
                              "segments_per_turn_sliding", "helix_angle_sliding_deg"] + far_cols
    (row,) = curve
    assert {k: row[k] for k in list(row)[:12]} == dict(
        muL_over_ell="0.5", n_segments="4", push_speed="0.01", F_far_max_lo="2.0", F_far_max_hi="2.06",
        status="bracketed", entry_force_bound="1.5", segments_per_wave="8", L_over_ell="1.0", stages="3",
        segments_per_turn_sliding="20.0", helix_angle_sliding_deg="2.0")  # the worst over the sliding stages
    for k in VARIANTS:
        assert float(row[f"soft_{k}_at_fc"]) == pytest.approx(soft[k]["far_at_fc"], rel=1e-9)
        assert float(row[f"soft_{k}_unbounded"]) == pytest.approx(soft[k]["far_max"], rel=1e-9)
    (lock,) = _rows(tmp_path / "lockup_length_at_fc.csv")
    assert list(lock)[:11] == ["n_segments", "push_speed", "status", "entry_force_bound", "segments_per_wave",
                               "L_over_ell", "stages", "segments_per_turn_sliding", "helix_angle_sliding_deg",
                               "muL_lock_lo", "muL_lock_hi"]
    assert (lock["status"], lock["stages"], lock["muL_lock_lo"], lock["muL_lock_hi"]) == ("open", "1", "0.5", "nan")
    assert (lock["n_segments"], lock["push_speed"], lock["segments_per_wave"], lock["L_over_ell"]) == (
        "4", "0.01", "8", "1.0")
    assert (lock["segments_per_turn_sliding"], lock["helix_angle_sliding_deg"]) == ("inf", "0.0")  # none slid
    for k in VARIANTS:
        assert float(lock[f"soft_{k}_at_fc"]) == pytest.approx(1.5, rel=1e-9)
        assert float(lock[f"soft_{k}_unbounded"]) == pytest.approx(soft[k]["lock"], rel=1e-9)
    stages = _rows(tmp_path / "stages.csv")
    assert [(s["varies"], s["parameter"], s["status"]) for s in stages] == [
        ("far_load", "2.0", "sliding"), ("far_load", "2.06", "sliding"), ("far_load", "2.1", "transient"),
        ("mu", "0.5", "transient")]
    assert list(stages[0]) == ["muL_over_ell", "varies", "n_segments", "push_speed", "stage", "parameter", "status",
                               "f_in", "segments_per_turn", "helix_angle", "helical", "sinusoidal", "reason"]
    assert [s["f_in"] for s in stages] == ["2.5", "2.7", "2.9", "0.6"] and stages[1]["sinusoidal"] == "0.2"
    profiles = _rows(tmp_path / "profiles.csv")  # the far lane's last steady profile, node by node
    prof = results[0]["lanes"][0]["profiles"][-1]
    assert len(profiles) == 5
    for i, p in enumerate(profiles):
        assert int(p["node"]) == i and float(p["s_from_far_end"]) == pytest.approx(i * float(ROD.L) / 4, rel=1e-12)
        assert float(p["theta"]) == prof["theta"][i] and float(p["wall_force"]) == 0.3
        assert float(p["axial_force"]) == prof["axial_force"][min(i, 3)]
        assert (p["muL_over_ell"], p["parameter"], p["mu"], p["n_segments"]) == ("0.5", "2.0", "0.5", "4")
        assert float(p["EI"]) == float(ROD.EI) and float(p["r"]) == float(ROD.R)
        assert float(p["w"]) == float(ROD.rho * ROD.g)
    assert list(profiles[0]) == ["muL_over_ell", "n_segments", "push_speed", "parameter", "node", "s_from_far_end",
                                 "theta", "wall_force", "axial_force", "mu", "EI", "w", "r"]
    (law,) = _rows(tmp_path / "helix_laws.csv")
    assert (law["varies"], law["parameter"], law["entry_force_over_F0"]) == ("far_load", "2.0", "2.5")
    # the friction's bookkeeping over the whole rod: (F at the entry − F at the far end)/(μ ∫N ds)
    assert float(law["whole_rod_dF_over_mu_int_N"]) == pytest.approx((0.55 - 0.4) / (0.5 * 0.3 * float(ROD.L)),
                                                                     rel=1e-12)
    assert law["helical_compared_over_ell"] == "0.0" and law["winding_over_ell"] == "0.0"
    assert math.isnan(float(law["pitch_over_lubinski"])) and law["hand_reversals"] == "0"
    (onset,) = _rows(tmp_path / "onsets.csv")
    assert (onset["steady_stages"], onset["sinusoidal_onset_lo"], onset["sinusoidal_onset_hi"]) == ("2", "2.5", "2.7")
    saved = json.loads((tmp_path / "curve.json").read_text())
    assert (saved["model"], saved["scheme"], saved["r_over_ell"], saved["damping"], saved["f_c"]) == (
        "rod3d", "implicit", 0.02, 20.0, 1.5)
    assert saved["settings"] == json.loads(json.dumps(S)) and saved["wall_s_this_call"] == 7.0
    assert saved["jobs_wall_s"] == [3.5] and len(saved["helix_laws"]) == 1 and len(saved["onsets"]) == 1
    assert saved["curve"][0]["F_far_max_hi"] == 2.06 and math.isnan(saved["lockup_length"][0]["muL_lock_hi"])
    assert json.dumps(summary, default=float) == json.dumps(saved)  # what it returns is what it wrote
    assert (tmp_path / "curve.png").stat().st_size > 0


def test_each_helix_law_column_is_the_comparisons_number_in_its_units(tmp_path, monkeypatch):
    """helix_laws.csv holds `helix_against_laws`' numbers of each steady profile (a stand-in
    here, with known numbers, called with the profile and the job's rod), lengths over ℓ and
    forces over F₀, ratios as they are."""
    from jaxrod.lockup import laws

    results = _hand_results()
    res, prof = results[0], results[0]["lanes"][0]["profiles"][0]
    seen = []
    hx = dict(inner_length=0.3 * ELL, F_range=(1.5 * F0, 2.25 * F0), pitch_ratio=1.1, N_ratio=0.9,
              N_ratio_with_weight=0.8, soft_string_ratio=1.05, soft_string_ratio_whole=0.95,
              winding_length=0.4 * ELL, reversals=3, wall_ratio_winding=0.7)

    def stand_in(theta, wall_force, axial_force, l0, EI, w, r, mu, wave):
        seen.append((theta, wall_force, axial_force, l0, EI, w, r, mu, wave))
        return hx

    monkeypatch.setattr(laws, "helix_against_laws", stand_in)
    lx._write(str(tmp_path), dict(lx.SETTINGS["tiny"], f_c=1.5), results, 7.0)
    assert seen == [(prof["theta"], prof["wall_force"], prof["axial_force"], res["l0"], res["EI"], res["w"], res["r"],
                     prof["mu"], 2 * math.pi * math.sqrt(res["ell"] * res["r"]))]
    (law,) = _rows(tmp_path / "helix_laws.csv")
    got = {k: float(v) for k, v in law.items() if k != "varies"}
    assert got == pytest.approx(dict(
        muL_over_ell=0.5, n_segments=4, push_speed=0.01, parameter=2.0, entry_force_over_F0=2.5,
        helical_compared_over_ell=0.3, F_lo_over_F0=1.5, F_hi_over_F0=2.25, pitch_over_lubinski=1.1,
        N_over_mitchell=0.9, N_over_mitchell_plus_w=0.8, dF_ds_over_mu_N=1.05, whole_rod_dF_over_mu_int_N=0.95,
        winding_over_ell=0.4, hand_reversals=3, winding_int_N_over_int_mitchell=0.7), rel=1e-12)


def test_the_jobs_run_costliest_first_and_a_job_already_run_with_the_same_settings_is_skipped(
        tmp_path, monkeypatch, capsys):
    S = dict(groups=((2.0, (0.5, 1.0), None), (4.0, (3.0,), "auto")), f_c=6.0,
             runs=((16, 0.01), (24, 0.01), (16, 0.004)), converge=(1.0, "lock"), first_push=0.4, stage_push=0.15,
             max_stages=2, saves_per_stage=11)
    monkeypatch.setitem(lx.SETTINGS, "test", S)
    ran = []

    def job(args):  # a job's JSON without lanes, where the staircase would have written it
        (Lx, Xs, lock), (per_wave, speed), S_job, path, progress = args
        ran.append(((Lx, Xs, lock), (per_wave, speed), progress))
        assert S_job is S
        with open(path, "w") as fh:
            json.dump(dict(L_over_ell=Lx, per_wave=per_wave, speed=speed, lanes=[], wall_s=1.0, settings=S_job), fh)
        return path

    monkeypatch.setattr(lx, "_job", job)
    summary = lx.lockup(str(tmp_path), quick="test", progress=True, workers=1)
    # cost: lanes × L/ℓ × segments per wave / speed
    assert ran == [((4.0, (), "auto"), (16, 0.004), True), ((4.0, (3.0,), "auto"), (16, 0.01), True),
                   ((4.0, (), "auto"), (24, 0.01), True), ((2.0, (1.0,), None), (16, 0.004), True),
                   ((2.0, (0.5, 1.0), None), (16, 0.01), True), ((2.0, (1.0,), None), (24, 0.01), True)]
    assert "lock-up: 6 staircase(s) to run on 1 worker(s), f_c = 6 F0" in capsys.readouterr().out
    assert summary["jobs_wall_s"] == [1.0] * 6 and summary["settings"] == S
    assert isinstance(summary["wall_s_this_call"], float) and 0.0 <= summary["wall_s_this_call"] < 60.0
    assert [r["segments_per_wave"] for r in summary["onsets"]] == [16, 16, 24]
    # again: every job is there with the same settings; one removed and one of other settings run again
    ran.clear()
    os.remove(tmp_path / "jobs" / "L2_w24_v10.json")
    other = tmp_path / "jobs" / "L4_w16_v10.json"
    other.write_text(json.dumps(dict(json.loads(other.read_text()), settings=dict(S, f_c=5.0))))
    lx.lockup(str(tmp_path), quick="test", progress=False, workers=1)
    assert ran == [((4.0, (3.0,), "auto"), (16, 0.01), False), ((2.0, (1.0,), None), (24, 0.01), False)]
    ran.clear()
    lx.lockup(str(tmp_path), quick="test", progress=False)
    assert ran == []


def test_a_tiny_lockup_run_writes_its_job_and_the_files_from_it(tmp_path, monkeypatch):
    """One group (L = ℓ, a far-load lane at μL/ℓ = 0.5, the lock-up lane "auto") at 8 segments per
    buckle wave and 10 mm/s, two stages of 2 mm, f_c = 3.2 F₀. By hand, from 3.2 F₀ over X = 0.5:
    Chen's onset 2√2 is reached after X_h = 2(arctan 1.6 − arctan √2) with the weight term
    (4(1/2√2 − 1/3.2) without), then the sinusoid (weight only) loses the rest; Wu & Juvkam-Wold's
    onset 3.657 F₀ is above 3.2, so their rod is sinusoidal all along: F_far = 3.2 − 0.5. The
    lock-up lengths at 3.2 F₀ add the sinusoid's 2√2 − 2 and the straight part's 2 (3.2 for Wu &
    Juvkam-Wold). The far-load lane starts at 0.7 × the smallest F_far (Chen with the weight
    term), the lock-up lane at 0.8 × the smallest lock-up length. 10 segments: 8 per wave
    2π√(ℓr) = 2π√0.02 ℓ, rounded up."""
    f_c, X = 3.2, 0.5
    xh = {"with_weight": 2 * (math.atan(f_c / 2) - math.atan(math.sqrt(2))),
          "without_weight": 4 * (1 / (2 * math.sqrt(2)) - 1 / f_c)}
    at_fc = {f"chen/{law}": 2 * math.sqrt(2) - (X - x) for law, x in xh.items()}
    at_fc.update({"wu_juvkam_wold/with_weight": f_c - X, "wu_juvkam_wold/without_weight": f_c - X})
    lock_fc = {f"chen/{law}": x + 2 * math.sqrt(2) - 2 + 2 for law, x in xh.items()}
    lock_fc.update({"wu_juvkam_wold/with_weight": f_c, "wu_juvkam_wold/without_weight": f_c})
    unbounded = _soft_by_hand(X, 1.5)  # the unbounded columns do not depend on f_c
    S = dict(groups=((1.0, (X,), "auto"),), f_c=f_c, runs=((8, SPEED),), first_push=0.002, stage_push=0.002,
             max_stages=2, saves_per_stage=11)
    monkeypatch.setitem(lx.SETTINGS, "tiny", S)
    summary = lx.lockup(str(tmp_path), quick="tiny", progress=False, workers=1)
    assert sorted(os.listdir(tmp_path / "jobs")) == ["L1_w8_v10.json"]
    for name in ("curve.csv", "lockup_length_at_fc.csv", "stages.csv", "onsets.csv", "curve.json", "curve.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    job = json.loads((tmp_path / "jobs" / "L1_w8_v10.json").read_text())
    assert N == math.ceil(8 / (2 * math.pi * math.sqrt(0.02)))
    assert (job["L_over_ell"], job["per_wave"], job["speed"], job["n"], job["f_c"], job["mu_of_X"]) == (
        1.0, 8, SPEED, N, f_c, 1.0)
    assert job["settings"] == json.loads(json.dumps(S))
    assert job["F0"] == pytest.approx(F0, rel=1e-12) and job["ell"] == pytest.approx(ELL, rel=1e-12)
    assert job["l0"] == pytest.approx(ELL / N, rel=1e-12) and job["r"] == pytest.approx(0.02 * ELL, rel=1e-12)
    assert job["EI"] == float(ROD.EI) and job["w"] == float(ROD.rho * ROD.g) and 0 < job["wall_s"] < 3600
    far, lock = job["lanes"]
    assert (far["X"], far["vary_mu"], lock["vary_mu"], lock["start"]) == (X, False, True, 0.0)
    assert far["start"] == pytest.approx(0.7 * min(at_fc.values()), rel=1e-9)
    assert far["start"] == pytest.approx(0.7 * at_fc["chen/with_weight"], rel=1e-9)
    assert lock["X"] == pytest.approx(0.8 * lock_fc["chen/with_weight"], rel=1e-9)
    assert far["stages"][0]["parameter"] == far["start"]
    assert lock["stages"][0]["parameter"] == pytest.approx(lock["X"], rel=1e-9)
    assert all(1 <= len(lane["stages"]) <= 2 for lane in (far, lock))
    # the files are the job's lanes
    (row,) = _rows(tmp_path / "curve.csv")
    assert float(row["muL_over_ell"]) == 0.5 and int(row["n_segments"]) == N and float(row["push_speed"]) == SPEED
    assert row["status"] == far["status"] and int(row["stages"]) == len(far["stages"])
    assert row["F_far_max_lo"] == ("nan" if far["lo"] is None else str(far["lo"]))
    assert row["F_far_max_hi"] == ("nan" if far["hi"] is None else str(far["hi"]))
    (locks,) = _rows(tmp_path / "lockup_length_at_fc.csv")
    assert locks["status"] == lock["status"] and int(locks["stages"]) == len(lock["stages"])
    assert locks["muL_lock_lo"] == ("nan" if lock["lo"] is None else str(lock["lo"]))
    for k in VARIANTS:
        assert float(row[f"soft_{k}_at_fc"]) == pytest.approx(at_fc[k], rel=1e-9), k
        assert float(row[f"soft_{k}_unbounded"]) == pytest.approx(unbounded[k]["far_max"], rel=1e-9), k
        assert float(locks[f"soft_{k}_at_fc"]) == pytest.approx(lock_fc[k], rel=1e-9), k
        assert float(locks[f"soft_{k}_unbounded"]) == pytest.approx(unbounded[k]["lock"], rel=1e-9), k
    stages = _rows(tmp_path / "stages.csv")
    assert [(s["varies"], float(s["parameter"])) for s in stages] == (
        [("far_load", s["parameter"]) for s in far["stages"]] + [("mu", s["parameter"]) for s in lock["stages"]])
    assert summary["settings"] == S and summary["f_c"] == f_c and summary["jobs_wall_s"] == [job["wall_s"]]
    # a second call finds the job done with the same settings and only writes the files again
    monkeypatch.setattr(lx, "_job", lambda args: pytest.fail("the job was run again"))
    again = lx.lockup(str(tmp_path), quick="tiny", progress=False, workers=1)
    assert json.dumps(again["curve"]) == json.dumps(summary["curve"])
    assert json.dumps(again["lockup_length"]) == json.dumps(summary["lockup_length"])


# --------------------------------------------------------------------------------------------
# jaxrod.lockup.push.inject_lanes


def test_each_lane_is_its_own_injection_at_the_soft_string_force_of_its_mu_and_far_load(capsys):
    """Two lanes (μ = 0.5 against 1.5 F₀, μ = 0.05 against 0.5 F₀) pushed 10 mm in five parts: once the
    start's axial wave has died out (damping 20/s: e^{−10 t}) each lane's entry carries its own far
    load plus X(1 − 1/2n) + bias, plus the drag (the straight rod of tests/test_lockup_push.py), so
    the far end gets less than the entry force, the more so at the larger μ; the entry advances at
    the set speed and the far end with it. The lanes swapped, the smaller-μ lane is the same run to
    rounding while the other, against 4 F₀ with a cap of 3 F₀, is held at the end of a part."""
    mus, loads = np.array([0.5, 0.05]), np.array([1.5, 0.5])
    rec = inject_lanes(ROD, mus, loads * F0, SPEED, 1.0, n=N, n_save=51, chunks=5, damping=DAMPING)
    assert capsys.readouterr() == ("", "")  # silent unless asked for progress
    assert rec["f_in"].shape == rec["push"].shape == (2, 51) and rec["u"].shape == (2, 51, N + 1)
    assert rec["theta"].shape == rec["wall_force"].shape == (2, 51, N + 1) and rec["t"].shape == (51,)
    np.testing.assert_allclose(rec["t"], np.linspace(0.0, 1.0, 51), atol=1e-12)
    assert np.all(rec["phase"] == 0) and np.all(rec["result"] == 0) and np.all(np.isinf(rec["held_from"]))
    assert np.array_equal(rec["mu"], mus) and rec["scheme"] == "implicit" and rec["n"] == N
    assert rec["F0"] == pytest.approx(F0, rel=1e-12) and rec["ell"] == pytest.approx(ELL, rel=1e-12)
    np.testing.assert_allclose(rec["F_far"], np.repeat(loads[:, None] * F0, 51, axis=1), rtol=1e-15)
    np.testing.assert_allclose(rec["f_far"], np.repeat(loads[:, None], 51, axis=1), rtol=1e-12)
    np.testing.assert_allclose(rec["f_in"], rec["F_in"] / F0, rtol=1e-12)
    np.testing.assert_allclose(rec["push"], SPEED * np.broadcast_to(rec["t"], (2, 51)), atol=1e-9)
    tail = rec["t"] >= 0.8 - 1e-9
    f_in = rec["f_in"][:, tail].mean(axis=1)
    np.testing.assert_allclose(f_in, loads + mus * _per_X(rec["dt"]) + DRAG, atol=2e-3)
    assert np.all(loads < f_in) and loads[0] / f_in[0] < loads[1] / f_in[1] < 1
    advance = rec["u"][:, -1, 0] - rec["u"][:, 0, 0]  # the far end slides with the entry, less its compression
    np.testing.assert_allclose(advance, rec["push"][:, -1], rtol=2e-3)

    swapped = inject_lanes(ROD, mus[::-1], np.array([0.5, 4.0]) * F0, SPEED, 1.0, n=N, n_save=51, chunks=5,
                           cap=3.0, damping=DAMPING, progress=True)
    lines = capsys.readouterr().out.splitlines()  # asked for: one line per part, the time run so far
    assert lines == [f"  {0.2 * k:.4g} s of 1 s run" for k in range(1, 6)]
    np.testing.assert_allclose(swapped["f_in"][0], rec["f_in"][1], atol=1e-9)
    np.testing.assert_allclose(swapped["u"][0], rec["u"][1], atol=1e-12)
    assert math.isinf(swapped["held_from"][0])
    t_hold = swapped["held_from"][1]
    # held at the end of the first part over which its entry force passed the cap
    t = rec["t"]
    first = next(b for b in (0.2, 0.4, 0.6, 0.8)
                 if np.max(swapped["f_in"][1][(t >= b - 0.2 - 1e-9) & (t <= b + 1e-9)]) > 3.0)
    assert t_hold == pytest.approx(first, abs=1e-9)
    after = t >= t_hold - 1e-9
    np.testing.assert_allclose(swapped["push"][1][after], SPEED * t_hold, atol=1e-9)
    assert np.all(swapped["f_in"][1][after] > 3.0)  # static friction keeps the force it was held at


def test_inject_lanes_refuses_a_lane_without_friction_naming_it():
    """A lane needs μ > 0 (a far load may be 0): the message names the lane's element, on one line."""
    with pytest.raises(ValueError) as e:
        inject_lanes(ROD, [0.5, 0.0], [0.0, 0.0], SPEED, 0.2, n=N)
    assert str(e.value) == "mus[1] = 0.0 is invalid: expected a finite number > 0."


# --------------------------------------------------------------------------------------------
# jaxrod.lockup.staircase


def test_next_goes_half_way_to_the_secants_crossing_within_its_bounds():
    """By hand, f_c = 5.6, rel = 0.01: from (1.0, 4.0), (1.1, 5.0) the secant of log f̄ reaches 5.6
    at 1.1 + ln(1.12)/(10 ln 1.25) = 1.150788; half of the way is 1.125394 (above the least step
    1.1 × 1.009 = 1.1099, below the growth 1.1 × 1.12)."""
    half = 1.1 + 0.5 * math.log(5.6 / 5.0) / (math.log(5.0 / 4.0) / 0.1)
    assert half == pytest.approx(1.125394, abs=1e-6)
    assert _next([(1.0, 4.0), (1.1, 5.0)], 1.1, 5.6, 0.01) == pytest.approx(half, rel=1e-12)
    # far from f_c the step is at most `growth`; one stage only: the growth step (from 0: 0.1)
    assert _next([(1.0, 2.0), (1.1, 2.2)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.12, rel=1e-12)
    assert _next([(2.0, 3.0)], 2.0, 6.0, 0.03) == pytest.approx(2.24, rel=1e-12)
    assert _next([(2.0, 3.0)], 2.0, 6.0, 0.2) == pytest.approx(2.0 * 1.18, rel=1e-12)  # the least step is larger
    assert _next([(0.0, 3.0)], 0.0, 6.0, 0.03) == 0.1
    # within 5 % of f_c, or within 10 % without a rise: only the least step 0.9 rel
    assert _next([(1.0, 4.0), (1.1, 5.8)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.027, rel=1e-12)
    assert _next([(1.0, 5.6), (1.1, 5.5)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.027, rel=1e-12)
    # a force that did not rise, far from f_c: noise, the growth step
    assert _next([(1.0, 3.0), (1.1, 2.9)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.12, rel=1e-12)
    assert _next([(1.1, 3.0), (1.1, 3.2)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.12, rel=1e-12)
    # a repeat at the same value (no slope to read) within 10 % of f_c: the least step
    assert _next([(1.1, 5.3), (1.1, 5.5)], 1.1, 6.0, 0.03) == pytest.approx(1.1 * 1.027, rel=1e-12)


def test_a_staircase_brackets_both_lanes_and_records_every_stage():
    """f_c = 2.2 F₀, rel = 0.5 (the least step 1.45 ×): the far-load lane (μL/ℓ = 0.5) from 1.5 F₀ slides
    at 1.5 + 0.5 per_X + drag ≈ 2.0 F₀ (a lower bound) and at 2.175 F₀ at ≈ 2.7 F₀ (above: the upper
    bound); the μ lane against 1.6 F₀ from μL/ℓ = 0.5 slides at ≈ 2.1 F₀ and at 0.725 at ≈ 2.3 F₀.
    A first stage still ringing from the start is repeated at the same parameter. Each steady stage
    at or below f_c keeps a profile of the straight rod: the wall force is the weight, the axial force
    rises from the far load toward the entry force."""
    res = staircase(ROD, [0.5, 0.5], [1.5, 1.6], SPEED, f_c=2.2, vary_mu=[False, True], rel=0.5, n=N,
                    first_push=0.002, stage_push=0.002, max_stages=4, saves_per_stage=11, damping=DAMPING)
    assert sorted(res) == sorted(["lanes", "F0", "ell", "n", "dt", "l0", "r", "L_over_ell", "f_c", "speed", "mus",
                                  "far_loads", "vary_mu", "scheme", "X"])
    assert (res["f_c"], res["speed"], res["n"], res["scheme"]) == (2.2, SPEED, N, "implicit")
    assert res["F0"] == pytest.approx(F0, rel=1e-12) and res["ell"] == pytest.approx(ELL, rel=1e-12)
    assert res["l0"] == pytest.approx(ELL / N, rel=1e-12) and res["L_over_ell"] == pytest.approx(1.0, rel=1e-12)
    assert res["r"] == pytest.approx(0.02 * ELL, rel=1e-12)
    np.testing.assert_allclose(res["X"], [0.5, 0.5], rtol=1e-12)
    assert list(res["far_loads"]) == [1.5, 1.6] and list(res["vary_mu"]) == [False, True]
    w = float(ROD.rho * ROD.g)
    for lane, lo, hi, load in zip(res["lanes"], (1.5, 0.5), (2.175, 0.725), (1.5, 1.6)):
        assert sorted(lane) == ["hi", "lo", "profiles", "stages", "status"]
        assert lane["status"] == BRACKETED, lane["stages"]
        assert lane["lo"] == pytest.approx(lo, rel=1e-12) and lane["hi"] == pytest.approx(hi, rel=1e-12)
        stages = lane["stages"]
        assert [s["stage"] for s in stages] == list(range(len(stages)))
        assert all(sorted(s) == ["f_in", "helical", "helix_angle", "parameter", "reason", "segments_per_turn",
                                 "sinusoidal", "stage", "status"] for s in stages)
        assert stages[-1]["status"] == SLIDING and stages[-1]["f_in"] > 2.2
        assert stages[-2]["status"] == SLIDING and stages[-2]["f_in"] <= 2.2
        assert all(s["parameter"] == stages[0]["parameter"] for s in stages[:-1])  # repeats, then the lower bound
        assert all(s["status"] == "transient" for s in stages[:-2])
        assert all(s["helical"] == 0.0 and s["sinusoidal"] == 0.0 for s in stages)  # a straight rod
        (prof,) = lane["profiles"]
        assert prof["parameter"] == pytest.approx(lo, rel=1e-12) and prof["mu"] == pytest.approx(0.5, rel=1e-12)
        assert np.shape(prof["theta"]) == np.shape(prof["wall_force"]) == (N + 1,)
        assert np.shape(prof["axial_force"]) == (N,)
        np.testing.assert_allclose(prof["wall_force"], w, rtol=1e-3)
        assert prof["f_in"] == pytest.approx(stages[-2]["f_in"], rel=0.01)
        Fx = np.asarray(prof["axial_force"]) / F0
        assert np.all(np.diff(Fx) > 0) and load < Fx[0] < Fx[-1] < prof["f_in"]
    # the lower bounds' steady entry force is the straight rod's (the upper stages still ring from the
    # jump of their parameter)
    far, mu_lane = res["lanes"]
    assert far["stages"][-2]["f_in"] == pytest.approx(1.5 + 0.5 * _per_X(res["dt"]) + DRAG, abs=0.01)
    assert mu_lane["stages"][-2]["f_in"] == pytest.approx(1.6 + 0.5 * _per_X(res["dt"]) + DRAG, abs=0.01)


def test_a_lane_over_the_bound_at_its_start_a_wide_bracket_and_lanes_that_never_settle():
    """f_c = 2.2 F₀. One repeat: the far-load lane from 2.5 F₀ slides above f_c at once (≈ 3 F₀) and
    stops with only an upper bound; the lane at μL/ℓ = 0.05 with no far load (≈ 0.07 F₀, the start's
    axial wave still as large) is not settled after its stage and one repeat, and stops as
    transient. Two repeats (the default) and rel = 0.03: the same lane stops after three stages;
    the far-load lane from 1.6 F₀ (≈ 2.1 F₀, below f_c) takes the growth step 1.12 × to 1.792 F₀
    (≈ 2.3 F₀, above): a bracket wider than 3 %."""
    res = staircase(ROD, [0.5, 0.05], [2.5, 0.0], SPEED, f_c=2.2, vary_mu=[False, True], n=N, repeats=1,
                    first_push=0.002, stage_push=0.002, max_stages=4, saves_per_stage=11, damping=DAMPING)
    over, ringing = res["lanes"]
    assert over["status"] == "below start" == BELOW_START and over["lo"] is None and over["hi"] == 2.5
    assert over["stages"][-1]["status"] == SLIDING and over["stages"][-1]["f_in"] > 2.2
    assert over["profiles"] == [] and all(s["parameter"] == 2.5 for s in over["stages"])
    assert ringing["status"] == "transient" and ringing["lo"] is None and ringing["hi"] is None
    assert [(s["parameter"], s["status"]) for s in ringing["stages"]] == [(0.05, "transient")] * 2
    res = staircase(ROD, [0.5, 0.05], [1.6, 0.0], SPEED, f_c=2.2, vary_mu=[False, True], n=N,
                    first_push=0.002, stage_push=0.002, max_stages=5, saves_per_stage=11, damping=DAMPING)
    wide, ringing = res["lanes"]
    assert wide["status"] == "wide" and wide["lo"] == 1.6 and wide["hi"] == pytest.approx(1.6 * 1.12, rel=1e-12)
    assert [s["status"] for s in wide["stages"][-2:]] == [SLIDING, SLIDING]
    assert wide["stages"][-2]["f_in"] <= 2.2 < wide["stages"][-1]["f_in"]
    assert ringing["status"] == "transient" and ringing["profiles"] == []
    assert [(s["parameter"], s["status"]) for s in ringing["stages"]] == [(0.05, "transient")] * 3


def test_staircase_refuses_a_lane_without_friction_naming_it():
    """A lane needs μ > 0 (a far load may be 0, as the lock-up lane's is): one line naming the element."""
    with pytest.raises(ValueError) as e:
        staircase(ROD, [0.5, 0.0], [0.3, 0.0], SPEED, n=N)
    assert str(e.value) == "mus[1] = 0.0 is invalid: expected a finite number > 0."
    with pytest.raises(ValueError) as e:
        staircase(ROD, [0.5], [-0.1], SPEED, n=N)
    assert str(e.value) == "far_loads[0] = -0.1 is invalid: expected a finite number >= 0."


# --------------------------------------------------------------------------------------------
# verdict, helix_against_laws, the closed forms' messages


def test_verdict_reads_a_record_of_exactly_two_saves_per_window():
    """Ten saves for five windows: the last two parts are saves 6–7 and 8–9 (edges at 0.54, 0.72 and
    0.9 of a push advancing 0.1 per save); the transfer is the far end's advance over the entry's
    on each, the force the mean entry force there."""
    push = np.linspace(0.0, 0.9, 10)
    step = np.array([1, 1, 1, 1, 1, 1, 0.96, 0.5, 0.95]) * 0.1
    far = np.concatenate([[0.0], np.cumsum(step)])
    f_in = np.array([1.0, 2.0, 3.0, 3.0, 3.0, 3.0, 3.0, 3.01, 3.02, 3.03])
    try:
        got = verdict(push, far, f_in)
    except ValueError as e:
        pytest.fail(f"a record of exactly 2 × windows saves was refused: {e}")
    assert got["transfer"] == pytest.approx((0.96, 0.95), rel=1e-9)
    assert got["force"] == pytest.approx((3.005, 3.025), rel=1e-12)
    assert got["status"] == SLIDING
    with pytest.raises(ValueError, match="at least 10 saves"):
        verdict(push[:9], far[:9], f_in[:9])
    # four windows need eight saves: the last two parts are saves 4–5 and 6–7
    assert verdict(push[:8], far[:8], f_in[:8], criterion=Criterion(windows=4))["transfer"] == pytest.approx(
        (1.0, 0.96), rel=1e-9)


def test_the_half_turn_of_a_pitch_longer_than_the_rod_is_the_whole_rod():
    """A rod barely turning (a pitch of 4 rod lengths, or of 10²² m: the rounding noise of a
    straight rod's angle) averages its wall force over one pitch, that is over the whole rod at
    every node; a rod not turning at all over the least window, its node and its two neighbours."""
    n, l0 = 50, 0.1
    s = np.arange(n + 1) * l0
    wall = 1.0 + 0.5 * s**2
    for rate in (2 * np.pi / (4 * n * l0), 1e-22):
        got = helix_against_laws(rate * s, wall, np.full(n, 2.0), l0, 0.05, 0.8, 0.04, 0.2, 1.0)
        np.testing.assert_allclose(got["N_turn"], np.mean(wall), rtol=1e-12)
    flat = helix_against_laws(np.zeros(n + 1), wall, np.full(n, 2.0), l0, 0.05, 0.8, 0.04, 0.2, 1.0)
    np.testing.assert_allclose(flat["N_turn"][1:-1], (wall[:-2] + wall[1:-1] + wall[2:]) / 3, rtol=1e-12)


EI_, W_, R_, MU_ = 0.0191, 0.112, 5e-3, 0.3


@pytest.mark.parametrize("call, message", [
    (lambda: cf.straight_transfer(1.0, -2.0, W_, MU_), "s = -2.0 m is invalid: it must be finite and >= 0."),
    (lambda: cf.straight_transfer(float("nan"), 2.0, W_, MU_), "F_in = nan N is invalid: it must be finite and >= 0."),
    (lambda: cf.helical_transfer(1.0, -2.0, EI_, W_, R_, MU_), "s = -2.0 m is invalid: it must be finite and >= 0."),
    (lambda: cf.helical_transfer(-1.0, 2.0, EI_, W_, R_, MU_),
     "F_in = -1.0 N is invalid: it must be not NaN and >= 0."),
    (lambda: cf.sinusoidal_transfer(1.0, float("inf"), EI_, W_, R_, MU_),
     "s = inf m is invalid: it must be finite and >= 0."),
    (lambda: cf.sinusoidal_transfer(float("nan"), 1.0, EI_, W_, R_, MU_),
     "F_in = nan N is invalid: it must be not NaN and >= 0."),
    (lambda: cf.helical_transfer(1.0, 1.0, EI_, W_, R_, -0.1), "mu = -0.1 is invalid: it must be finite and >= 0."),
])
def test_a_bad_closed_form_argument_is_named_with_its_unit_on_one_line(call, message):
    with pytest.raises(ValueError) as e:
        call()
    assert str(e.value) == message


def test_a_soft_helix_under_half_a_newton_has_lubinskis_pitch_and_mitchells_wall_force():
    """An exact helix of turn rate β = 5 1/m in a rod of EI = 0.01 N·m² under Lubinski's force
    F = 2EIβ² = 0.5 N, pressing on the wall with Mitchell's r F²/(4EI): both ratios are 1, whatever
    the size of F."""
    n, l0, EI, r, beta = 200, 0.05, 0.01, 0.04, 5.0
    s = np.arange(n + 1) * l0
    F = 2 * EI * beta**2
    wall = np.full(n + 1, r * F**2 / (4 * EI))
    got = helix_against_laws(beta * s, wall, np.full(n, F), l0, EI, 0.8, r, 0.2, 2.0)
    assert got["inner"].any()
    assert got["pitch_ratio"] == pytest.approx(1.0, rel=1e-9)
    assert got["N_ratio"] == pytest.approx(1.0, rel=1e-9)
    np.testing.assert_allclose(got["pitch_lubinski"], 2 * np.pi / beta, rtol=1e-12)


def test_a_lane_of_a_batched_record_keeps_the_shared_entries_and_takes_its_own_rows():
    """`lane(rec, k)`: the times, phases, units, resolution and scheme are shared by every lane;
    every other entry is the lane's row k."""
    from jaxrod.lockup.push import lane

    shared = dict(t=np.linspace(0, 1, 4), phase=np.zeros(4, int), ts=np.arange(3.0), F0=2.0, ell=1.5, r=0.01, n=10,
                  dt=1e-4, scheme="implicit")
    own = dict(f_in=np.arange(8.0).reshape(2, 4), push=-np.arange(8.0).reshape(2, 4), u=np.ones((2, 4, 11)) * [[[1]], [[2]]])
    got = lane({**shared, **own}, 1)
    assert set(got) == set(shared) | set(own)
    for k, v in shared.items():
        assert got[k] is v
    np.testing.assert_array_equal(got["f_in"], [4.0, 5.0, 6.0, 7.0])
    np.testing.assert_array_equal(got["push"], [-4.0, -5.0, -6.0, -7.0])
    assert got["u"].shape == (4, 11) and np.all(got["u"] == 2)


def test_a_job_gives_each_lane_its_mu_from_mul_over_ell_at_its_rod_length(tmp_path, monkeypatch):
    """`_job` on a group at L/ℓ = 2 (the rod two buckle lengths long: μ = 1 gives L = 2ℓ) runs
    the lanes μL/ℓ = 0.5 and 1 at μ = X/(L/ℓ) = 0.25 and 0.5, and writes each lane's X back."""
    from jaxrod.lockup import staircase as sc

    seen = {}

    def stand_in(rod, mus, starts, speed, **kw):
        seen.update(mus=list(mus), speed=speed)
        return dict(lanes=[dict(profiles=[]) for _ in mus], n=8, dt=1e-4, F0=1.0, ell=1.0, l0=0.1, r=0.005)

    monkeypatch.setattr(sc, "staircase", stand_in)
    S = dict(lx.SETTINGS["tiny"], f_c=1.5)
    path = str(tmp_path / "job.json")
    lx._job(((2.0, (0.5, 1.0), None), (8, 10e-3), S, path, False))
    assert seen == dict(mus=[0.25, 0.5], speed=10e-3)
    job = json.load(open(path))
    assert [lane["X"] for lane in job["lanes"]] == [0.5, 1.0] and job["mu_of_X"] == 0.5


def test_a_job_hands_every_setting_to_its_staircase(tmp_path, monkeypatch):
    """`_job` runs one staircase with the setting's f_c, pushes, stage count, saves per stage and
    the driver's damping, at the job's speed and its number of segments (8 per buckle wave here,
    at least 8); the far-load lanes at μ = X/(L/ℓ), the lock-up lane last and varying μ."""
    import sys

    seen = {}

    class Seen(Exception):
        pass

    def record(rod, mus, starts, speed, **kw):
        seen.update(kw, mus=list(mus), starts=list(starts), speed=speed)
        raise Seen

    monkeypatch.setattr(sys.modules["jaxrod.lockup.staircase"], "staircase", record)
    S = dict(f_c=4.5, first_push=0.003, stage_push=0.002, max_stages=3, saves_per_stage=7)
    with pytest.raises(Seen):
        lx._job(((2.0, (0.5, 1.0), 1.5), (8, 0.02), S, str(tmp_path / "job.json"), False))
    assert {k: seen[k] for k in S} == S
    assert seen["damping"] == lx.DAMPING and seen["speed"] == 0.02 and seen["progress"] is False
    assert seen["mus"] == [0.25, 0.5, 0.75] and seen["vary_mu"] == [False, False, True]
    assert seen["starts"][2] == 0.0 and min(seen["starts"][:2]) >= 0.1
    assert seen["n"] == max(8, math.ceil(8 * 2.0 / (2 * math.pi * math.sqrt(lx.R_OVER_ELL))))
