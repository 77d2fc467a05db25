"""Structure and sanity of `results.json` from a tiny run (not specific expected values). The
whole reproduction (every experiment, 2.5 min) is `slow`; the default suite runs E2 and E3."""

import json
import math

import pytest

from jaxrod.reproduce import EXPERIMENTS, reproduce


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    res = reproduce(list(EXPERIMENTS), str(out), quick="tiny", progress=False)  # "all" and lockup
    return out, res


@pytest.mark.slow
def test_every_experiment_writes_figures_data_and_numbers(results):
    out, res = results
    assert set(res) == {"e1", "e2", "e3", "e4", "e5", "e6", "helix", "lockup"}
    assert json.loads((out / "results.json").read_text()).keys() == res.keys()
    for f in ("e2/phase.png", "e3/map.png", "e3/map.json", "e4/e4_critical_load.png", "e4/e4_critical_load.csv",
              "e5/e5_modes.png", "e5/e5_modes.csv", "e6/e6_spectra.png", "e6/e6_spectra.csv",
              "e1/e1_force_displacement.png", "e1/e1_force_displacement.csv", "e1/e1_speed.png", "e1/e1_speed.csv", "e6/e6_full_model.png",
              "e6/e6_full_model.csv", "helix/helix_post_buckling.png", "helix/helix_post_buckling.csv",
              "lockup/curve.png", "lockup/curve.csv", "lockup/stages.csv", "lockup/curve.json"):
        assert (out / f).stat().st_size > 0, f


@pytest.mark.slow
def test_exponents_are_finite_and_frictionless_loads_vanish(results):
    _, res = results
    assert math.isfinite(res["e3"]["boundary_exponent"]) and res["e3"]["boundary_exponent"] < 0
    assert res["e3"]["frictionless_buckles_for_every_dF_gt_0"] is True
    # the phase portraits' grid classification agrees with the theory's stable zones
    agreement = res["e2"]["grid_agreement_simulated_vs_analytic"]
    assert len(agreement) == 6 and min(agreement.values()) >= 0.95, agreement
    for label, entry in res["e4"].items():
        if not isinstance(entry, dict):
            continue
        assert math.isfinite(entry["exponent"]) and entry["exponent"] > 0, label
        # frictionless: the rod buckles as soon as it is loaded past F0; what is left is the
        # growth time to reach 0.5 rad within the search horizon
        assert entry["frictionless_result"] == 0
        assert abs(entry["frictionless_dF_star"]) < 0.2 * 1.308, label
        assert all(f > abs(entry["frictionless_dF_star"]) for f in entry["dF_star"] if f == f), label


@pytest.mark.slow
def test_buckling_modes_do_not_fall_below_the_frictionless_mode(results):
    _, res = results
    for kind in ("random-velocity", "random-position"):
        e = res["e5"][kind]
        assert all(m >= 6 for m in e["dominant_mode_mean"] if m == m), kind
        # single realizations may pick mode 5 (F0_5 is 0.9 % above F0_6 and random fields do not
        # give every mode the same amplitude); never anything lower
        assert e["dominant_mode_min"] >= 5, kind
    sine = next(v for k, v in res["e6"].items() if isinstance(v, dict) and k.startswith("sine"))
    assert sine["dominant_mode_after"] == 6


@pytest.mark.slow
def test_full_model_e1_and_e6_are_sane(results):
    """E1: every rod buckles within the horizon, friction raises the critical force above the
    frictionless one at every v₀, and the frictionless one is not below F⁰₆. E6 (3D rod): the
    rod stays on the wall (no upward buckling), twist holds a small share of the energy, and
    the energy balance closes."""
    _, res = results
    e1 = res["e1"]
    f0, f3 = e1["mu=0.0"]["critical_force"], e1["mu=0.3"]["critical_force"]
    assert all(e1["mu=0.0"]["buckled"]) and all(e1["mu=0.3"]["buckled"])
    assert all(b > a for a, b in zip(f0, f3))
    assert min(f0) > 0.9 * e1["F0_6_theory"]
    e6 = res["e6"]["full_model"]
    assert e6["max_lift_off_gap_over_R"] < 0.01
    assert e6["twist_over_total_max"] < 0.01
    assert e6["energy_balance_max_J"] < 1e-2 * e6["dissipated_J"]


@pytest.mark.slow
def test_post_buckling_cycle_closes_its_energy_balance(results):
    """The load–hold–unload–hold cycle: the energy balance closes over the whole path, the
    friction cycle dissipates more than the frictionless one, and the pushed end comes back."""
    _, res = results
    h = res["helix"]
    for mu in ("mu=0.0", "mu=0.3"):
        assert h[mu]["energy_balance_max_J"] < 1e-2 * h[mu]["work_in_J"], mu
        assert h[mu]["loop_area_J"] > 0, mu
    assert h["mu=0.3"]["dissipated_J"] > h["mu=0.0"]["dissipated_J"]
    assert h["theory"]["onset_chen"] < h["theory"]["onset_mitchell"]


@pytest.mark.slow
def test_lockup_curve_carries_every_variant_beside_the_rod(results):
    """The lock-up experiment (tiny: one μL/ℓ and the lock-up lane, two short stages): every
    row of the curve has the columns the README names and the soft string's values at the entry
    force bound, each below its unbounded one; its lock-up length at the bound is below the
    unbounded one for every variant."""
    _, res = results
    lk = res["lockup"]
    assert lk["model"] == "rod3d" and len(lk["curve"]) == 1 and len(lk["lockup_length"]) == 1
    row = lk["curve"][0]
    for col in ("muL_over_ell", "n_segments", "push_speed", "F_far_max_lo", "F_far_max_hi", "status"):
        assert col in row, col
    for onset, law in (("chen", "with_weight"), ("wu_juvkam_wold", "without_weight")):
        assert 0 < row[f"soft_{onset}/{law}_at_fc"] < row[f"soft_{onset}/{law}_unbounded"]
        lock = lk["lockup_length"][0]
        assert 0 < lock[f"soft_{onset}/{law}_at_fc"] < lock[f"soft_{onset}/{law}_unbounded"]


def test_quick_reproduction_of_e2_and_e3(tmp_path):
    """The default suite's version: E2 (phase portrait) and E3 (map) in their tiny setting write
    their figures, data and numbers; the map's exponent is negative and μ = 0 buckles for every
    ΔF > 0, as in the full run."""
    res = reproduce(["e2", "e3"], str(tmp_path), quick="tiny", progress=False)
    assert set(res) == {"e2", "e3"}
    assert json.loads((tmp_path / "results.json").read_text()).keys() == res.keys()
    for f in ("e2/phase.png", "e3/map.png", "e3/map.json"):
        assert (tmp_path / f).stat().st_size > 0, f
    assert math.isfinite(res["e3"]["boundary_exponent"]) and res["e3"]["boundary_exponent"] < 0
    assert res["e3"]["frictionless_buckles_for_every_dF_gt_0"] is True
    # E2's number: the phase portraits' grid of initial states, each classified by a simulation
    # and by the theory's stable zone (P5), agree on at least 95 % of the points of every panel
    agreement = res["e2"]["grid_agreement_simulated_vs_analytic"]
    print("E2 agreement per panel:", agreement)
    assert len(agreement) == 6 and min(agreement.values()) >= 0.95, agreement


def test_statistics_over_realizations_skip_failed_ones_without_warnings():
    """E4's and E5's mean and spread over the realizations that succeeded equal numpy's
    nanmean/nanstd (ddof 1 and 0), and a μ where none did gives NaN silently (the tiny run hits
    it in E4)."""
    import warnings

    import numpy as np

    from jaxrod.experiments._stats import finite_mean_std

    nan = np.nan
    F = np.array([[1.0, 2.0, nan], [nan, nan, nan], [3.0, nan, nan], [1.0, 2.0, 4.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mean, std = finite_mean_std(F)
        _, std0 = finite_mean_std(F, ddof=0)
        one = finite_mean_std(np.array([[2.0], [nan]]))
        row = finite_mean_std(F[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        np.testing.assert_array_equal(mean, np.nanmean(F, axis=1))
        np.testing.assert_allclose(std, np.nanstd(F, axis=1, ddof=1), rtol=1e-15)
        np.testing.assert_allclose(std0, np.nanstd(F, axis=1), rtol=1e-15)
    np.testing.assert_array_equal(one[0], [2.0, nan])
    np.testing.assert_array_equal(one[1], [nan, nan])
    np.testing.assert_allclose(row, (1.5, np.sqrt(0.5)), rtol=1e-15)


def test_reproduce_with_the_3d_rod_refuses_what_it_does_not_run(tmp_path):
    with pytest.raises(ValueError, match="model = 'beam'"):
        reproduce(["e3"], str(tmp_path), model="beam")
    with pytest.raises(ValueError, match=r"\['e1', 'lockup'\] for model 'rod3d'"):
        reproduce(["e1", "lockup"], str(tmp_path), model="rod3d")
    with pytest.raises(ValueError, match="n = 2 is invalid"):
        reproduce(["e3"], str(tmp_path), model="rod3d", n=2)
    assert not (tmp_path / "results.json").exists()


@pytest.mark.slow  # 8 segments, 2 loads, 3 E4 points (and their wider retries), E5 on them, E6C (~1 min)
def test_reproduce_with_the_3d_rod_writes_every_point_once(tmp_path):
    """`reproduce e3 e4 e5 e6 --model rod3d` (tiny): each part writes its files and records under
    `<name>_rod3d`; run again, it replays: no run and no CSV row is added."""
    res = reproduce(["e3", "e4", "e5", "e6"], str(tmp_path), quick="tiny", model="rod3d", progress=False)
    assert set(res) == {"e3_rod3d", "e4_rod3d", "e5_rod3d", "e6_rod3d"}
    assert res["e3_rod3d"]["n"] == 8 and len(res["e3_rod3d"]["runs"]) == 2
    files = ("e3/rod3d_runs.csv", "e3/rod3d_boundary_n8_implicit.png", "e4/rod3d_n8.csv", "e4/rod3d_n8.png",
             "e5/rod3d_n8.png", "e6/rod3d_random_position_n8.csv")
    assert all((tmp_path / f).exists() for f in files) and res["e5_rod3d"]["n"] == 8
    before = {f: (tmp_path / f).read_text() if f.endswith(".csv") else None for f in files}
    e4_rows = before["e4/rod3d_n8.csv"].splitlines()
    assert len(e4_rows) >= 1 + 2 + 1 and all(r.split(",")[0] in "ABC" for r in e4_rows[1:])  # + wider retries
    again = reproduce(["e3", "e4", "e5", "e6"], str(tmp_path), quick="tiny", model="rod3d", progress=False)
    for f, text in before.items():
        assert text is None or (tmp_path / f).read_text() == text, f
    assert again["e3_rod3d"]["runs"] == res["e3_rod3d"]["runs"]


def test_e4_with_the_3d_rod_takes_a_point_of_a_longer_horizon_and_runs_no_other(tmp_path, monkeypatch):
    """A point recorded on the setting's horizon or a longer one (a run stable for longer is stable
    for the shorter) is reported, on its longest horizon, and not run again; a point recorded only
    on a shorter horizon is run (here `e4_point` raises instead), and so is one whose bracket held no
    boundary, with a wider bracket."""
    from jaxrod.experiments.e4 import rod3d as paper3d

    cols = paper3d.E4_COLUMNS  # the tiny setting: n = 8, μ = 0.3, one realization, horizon 0.05 s
    path = tmp_path / "rod3d_n8.csv"

    def write(rows):
        path.write_text(",".join(cols) + "\n" + "".join(",".join(str(r.get(c, "")) for c in cols) + "\n"
                                                        for r in rows))

    def refuse(case, mu, realization, n, t1, width, rtol):
        raise RuntimeError(f"ran {case} {realization} at width {width:g}")

    monkeypatch.setattr(paper3d, "e4_point", refuse)
    a = [dict(case="A", mu=0.3, realization=0, n=8, t1=t1, dF_star_field=9.3, dF_star=f, result=0)
         for t1, f in ((0.5, 9.0), (2.0, 9.1))] + [
        dict(case="C", mu=0.3, realization=0, n=8, t1=0.05, dF_star_field=7.0, dF_star=7.2, result=0)]
    b_short = dict(case="B", mu=0.3, realization=0, n=8, t1=0.01, dF_star_field=13.6, dF_star=11.0, result=0)
    write(a + [b_short])
    with pytest.raises(RuntimeError, match="^ran B 0 at width 1.5$"):
        paper3d.e4(str(tmp_path), quick="tiny", progress=False)
    write(a + [b_short, {**b_short, "t1": 0.05, "dF_star": 12.0}])
    res = paper3d.e4(str(tmp_path), quick="tiny", progress=False)
    assert res["points"] == {"A mu=0.3": dict(rod3d=[9.1], field=[9.3]), "B mu=0.3": dict(rod3d=[12.0], field=[13.6]),
                             "C mu=0.3": dict(rod3d=[7.2], field=[7.0])}
    # a search whose bracket held no boundary (result 2) is run again with the width squared
    write(a + [{**b_short, "t1": 0.05, "width": 1.5, "dF_star": "nan", "result": 2}])
    with pytest.raises(RuntimeError, match="^ran B 0 at width 2.25$"):
        paper3d.e4(str(tmp_path), quick="tiny", progress=False)
