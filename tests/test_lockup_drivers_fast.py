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
from jaxrod.lockup.staircase import BELOW_START, BRACKETED, WIDE, _next, _stage_rule, crossing, staircase
from jaxrod.lockup.verdict import LOCKED, SLIDING, Criterion, verdict

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
    """The full setting runs every lane at the base (16 segments per wave, 10 mm/s), twice the
    segments, half and a quarter of the speed (the quasi-static limit and the segment convergence
    at every point, issue [lockup-converged]); μL/ℓ = 4 (past the bound's lock-up) only at the base;
    the `refine` lanes (μL/ℓ = 0.5 and 3) also at four times the base's segments, and μL/ℓ = 3 at twice
    them at half and a quarter of the speed."""
    jobs = list(lx._jobs(lx.SETTINGS[False]))
    runs = [(16, 10e-3), (32, 10e-3), (16, 5e-3), (16, 2.5e-3)]
    assert jobs == ([((2.0, (0.5, 1.0, 1.5, 2.0), None), run) for run in runs]
                    + [((4.0, (3.0, 4.0), "auto"), runs[0])] + [((4.0, (3.0,), "auto"), run) for run in runs[1:]]
                    + [((2.0, (0.5,), None), (64, 10e-3)), ((4.0, (3.0,), None), (64, 10e-3)),
                       ((4.0, (3.0,), None), (32, 5e-3)), ((4.0, (3.0,), None), (32, 2.5e-3))])
    # without "lock" in converge a group with no converge lane is not run again; without converge
    # every lane runs at every setting
    S = dict(groups=((1.5, (0.5,), 0.7), (3.0, (2.0,), None)), runs=((8, 0.02), (12, 0.02)), converge=(2.0,))
    assert list(lx._jobs(S)) == [
        ((1.5, (0.5,), 0.7), (8, 0.02)), ((3.0, (2.0,), None), (8, 0.02)), ((3.0, (2.0,), None), (12, 0.02))]
    S.pop("converge")
    assert list(lx._jobs(S)) == [
        ((1.5, (0.5,), 0.7), (8, 0.02)), ((1.5, (0.5,), 0.7), (12, 0.02)), ((3.0, (2.0,), None), (8, 0.02)),
        ((3.0, (2.0,), None), (12, 0.02))]


def _run_row(X, w, v, c, e=0.01, quantity="F_far_max", status="bracketed"):
    """A run row crossing the bound at `c` with interpolation error `e`, inside a 2 % bracket."""
    return dict(quantity=quantity, muL_over_ell=X, n_segments=2 * w, push_speed=v, protocol="staircase", kind="run",
                lo=c - 0.01 * c, hi=c + 0.01 * c, crossing=c, crossing_error=e, status=status, segments_per_wave=w)


def test_the_converged_value_is_the_quarter_speeds_or_extrapolated_to_zero_speed_with_its_error_bar():
    """Crossings 2.00 (v), 2.10 (v/2), 2.14 (v/4) and 2.035 at twice the segments, interpolation
    errors 0.01: v/4 is +1.9 % on v/2, not converged at 1 %: extrapolated linearly through v/2, v/4
    to 2.18; the quadratic through all three gives (8·2.14 − 6·2.10 + 2)/3 = 2.1733…; bar =
    |2.18 − 2.1733| + (2·0.01 + 0.01) + |2.035 − 2.00|. Segments +1.75 % (converged at 2 %), half
    speed +5 %. At μL/ℓ = 2, v/4 +0.5 % on v/2: converged in speed, the value is v/4's 1.015, its
    bar |1.015 − 1.01| + 0.01 + 0.025 (twice the segments 1.035 against 1.01: +2.5 %, not converged),
    its bracket v/4's. A point with a run without a crossing or missing gets no row; the lock-up
    length's point (μL/ℓ NaN) is one point."""
    S = dict(runs=((16, 0.01), (32, 0.01), (16, 0.005), (16, 0.0025)))
    rows = [_run_row(1.0, 16, 0.01, 2.00), _run_row(1.0, 32, 0.01, 2.035),
            _run_row(1.0, 16, 0.005, 2.10), _run_row(1.0, 16, 0.0025, 2.14),
            _run_row(2.0, 16, 0.01, 1.01), _run_row(2.0, 32, 0.01, 1.035),
            _run_row(2.0, 16, 0.005, 1.01), _run_row(2.0, 16, 0.0025, 1.015),
            _run_row(3.0, 16, 0.01, 1.01), _run_row(3.0, 32, 0.01, 1.01),
            _run_row(3.0, 16, 0.005, 1.01), _run_row(3.0, 16, 0.0025, math.nan, status="open")]
    rows += [_run_row(math.nan, w, v, 2.93, 0.004, quantity="muL_lock") for w, v in S["runs"]]
    one, two, lock = lx.converged(rows, S)
    assert (one["quantity"], one["muL_over_ell"], one["kind"], one["push_speed"]) == ("F_far_max", 1.0, "converged", 0.0)
    assert one["status"] == "extrapolated to v = 0" and one["quasi_static"] == pytest.approx(2.18, abs=1e-12)
    assert one["error_bar"] == pytest.approx(abs(2.18 - (8 * 2.14 - 6 * 2.10 + 2.0) / 3) + 0.03 + 0.035, abs=1e-12)
    assert (one["lo"], one["hi"]) == (pytest.approx(2.18 - one["error_bar"]), pytest.approx(2.18 + one["error_bar"]))
    assert one["d_segments"] == pytest.approx(0.0175) and one["d_half_speed"] == pytest.approx(0.05)
    assert one["d_quarter_speed"] == pytest.approx(2.14 / 2.10 - 1)
    assert one["converged_segments"] and not one["converged_speed"] and one["segments_pair"] == "32/16"
    assert two["status"] == "converged in speed" and two["quasi_static"] == pytest.approx(1.015)
    assert two["error_bar"] == pytest.approx(0.005 + 0.01 + 0.025) and two["converged_speed"]
    assert not two["converged_segments"]
    assert (two["bracket_lo"], two["bracket_hi"]) == (pytest.approx(1.015 * 0.99), pytest.approx(1.015 * 1.01))
    assert lock["quantity"] == "muL_lock" and lock["quasi_static"] == pytest.approx(2.93)
    assert lock["error_bar"] == pytest.approx(0.004) and lock["converged_segments"] and lock["converged_speed"]
    assert lx.converged(rows, dict(runs=((16, 0.01), (32, 0.01), (16, 0.005)))) == []  # no quarter speed run


def test_the_jobs_run_costliest_first_and_a_lane_already_run_with_the_same_settings_is_skipped(
        tmp_path, monkeypatch, capsys):
    S = dict(groups=((2.0, (0.5, 1.0), None), (4.0, (3.0,), "auto")), f_c=6.0,
             runs=((16, 0.01), (24, 0.01), (16, 0.004)), converge=(1.0, "lock"), first_push=0.4, stage_push=0.15,
             max_stages=2, saves_per_stage=11)
    monkeypatch.setitem(lx.SETTINGS, "test", S)
    ran = []

    def job(args):  # a job's JSON with its lanes bracketed, where the staircase would have written it
        (Lx, Xs, lock), (per_wave, speed), S_job, path, progress = args
        ran.append(((Lx, Xs, lock), (per_wave, speed), progress, os.path.basename(path)))
        assert S_job is S
        lanes = [dict(X=X, vary_mu=False, status="bracketed", lo=1.0, hi=1.02, stages=[], profiles=[]) for X in Xs]
        lanes += [dict(X=1.0, vary_mu=True, status="bracketed", lo=2.0, hi=2.05, stages=[], profiles=[])] if lock else []
        with open(path, "w") as fh:
            json.dump(dict(L_over_ell=Lx, per_wave=per_wave, speed=speed, n=8, f_c=6.0, lanes=lanes, wall_s=1.0,
                           settings=S_job, ell=1.0, r=0.02, F0=1.0, l0=0.1, EI=1.0, w=1.0), fh)
        return path

    monkeypatch.setattr(lx, "_job", job)
    monkeypatch.setattr(lx, "_write", lambda out, S, results, wall: dict(results=results))
    summary = lx.lockup(str(tmp_path), quick="test", progress=True, workers=1)
    # cost: lanes × L/ℓ × segments per wave / speed
    assert ran == [((4.0, (), "auto"), (16, 0.004), True, "L4_Xlock_w16_v4.json"),
                   ((4.0, (3.0,), "auto"), (16, 0.01), True, "L4_X3-lock_w16_v10.json"),
                   ((4.0, (), "auto"), (24, 0.01), True, "L4_Xlock_w24_v10.json"),
                   ((2.0, (1.0,), None), (16, 0.004), True, "L2_X1_w16_v4.json"),
                   ((2.0, (0.5, 1.0), None), (16, 0.01), True, "L2_X0.5-1_w16_v10.json"),
                   ((2.0, (1.0,), None), (24, 0.01), True, "L2_X1_w24_v10.json")]
    assert "lock-up: 6 staircase(s) to run on 1 worker(s), f_c = 6 F0" in capsys.readouterr().out
    # one job result per lane, in the setting's order
    assert [(r["L_over_ell"], r["per_wave"], r["speed"], [ln["X"] for ln in r["lanes"]]) for r in summary["results"]] == [
        (2.0, 16, 0.01, [0.5]), (2.0, 16, 0.01, [1.0]), (2.0, 24, 0.01, [1.0]), (2.0, 16, 0.004, [1.0]),
        (4.0, 16, 0.01, [3.0]), (4.0, 16, 0.01, [1.0]), (4.0, 24, 0.01, [1.0]), (4.0, 16, 0.004, [1.0])]
    # again: every lane is there with the same settings; a job removed, one of other settings, and an
    # open lane of fewer stages allowed than the setting's are run again (only their lanes)
    ran.clear()
    os.remove(tmp_path / "jobs" / "L2_X1_w24_v10.json")
    other = tmp_path / "jobs" / "L4_X3-lock_w16_v10.json"
    other.write_text(json.dumps(dict(json.loads(other.read_text()), settings=dict(S, f_c=5.0))))
    opened = tmp_path / "jobs" / "L2_X0.5-1_w16_v10.json"
    d = json.loads(opened.read_text())
    d["lanes"][0]["status"] = "open"
    opened.write_text(json.dumps(dict(d, settings=dict(S, max_stages=1))))
    lx.lockup(str(tmp_path), quick="test", progress=False, workers=1)
    assert [r[:2] for r in ran] == [((4.0, (3.0,), "auto"), (16, 0.01)), ((2.0, (1.0,), None), (24, 0.01)),
                                    ((2.0, (0.5,), None), (16, 0.01))]
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
    assert sorted(os.listdir(tmp_path / "jobs")) == ["L1_X0.5-lock_w8_v10.json"]
    for name in ("curve.csv", "stages.csv", "onsets.csv", "curve.json", "curve.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    job = json.loads((tmp_path / "jobs" / "L1_X0.5-lock_w8_v10.json").read_text())
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
    row, locks = _rows(tmp_path / "curve.csv")
    assert float(row["muL_over_ell"]) == 0.5 and int(row["n_segments"]) == N and float(row["push_speed"]) == SPEED
    assert row["status"] == far["status"] and int(row["stages"]) == len(far["stages"])
    assert row["lo"] == ("nan" if far["lo"] is None else str(far["lo"]))
    assert row["hi"] == ("nan" if far["hi"] is None else str(far["hi"]))
    assert locks["quantity"] == "muL_lock"
    assert locks["status"] == lock["status"] and int(locks["stages"]) == len(lock["stages"])
    assert locks["lo"] == ("nan" if lock["lo"] is None else str(lock["lo"]))
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


def test_the_crossing_interpolates_the_steady_stages_and_estimates_its_error_by_a_quadratic():
    """`crossing` on hand-made stages, f_c = 6: on a linear law f = 2 + 4p (crossing at p = 1) the
    linear crossing is exact and so is the quadratic (error 0); on f = 6p² (crossing at p = 1) from
    stages at 0.9, 0.95, 1.05 the linear crossing is 0.95 + (6 − 5.415)/(6.615 − 5.415)·0.1 and the
    quadratic through the three is the law itself, so the error is the linear crossing's distance
    from 1; transient and locked stages are not read, and the stage order does not matter; a single
    steady stage below gives half the interval as the error; no steady stage above: None."""
    def st(p, f, status=SLIDING):
        return dict(parameter=p, f_in=f, status=status)

    lin = [st(p, 2 + 4 * p) for p in (0.8, 0.9, 1.05)]
    c, e = crossing(lin, 6.0)
    assert c == pytest.approx(1.0, rel=1e-12) and e == pytest.approx(0.0, abs=1e-12)
    quad = [st(1.05, 6 * 1.05 ** 2), st(0.9, 6 * 0.81), st(0.95, 6 * 0.95 ** 2), st(1.0, 3.0, "transient"),
            st(0.97, math.nan, "locked")]
    c, e = crossing(quad, 6.0)
    expect = 0.95 + (6 - 6 * 0.95 ** 2) / (6 * 1.05 ** 2 - 6 * 0.95 ** 2) * 0.1
    assert c == pytest.approx(expect, rel=1e-12) and e == pytest.approx(abs(expect - 1.0), rel=1e-9)
    assert e > 1e-3  # the curvature is seen
    c, e = crossing([st(0.9, 5.0), st(1.1, 7.0)], 6.0)
    assert (c, e) == (pytest.approx(1.0), pytest.approx(0.1))
    assert crossing([st(0.9, 5.0), st(1.1, 7.0, "locked")], 6.0) is None
    assert crossing([st(1.1, 7.0)], 6.0) is None


def test_the_stage_rule_on_synthetic_verdicts():
    """`_stage_rule` on hand-made stages, f_c = 6: a steady slide at ≤ f_c is a lower bound and sets the
    next parameter (`_next`); the stage that crosses f_c (or locks) is the upper bound and stops the
    lane, bracketed when hi − lo ≤ rel·hi (1.0 → 1.029 at rel = 3 %: 2.8 %), wide when not (1.0 → 1.05:
    4.8 %, and at rel = 4.5 %), below start without a lower bound; a transient stage is repeated
    `repeats` times (None, the lane open), then stops the lane as transient; unresolved and failed
    stop it with their status."""
    def lane():
        return dict(status="open", lo=None, hi=None, steady=[], repeats=0)

    a = lane()
    assert _stage_rule(a, 1.0, SLIDING, 5.0, 6.0, 0.03, 2) == pytest.approx(_next([(1.0, 5.0)], 1.0, 6.0, 0.03))
    assert (a["lo"], a["status"], a["steady"]) == (1.0, "open", [(1.0, 5.0)])
    assert _stage_rule(a, 1.029, SLIDING, 6.2, 6.0, 0.03, 2) is None
    assert (a["lo"], a["hi"], a["status"]) == (1.0, 1.029, BRACKETED)
    for rel in (0.03, 0.045):  # 1.0 → 1.05 is 4.76 % of 1.05
        b = lane()
        _stage_rule(b, 1.0, SLIDING, 5.9, 6.0, rel, 2)
        assert _stage_rule(b, 1.05, LOCKED, float("nan"), 6.0, rel, 2) is None and b["status"] == WIDE
    b = lane()
    _stage_rule(b, 1.0, SLIDING, 5.9, 6.0, 0.05, 2)
    _stage_rule(b, 1.05, LOCKED, float("nan"), 6.0, 0.05, 2)
    assert b["status"] == BRACKETED
    c = lane()
    assert _stage_rule(c, 2.0, SLIDING, 6.5, 6.0, 0.03, 2) is None and (c["status"], c["hi"]) == (BELOW_START, 2.0)
    d = lane()
    for k in range(2):
        assert _stage_rule(d, 1.0, "transient", 4.0, 6.0, 0.03, 2) is None
        assert (d["status"], d["repeats"]) == ("open", k + 1)
    assert _stage_rule(d, 1.0, "transient", 4.0, 6.0, 0.03, 2) is None and d["status"] == "transient"
    # a steady stage after a repeat resets the count
    e = lane()
    _stage_rule(e, 1.0, "transient", 4.0, 6.0, 0.03, 2)
    _stage_rule(e, 1.0, SLIDING, 4.0, 6.0, 0.03, 2)
    assert e["repeats"] == 0 and e["lo"] == 1.0
    for status in ("unresolved", "failed"):
        f = lane()
        assert _stage_rule(f, 1.0, status, 4.0, 6.0, 0.03, 2) is None and f["status"] == status and f["lo"] is None


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
        assert sorted(lane) == ["crossing", "crossing_error", "hi", "lo", "profiles", "stages", "status"]
        assert lane["status"] == BRACKETED, lane["stages"]
        (p0, f0), (p1, f1) = [(s["parameter"], s["f_in"]) for s in lane["stages"][-2:]]
        assert lane["crossing"] == pytest.approx(p0 + (2.2 - f0) * (p1 - p0) / (f1 - f0), rel=1e-12)
        assert lane["crossing_error"] == pytest.approx(0.5 * (p1 - p0), rel=1e-12)  # one steady stage below
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


def test_a_point_refined_to_four_times_the_segments_is_judged_on_the_last_refinement():
    """Where n against 2n fails and the point ran at 4n too (`SETTINGS[...]["refine"]`), the segment
    test is 4n against 2n and the bar's segment term the larger of |c(4n) − c(2n)| and the distance
    of the speed-converged value from c(2n); without the 4n run, |c(2n) − c(n)| as before. Where it
    also ran at 2n at half the speed, that pair is tested too, and its change replaces the
    distance of the value from c(2n) (both pairs measured, the larger change named)."""
    from jaxrod.experiments.lockup_convergence import converged

    S = {"runs": ((16, 0.01), (32, 0.01), (16, 0.005), (16, 0.0025))}

    def run(w, v, c, e=0.002):
        return dict(quantity="F_far_max", muL_over_ell=0.5, kind="run", segments_per_wave=w, push_speed=v,
                    status="bracketed", lo=c - 0.05, hi=c + 0.05, crossing=c, crossing_error=e)

    rows = [run(16, 0.01, 3.50), run(32, 0.01, 3.66), run(16, 0.005, 3.65), run(16, 0.0025, 3.66)]
    (coarse,) = converged(rows, S)
    assert coarse["segments_pair"] == "32/16" and not coarse["converged_segments"] and coarse["converged_speed"]
    assert coarse["quasi_static"] == pytest.approx(3.66)
    assert coarse["error_bar"] == pytest.approx(0.01 + 0.002 + 0.16)  # speed + v/4's interpolation + |c(2n) − c(n)|
    (fine,) = converged(rows + [run(64, 0.01, 3.67)], S)
    assert fine["segments_pair"] == "64/32" and fine["converged_segments"]
    assert fine["d_segments"] == pytest.approx(3.67 / 3.66 - 1)
    assert fine["quasi_static"] == pytest.approx(3.66)  # the value stays the speed-converged one at n
    assert fine["error_bar"] == pytest.approx(0.01 + 0.002 + 0.01)
    apart = [run(16, 0.01, 3.50), run(32, 0.01, 3.80), run(16, 0.005, 3.65), run(16, 0.0025, 3.66), run(64, 0.01, 3.81)]
    (far,) = converged(apart, S)
    assert far["converged_segments"] and far["error_bar"] == pytest.approx(0.01 + 0.002 + 0.14)  # |3.66 − 3.80|
    (slow,) = converged(apart + [run(32, 0.005, 3.68)], S)  # 2n at v/2: +0.82 % on n at v/2
    assert slow["converged_segments"] and slow["segments_pair"] == "32/16 at v/2"
    assert slow["d_segments"] == pytest.approx(3.68 / 3.65 - 1)
    assert slow["error_bar"] == pytest.approx(0.01 + 0.002 + 0.03)  # the v/2 pair's change, not |3.66 − 3.80|
    (off,) = converged(apart + [run(32, 0.005, 3.75)], S)  # +2.7 % at v/2: not converged, named
    assert not off["converged_segments"] and off["segments_pair"] == "32/16 at v/2"
    assert math.isnan(off["d_segments_faster"])


def test_a_point_run_at_twice_the_segments_at_a_quarter_of_the_speed_is_judged_there():
    """Where the point also ran at 2n at v/4, the speed its value is read from, that pair alone
    decides the segments: +0.27 % at v/4 converges though 2n at v/2 was +2.7 % (kept as
    `d_segments_faster`), and the bar's segment term is |c(2n, v/4) − c(n, v/4)|; −2.5 % at v/4
    does not converge though every faster pair did."""
    from jaxrod.experiments.lockup_convergence import converged

    S = {"runs": ((16, 0.01), (32, 0.01), (16, 0.005), (16, 0.0025))}

    def run(w, v, c, e=0.002):
        return dict(quantity="F_far_max", muL_over_ell=3.0, kind="run", segments_per_wave=w, push_speed=v,
                    status="bracketed", lo=c - 0.05, hi=c + 0.05, crossing=c, crossing_error=e)

    rows = [run(16, 0.01, 3.50), run(32, 0.01, 3.80), run(16, 0.005, 3.65), run(16, 0.0025, 3.66),
            run(64, 0.01, 3.81), run(32, 0.005, 3.75)]
    (pt,) = converged(rows + [run(32, 0.0025, 3.67)], S)
    assert pt["converged_segments"] and pt["segments_pair"] == "32/16 at v/4"
    assert pt["d_segments"] == pytest.approx(3.67 / 3.66 - 1)
    assert pt["d_segments_faster"] == pytest.approx(3.75 / 3.65 - 1)
    assert pt["quasi_static"] == pytest.approx(3.66)
    assert pt["error_bar"] == pytest.approx(0.01 + 0.002 + 0.01)
    (bad,) = converged([run(16, 0.01, 3.50), run(32, 0.01, 3.52), run(16, 0.005, 3.65), run(16, 0.0025, 3.66),
                        run(32, 0.0025, 3.66 * 0.975)], S)
    assert not bad["converged_segments"] and bad["d_segments"] == pytest.approx(-0.025)
    assert bad["d_segments_faster"] == pytest.approx(3.52 / 3.50 - 1)


def test_the_path_band_is_the_other_protocols_crossings_against_the_base_run(tmp_path):
    """`protocol_rows` reads `stage_protocols.json`'s runs of every point (not the single-lane runs
    that came first), each lane's crossing from its steady stages; `converged` puts the other
    protocols' crossings at the base (n, v) against the base run's as the path band (0 included),
    and a protocol row never stands in for the base run."""
    from jaxrod.experiments.lockup_convergence import converged
    from jaxrod.experiments.lockup_path import PROTOCOLS, protocol_rows

    lane = dict(point=1.0, start=1.0, status="bracketed", lo=2.0, hi=2.05, stages=5,
                steady=[(1.9, 5.0), (2.0, 5.8), (2.05, 6.2)])
    lock = dict(point="lock", start=1.0, status="open", lo=3.0, hi=None, stages=24, steady=[(3.0, 5.5)])
    runs = {"settle": dict(protocol="settle", muL_over_ell=1.0, steady=[]),
            "settle@L2": dict(protocol="settle", L_over_ell=2.0, n=37, speed=0.01, lanes=[lane, lock])}
    (tmp_path / "stage_protocols.json").write_text(json.dumps(runs))
    far, lk = protocol_rows(str(tmp_path), 6.0, 16)
    assert (far["protocol"], far["muL_over_ell"], far["n_segments"], far["segments_per_wave"]) == (
        PROTOCOLS["settle"], 1.0, 37, 16)
    assert far["crossing"] == pytest.approx(2.025) and far["source"] == "stage_protocols.json:settle@L2"
    assert lk["quantity"] == "muL_lock" and math.isnan(lk["crossing"]) and math.isnan(lk["hi"])
    assert protocol_rows(str(tmp_path / "none"), 6.0, 16) == []

    S = dict(runs=((16, 0.01), (32, 0.01), (16, 0.005), (16, 0.0025)))
    rows = [_run_row(1.0, 16, 0.01, 2.00), _run_row(1.0, 32, 0.01, 2.01), _run_row(1.0, 16, 0.005, 2.02),
            _run_row(1.0, 16, 0.0025, 2.02)]
    (alone,) = converged(rows, S)
    assert (alone["d_path_lo"], alone["d_path_hi"], alone["path_protocols"]) == (0.0, 0.0, 0)
    other = [dict(_run_row(1.0, 16, 0.01, 2.06), protocol="staircase_settle_0.3m"),
             dict(_run_row(1.0, 16, 0.01, 1.98), protocol="staircase_start_half"),
             dict(_run_row(1.0, 16, 0.005, 1.50), protocol="staircase_start_half")]  # not at the base speed
    (band,) = converged(other + rows, S)  # listed first: still not taken for the base run
    assert band["quasi_static"] == alone["quasi_static"] and band["d_half_speed"] == pytest.approx(0.01)
    assert (band["d_path_lo"], band["d_path_hi"], band["path_protocols"]) == (
        pytest.approx(-0.01), pytest.approx(0.03), 2)
