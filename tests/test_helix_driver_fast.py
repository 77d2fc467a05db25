"""The post-buckling driver's bookkeeping, without 3D runs: `load_path` stitches its stages
(times, end displacement, energy accounts, the state handed on) from a recording stand-in for the
3D run, and `post_buckling` reports, from a synthetic load path of exact helices, the entries its
docstring and the README name (the helix at the largest displacement, Mitchell's and Lubinski's
laws, the CSV). The physics of a real path is the `slow` test in tests/test_rod3d_helix.py."""

from __future__ import annotations

import csv
import math
import types

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.experiments import helix
from jaxrod.experiments import rod3d as rod3d_driver
from jaxrod.experiments.helix import helix_measures, load_path, post_buckling
from jaxrod.integrators.base import save_grid
from jaxrod.rod3d import Rod3D


class _Run:
    """Stands in for `jaxrod.experiments.rod3d.run`: each call is one stage; the saved arrays are
    stage-local (time from 0, the end's position from an arbitrary origin, the energy accounts
    from 0), as the real run returns them."""

    def __init__(self, n, result=0):
        self.n, self.calls, self.result = n, [], result

    def __call__(self, model, q0, v0, t1, n_save, dt, **kw):
        k = len(self.calls)
        self.calls.append(dict(model=model, q0=q0, v0=v0, t1=t1, n_save=n_save, dt=dt, **kw))
        ts = np.linspace(0.0, t1, n_save)
        speed = float(model.speed)
        end_x = 3.0 + 7.0 * k - speed * ts  # the pushed end moves along −x at `speed`
        reaction = np.stack([100.0 + ts, 2.0 + 10.0 * k + ts, -50.0 - ts], -1)
        x = np.zeros((n_save, self.n + 1, 3)) + (k + ts)[:, None, None]
        obs = dict(end_x=end_x, reaction=reaction, normal_force=np.full((n_save, self.n + 1), k + 0.5),
                   axial_force=np.full((n_save, self.n), k + 0.25))
        return types.SimpleNamespace(
            result=self.result, ts=ts, observables=obs, q=types.SimpleNamespace(x=x),
            energies={"bending": 1.0 + ts, "kinetic": 0.5 * ts}, dissipated=0.1 * ts * (k + 1),
            work_in=0.3 * ts * (k + 1), q_final=("q after stage", k), v_final=("v after stage", k))


STAGES = [(4e-3, 0.5), (0.0, 0.2), (-4e-3, 0.5)]


@pytest.fixture
def stitched(monkeypatch):
    fake = _Run(8)
    steps = []
    monkeypatch.setattr(rod3d_driver, "run", fake)
    monkeypatch.setattr(helix, "default_step", lambda model, q, scheme: steps.append((model, q, scheme)) or 1e-3)
    p = load_path(jr.RodChannel.reference(0.0), 8, STAGES, sps=10.0, damping=7.0, progress=False, scheme="leapfrog")
    return p, fake, steps


def test_load_path_runs_each_stage_from_the_previous_ones_final_state(stitched):
    p, fake, steps = stitched
    assert len(fake.calls) == 3
    for k, (call, (speed, duration)) in enumerate(zip(fake.calls, STAGES)):
        assert float(call["model"].speed) == speed and float(call["model"].damping) == 7.0
        assert call["model"].n == 8 and call["t1"] == duration
        assert call["n_save"] == round(duration * 10.0) + 1
        assert call["dt"] == 1e-3 and call["stop_on_buckle"] is False and call["save_state"] is True
        if k:
            assert call["q0"] == ("q after stage", k - 1) and call["v0"] == ("v after stage", k - 1)
    # the default step is asked of each stage's rod, at its starting configuration, for the scheme run
    assert [m is c["model"] for (m, _, _), c in zip(steps, fake.calls)] == [True] * 3
    assert steps[1][1] == ("q after stage", 0) and steps[2][1] == ("q after stage", 1)
    assert {sc for _, _, sc in steps} == {"leapfrog"} and {c["scheme"] for c in fake.calls} == {"leapfrog"}
    # the first stage starts from the straight rod on the wall with the mode-6 imperfection of 0.5 mm
    s = np.arange(9) / 8
    unloaded = Rod3D(jr.RodChannel.reference(0.0), 8, control="displacement", damping=7.0)
    start = unloaded.initial_state(0.0, lateral_offset=0.5e-3 * np.sin(6 * np.pi * s))
    np.testing.assert_array_equal(np.asarray(fake.calls[0]["q0"].x), np.asarray(start[0].x))
    np.testing.assert_array_equal(np.asarray(fake.calls[0]["v0"].v), np.asarray(start[1].v))
    np.testing.assert_array_equal(p["dt"], [save_grid(d, round(d * 10.0) + 1, 1e-3)[1] for _, d in STAGES])


def test_load_path_stitches_time_displacement_and_energy_accounts(stitched):
    p, _, _ = stitched
    # one save per 0.1 s over 1.2 s; the first save of each later stage repeats the previous last
    np.testing.assert_allclose(p["ts"], np.linspace(0.0, 1.2, 13), atol=1e-12)
    np.testing.assert_array_equal(p["stage"], [0] * 6 + [1] * 2 + [2] * 5)
    # d: pushed 2 mm at 4 mm/s, held, pulled back 2 mm
    d = np.interp(p["ts"], [0.0, 0.5, 0.7, 1.2], [0.0, 2e-3, 2e-3, 0.0])
    np.testing.assert_allclose(p["d"], d, atol=1e-13)
    # the reaction is the y-component of the run's reaction observable
    np.testing.assert_allclose(p["reaction"][:6], 2.0 + np.linspace(0, 0.5, 6))
    np.testing.assert_allclose(p["reaction"][6:8], 12.0 + np.array([0.1, 0.2]))
    # accounts accumulate across stages: stage k adds (k + 1)·0.1 J/s dissipated, (k + 1)·0.3 J/s in
    dissipated = np.interp(p["ts"], [0.0, 0.5, 0.7, 1.2], [0.0, 0.05, 0.09, 0.24])
    np.testing.assert_allclose(p["dissipated"], dissipated, atol=1e-12)
    np.testing.assert_allclose(p["work_in"], 3.0 * dissipated, atol=1e-12)
    # the energy is the sum of the run's terms (stage-local; the accounts carry the balance)
    local_t = np.r_[np.linspace(0, 0.5, 6), [0.1, 0.2], np.linspace(0.1, 0.5, 5)]
    np.testing.assert_allclose(p["energy"], 1.0 + 1.5 * local_t, atol=1e-12)
    assert p["x"].shape == (13, 9, 3) and p["normal_force"].shape == (13, 9) and p["axial_force"].shape == (13, 8)
    np.testing.assert_allclose(p["normal_force"][:, 0], np.r_[[0.5] * 6, [1.5] * 2, [2.5] * 5])


def test_load_path_uses_a_given_step_and_stops_on_a_non_finite_stage(monkeypatch):
    fake = _Run(6)
    monkeypatch.setattr(rod3d_driver, "run", fake)
    monkeypatch.setattr(helix, "default_step", lambda model, q, scheme: pytest.fail("a given dt must be used"))
    load_path(jr.RodChannel.reference(0.3), 6, [(1e-3, 0.2)], sps=20.0, dt=2e-4, scheme="verlet", progress=False)
    assert fake.calls[0]["dt"] == 2e-4 and fake.calls[0]["scheme"] == "verlet"
    monkeypatch.setattr(rod3d_driver, "run", _Run(6, result=3))
    with pytest.raises(FloatingPointError, match=r"^stage 0 of the load path became non-finite \(result 3\)\.$"):
        load_path(jr.RodChannel.reference(0.3), 6, [(1e-3, 0.2)], sps=20.0, dt=2e-4, progress=False)


def test_load_path_prints_each_stage_when_asked(monkeypatch, capsys):
    monkeypatch.setattr(rod3d_driver, "run", _Run(6))
    load_path(jr.RodChannel.reference(0.0), 6, [(2e-3, 0.1), (0.0, 0.1)], sps=20.0, dt=1e-3)
    assert capsys.readouterr().out.splitlines() == ["  stage 0: speed +2 mm/s for 0.1 s (6 segments)",
                                                    "  stage 1: speed +0 mm/s for 0.1 s (6 segments)"]


# ------------------------------------------------------------- post_buckling on exact helices


def _helix_path(rod, n, stages, sps=20.0, progress=True):
    """A load path whose saves are exact helices on the wall: θ = β s, β growing linearly with the
    end displacement (0 to 12 1/m at d_max) and back; the axial force 2EIβ² + 1 N (a little above
    Lubinski's), the wall force the helix equilibrium plus gravity's normal component."""
    L, R, EI, w = float(rod.L), float(rod.R), float(rod.EI), float(rod.w)
    k = [np.full(max(2, round(d * sps) + 1) - (i > 0), i) for i, (_, d) in enumerate(stages)]
    stage = np.concatenate(k)
    ts = np.concatenate([np.linspace(0, d, len(kk) + (i > 0))[(i > 0):] + sum(dd for _, dd in stages[:i])
                         for i, ((_, d), kk) in enumerate(zip(stages, k))])
    t_load = stages[0][1]
    d_max = stages[0][0] * t_load
    d = d_max * np.interp(ts, np.cumsum([0] + [dd for _, dd in stages]), [0, 1, 1, 0, 0])
    beta = 12.0 * d / d_max
    # unloaded, a residual twist relaxes through the last hold from 2 to 1 1/m (β s ≤ π: no turn over the top)
    beta = np.where(stage == 3, beta + 1.0 + (ts[-1] - ts) / stages[3][1], beta)
    s = np.linspace(0.0, L, n + 1)
    th = beta[:, None] * s
    x = np.stack([np.broadcast_to(s, th.shape), R * np.sin(th), -R * np.cos(th)], -1)
    F = 2.0 * EI * beta**2 + 1.0
    N = (R * beta**2 * (F - EI * beta**2))[:, None] + w * np.cos(th)
    reaction = F + 0.5 * float(rod.mu_d) * np.sign(np.gradient(d))
    return dict(ts=ts, d=d, reaction=reaction, x=x, normal_force=N, axial_force=np.repeat(F[:, None], n, 1),
                energy=0.01 * d / d_max, dissipated=0.002 * ts, work_in=0.001 * ts + 0.01 * d / d_max,
                stage=stage, dt=np.full(len(stages), 1e-4))


@pytest.fixture
def cycle(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(helix, "load_path", lambda *a, **k: calls.append((a, k)) or _helix_path(*a, **k))
    res = post_buckling(str(tmp_path), quick="tiny", progress=False)
    return res, calls, tmp_path


def test_post_buckling_loads_holds_unloads_and_holds_at_both_frictions(cycle):
    res, calls, _ = cycle
    S = helix.HELIX_SIZES["tiny"]
    v, d_max, hold = S["speed"], S["d_max"], S["hold"]
    assert [float(a[0].mu_d) for a, _ in calls] == [0.0, 0.3]
    for a, k in calls:
        assert a[1] == S["n"] and a[2] == [(v, d_max / v), (0.0, hold), (-v, d_max / v), (0.0, hold)]
        assert k == dict(sps=S["sps"], progress=False)
    assert res["n_segments"] == S["n"] and res["speed_m_s"] == v and res["d_max_m"] == d_max
    assert res["hold_s"] == hold and res["damping_1_s"] == 50.0
    assert res["theory"] == helix.helix_theory(jr.RodChannel.reference(0.0))


def test_post_buckling_reports_the_helix_at_the_largest_displacement(cycle):
    res, calls, _ = cycle
    rod = jr.RodChannel.reference(0.0)
    EI, R, w = float(rod.EI), float(rod.R), float(rod.w)
    p = _helix_path(*calls[0][0], **calls[0][1])
    held = np.flatnonzero(p["stage"] == 1)[-1]
    r = res["mu=0.0"]
    F = 2.0 * EI * 144.0 + 1.0  # β = 12 1/m at d_max
    hx = r["helix_at_d_max"]
    assert math.isclose(hx["axial_force_N"], F, rel_tol=1e-12)
    assert math.isclose(hx["pitch_m"], 2 * math.pi / 12.0, rel_tol=1e-9)
    assert math.isclose(hx["pitch_lubinski_m"], math.pi * math.sqrt(8 * EI / F), rel_tol=1e-12)
    assert math.isclose(hx["N_equilibrium_N_m"], R * 144.0 * (F - EI * 144.0), rel_tol=1e-9)
    assert math.isclose(hx["mitchell_RF2_4EI_N_m"], R * F**2 / (4 * EI), rel_tol=1e-12)
    assert math.isclose(hx["mitchell_plus_w_N_m"], R * F**2 / (4 * EI) + w, rel_tol=1e-12)
    h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
    assert math.isclose(hx["N_bottom_N_m"], h["N_bottom"][held], rel_tol=1e-12)
    assert math.isclose(hx["N_mean_N_m"], h["N_mean"][held], rel_tol=1e-12)
    assert r["state_at_d_max"] == {"axial_force_N": hx["axial_force_N"], "turns_mid": float(h["turns"][held]),
                                   "theta_linearity_r2": float(h["linearity"][held]), "helix": True}
    assert r["turns_at_d_max"] == float(h["turns"][held])
    # after unloading: the last save's, the end of the last hold
    assert r["turns_after_unloading"] == float(h["turns"][-1]) != float(h["turns"][-2])
    assert r["max_abs_theta_after_unloading"] == float(h["max_abs_theta"][-1]) > 0.0


def test_post_buckling_compares_every_helical_loading_save_with_lubinski_and_the_equilibrium(cycle):
    res, calls, _ = cycle
    rod = jr.RodChannel.reference(0.0)
    p = _helix_path(*calls[0][0], **calls[0][1])
    h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
    hx = (p["stage"] == 0) & h["helical"]
    r = res["mu=0.0"]["helical_saves_loading"]
    assert r["count"] == int(hx.sum()) > 1
    lub = (2.0 * float(rod.EI) * h["beta"][hx] ** 2 + 1.0) / (2.0 * float(rod.EI) * h["beta"][hx] ** 2)
    assert r["F_over_lubinski_median_min_max"] == pytest.approx([np.median(lub), lub.min(), lub.max()], rel=1e-12)
    eq = h["N_minus_gravity"][hx] / h["N_equilibrium"][hx]
    assert r["N_over_equilibrium_median_min_max"] == pytest.approx([np.median(eq), eq.min(), eq.max()], rel=1e-12)


def test_post_buckling_records_the_first_full_turn_and_going_over_the_top(cycle):
    res, calls, _ = cycle
    for mu, (a, k) in zip((0.0, 0.3), calls):
        rod = jr.RodChannel.reference(mu)
        p = _helix_path(*a, **k)
        h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
        r = res[f"mu={mu}"]
        i = int(np.flatnonzero(h["over_top"] & (p["stage"] == 0))[0])
        assert r["over_the_top"] == {"reaction_N": p["reaction"][i], "axial_force_mid_N": h["F"][i],
                                     "reaction_save_before_N": p["reaction"][i - 1], "d_mm": p["d"][i] * 1e3}
        j = int(np.flatnonzero((np.abs(h["turns"]) >= 1.0) & (p["stage"] == 0))[0])
        assert j > i  # the rod goes over the top before the middle half holds a full turn
        assert r["first_full_turn_mid"] == {"reaction_N": p["reaction"][j], "axial_force_mid_N": h["F"][j],
                                            "d_mm": p["d"][j] * 1e3}
        loading = p["stage"] == 0
        assert r["peak_reaction_N"] == p["reaction"][loading].max()
        assert r["work_in_J"] == p["work_in"][-1] and r["dissipated_J"] == p["dissipated"][-1]
        balance = p["energy"] - p["energy"][0] + p["dissipated"] - p["work_in"]
        assert math.isclose(r["energy_balance_max_J"], np.abs(balance).max(), rel_tol=1e-12)
        area = np.sum(0.5 * (p["reaction"][1:] + p["reaction"][:-1]) * np.diff(p["d"]))
        assert math.isclose(r["loop_area_J"], area, rel_tol=1e-12, abs_tol=1e-15)
        assert r["dt"] == [1e-4] * 4
    # friction opens the loop: 0.5 μ N above on loading, below on unloading, over 2·d_max
    assert res["mu=0.0"]["loop_area_J"] == pytest.approx(0.0, abs=1e-15)
    assert res["mu=0.3"]["loop_area_J"] > 0


def test_post_buckling_writes_one_csv_row_per_save_and_friction(cycle):
    res, calls, out = cycle
    with open(out / "helix_post_buckling.csv") as fh:
        rows = list(csv.DictReader(fh))
    p = _helix_path(*calls[0][0], **calls[0][1])
    h = helix_measures(jr.RodChannel.reference(0.0), p["x"], p["normal_force"], p["axial_force"])
    assert len(rows) == 2 * len(p["ts"])
    assert list(rows[0]) == ["mu", "t", "stage", "d", "reaction", "axial_force_mid", "turns_mid", "pitch",
                             "N_mean", "N_minus_gravity", "max_abs_theta"]
    assert [float(r["mu"]) for r in rows] == [0.0] * len(p["ts"]) + [0.3] * len(p["ts"])
    for i in (0, len(p["ts"]) // 4, len(p["ts"]) - 1):
        row = rows[i]
        assert int(row["stage"]) == p["stage"][i]
        for key, val in (("t", p["ts"][i]), ("d", p["d"][i]), ("reaction", p["reaction"][i]),
                         ("axial_force_mid", h["F"][i]), ("turns_mid", h["turns"][i]), ("pitch", h["pitch"][i]),
                         ("N_mean", h["N_mean"][i]), ("N_minus_gravity", h["N_minus_gravity"][i]),
                         ("max_abs_theta", h["max_abs_theta"][i])):
            assert math.isclose(float(row[key]), float(val), rel_tol=1e-9, abs_tol=1e-12), key
    assert (out / "helix_post_buckling.png").stat().st_size > 0


def test_helix_measures_give_each_state_its_own_bottom_wall_force():
    """Two helices of different wall force in one batch: each state's `N_bottom` is its own
    largest wall force where the rod lies at the bottom, not the batch's."""
    rod = jr.RodChannel.reference(0.0)
    L, R, w = float(rod.L), float(rod.R), float(rod.w)
    n, beta = 102, 4 * math.pi
    s = np.linspace(0.0, L, n + 1)
    th = np.stack([beta * s, beta * s])
    x = np.stack([np.broadcast_to(s, th.shape), R * np.sin(th), -R * np.cos(th)], -1)
    N = np.array([[0.4], [0.9]]) + w * np.cos(th)
    h = helix_measures(rod, x, N, np.full((2, n), 5.0))
    np.testing.assert_allclose(h["N_bottom"], [0.4 + w, 0.9 + w], rtol=1e-12)
