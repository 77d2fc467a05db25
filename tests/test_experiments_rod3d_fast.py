"""The 3D rod's experiment drivers in the default suite: E1's displacement-controlled runs
(`experiments.rod3d.e1_curves`, one tiny compiled batch of 4 segments), and the bookkeeping of
E6's full-model check, the rolling check, the critical-velocity cross-check and E4/E5/E6C with the
3D rod (`experiments.paper3d` and `e4/e5/e6.rod3d`). Those drivers take minutes of compiled 3D
runs (their end-to-end checks are `slow`: tests/test_rod3d_cli.py, tests/test_reproduce.py), so
here their runs and searches are replaced by stand-ins whose answers the test fixes, and the test
checks what each driver reports and writes from them: the parameters it ran, the statistics it
draws from a run, the rows of its CSV."""

import csv
import datetime
import importlib
import math
import os
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import theory
from jaxrod._results import RESULTS
from jaxrod.experiments import paper3d as p3
from jaxrod.experiments import rod3d as exp3d
from jaxrod.integrators import default_step
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit
from jaxrod.rod3d.state import wall_angle

e4m = importlib.import_module("jaxrod.experiments.e4.rod3d")
e5m = importlib.import_module("jaxrod.experiments.e5.rod3d")
e6m = importlib.import_module("jaxrod.experiments.e6.rod3d")

# the reference rod by hand (RodChannel.reference: nitinol, L = 3 m, d = 1.5 mm, in R = 5.125 mm)
L, D, E, RHO, NU, R, G = 3.0, 1.5e-3, 77e9, 6450.0, 0.33, 5.125e-3, 9.81
EA = E * math.pi * D**2 / 4
EI = E * math.pi * D**4 / 64
GJ = E / (2 * (1 + NU)) * math.pi * D**4 / 32
W = RHO * G * math.pi * D**2 / 4


def _sines(n_interior, *amps):
    """Σ a_m sin(mπs/L) at the interior nodes s = j/(n_interior + 1), for (m, a_m) in `amps`."""
    s = np.arange(1, n_interior + 1) / (n_interior + 1)
    return sum(a * np.sin(m * np.pi * s) for m, a in amps)


def _read(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


# ---------------------------------------------------------------- experiments.rod3d: E1


def test_used_step_is_the_largest_step_that_lands_on_every_save():
    # save interval 1 ms: 1e-4 fits 10 times; 3e-4 does not fit, 4 steps of 0.25 ms do
    assert exp3d._used_step(0.01, 11, 1e-4) == pytest.approx(1e-4, rel=1e-12)
    assert exp3d._used_step(0.01, 11, 3e-4) == pytest.approx(2.5e-4, rel=1e-12)
    assert exp3d._used_step(0.01, 11, 5e-3) == pytest.approx(1e-3, rel=1e-12)  # never above the interval


def test_first_takes_member_zero_of_the_batched_positions():
    q = (jnp.arange(6.0).reshape(3, 2), jnp.arange(3.0) + 10)
    first = exp3d._first((q, "velocities are ignored"))
    np.testing.assert_array_equal(first[0], [0.0, 1.0])
    assert float(first[1]) == 10.0


@pytest.fixture(scope="module")
def e1_tiny():
    """E1 at 4 segments, μ = 0.3, pushed at 1 mm/s for 10 ms, sine amplitudes 10 and 30 mm/s (the
    explicit leapfrog at half its limit: its program compiles faster than the implicit one)."""
    v0s, speed, t1, n_save = (10e-3, 30e-3), 1e-3, 0.01, 11
    res = exp3d.e1_curves(0.3, v0s, n=4, speed=speed, t1=t1, n_save=n_save, dt_fraction=0.5, scheme="leapfrog")
    return res, dict(v0s=v0s, speed=speed, t1=t1, n_save=n_save)


def test_e1_pushes_the_end_at_the_speed_and_the_reaction_is_the_rods_axial_stiffness(e1_tiny):
    """The pushed end moves speed × t (displacement control) and, far below any buckling load,
    the reaction at it is the axial stiffness EA/L times the displacement (to the 15 % of the
    axial waves of 4 segments)."""
    res, c = e1_tiny
    ts = np.linspace(0.0, c["t1"], c["n_save"])
    np.testing.assert_allclose(res["ts"], ts, rtol=0, atol=1e-15)
    assert res["displacement"].shape == res["reaction"].shape == (2, c["n_save"])
    np.testing.assert_allclose(res["displacement"], np.broadcast_to(c["speed"] * ts, (2, c["n_save"])),
                               rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(res["reaction"][:, -1], EA / L * c["speed"] * c["t1"], rtol=0.15)
    assert np.all(res["reaction"][:, -1] > res["reaction"][:, 5]) and np.all(res["reaction"][:, 1:] > 0)
    assert res["n"] == 4


def test_e1_critical_force_is_the_largest_reaction_of_a_run_that_never_peaked(e1_tiny):
    """Below the frictionless load F⁰₆ (1.31 N) nothing breaks: the critical force is the largest
    reaction of the run, at its displacement; no run buckled or peaked."""
    res, _ = e1_tiny
    assert np.all(res["reaction"].max(1) < float(theory.reference_load(jr.RodChannel.reference(0.3))))
    np.testing.assert_array_equal(res["critical_force"], res["reaction"].max(1))
    i = res["reaction"].argmax(1)
    np.testing.assert_array_equal(res["d_critical"], res["displacement"][[0, 1], i])
    assert res["buckled"].tolist() == [False, False] and res["peaked"].tolist() == [False, False]


def test_e1_reports_the_step_it_took_and_runs_to_the_end(e1_tiny):
    """`dt` is at most half the explicit limit, puts each save on a step, and the runs (not
    buckled) took t1/dt steps; the energy balance is a small part of the initial kinetic energy
    (about ρA L v₀²/4)."""
    res, c = e1_tiny
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 4, control="displacement", speed=c["speed"])
    q0, _ = model.initial_state(0.0, lateral_velocity=sine_velocity(model, c["v0s"][0]))
    limit = float(step_limit(model, q0))
    per_save = c["t1"] / (c["n_save"] - 1) / res["dt"]
    assert res["dt"] <= 0.5 * limit and per_save == pytest.approx(round(per_save), abs=1e-9)
    assert res["dt"] > 0.5 * limit * per_save / (per_save + 1)  # the largest such step
    np.testing.assert_allclose(res["steps"] * res["dt"], c["t1"], rtol=1e-9)
    ke = RHO * math.pi * D**2 / 4 * L * np.asarray(c["v0s"]) ** 2 / 4
    assert np.all(res["balance"] >= 0) and np.all(res["balance"] < 0.1 * ke)


def test_e1_with_the_step_given_is_the_run_with_that_fraction_of_the_limit(e1_tiny):
    """`dt` given and `dt_fraction` × the limit at the initial state are one route: the same run."""
    res, c = e1_tiny
    model = Rod3D(jr.RodChannel.reference(0.3), 4, control="displacement", speed=c["speed"])
    q0, _ = model.initial_state(0.0, lateral_velocity=sine_velocity(model, c["v0s"][0]))
    again = exp3d.e1_curves(0.3, c["v0s"], n=4, speed=c["speed"], t1=c["t1"], n_save=c["n_save"],
                            dt=0.5 * step_limit(model, q0), scheme="leapfrog")
    assert again["dt"] == res["dt"]
    np.testing.assert_array_equal(again["reaction"], res["reaction"])


def test_e1_runs_stop_once_past_one_radian(monkeypatch):
    """E1's batch hands every member's run the 1 rad buckling threshold its docstring states (past
    the force peak) and the scheme asked for. (The run is a stand-in that records what it was
    handed and stops.)"""
    seen = {}

    def stand_in(model, q, v, t1, n_save, dt, **kw):
        seen.update(kw)
        raise RuntimeError("recorded")

    monkeypatch.setattr(exp3d, "run", stand_in)
    with pytest.raises(RuntimeError, match="recorded"):
        exp3d.e1_curves(0.3, (10e-3, 30e-3), n=4, t1=0.01, n_save=11, dt=1e-4, scheme="verlet")
    assert seen["threshold"] == 1.0 and seen["scheme"] == "verlet" and seen["stop_on_buckle"]


# ---------------------------------------------------------------- experiments.rod3d: E6 full model


def _fake_e6_solution(n, rod):
    """A run's record whose statistics are fixed by construction (201 saves over 0.1 s)."""
    ts = np.linspace(0.0, 0.1, 201)
    F0cr = float(theory.critical_load_continuous(rod))
    twist = 1e-4 * (1 + ts / 0.1)  # largest share 2e-4, at the end
    shear = np.full_like(ts, 3e-3)
    shear[50] = 5e-3
    bend = 0.01 * ts / 0.1
    energies = dict(bend=bend, twist=twist, shear=shear, kinetic=1.0 - bend - twist - shear)  # total 1
    amp = 0.15 * ts / 0.1  # passes 0.1 rad first at save 134
    i_b = 134
    Nn = np.ones((201, n + 1))
    Nn[10, 3], Nn[20, 4] = 0.8, 1.3  # interior, before buckling
    Nn[0], Nn[150], Nn[:, 0], Nn[:, -1] = 5.0, 7.0, 9.0, 0.1  # outside: not counted
    Fx = np.full((201, n), 6.0)
    Fx[30, 2], Fx[30, 5] = 6.0 + 0.25 * F0cr, 6.0 - 0.25 * F0cr  # range 0.5 F⁰cr, mean unchanged
    Fx[0, 0], Fx[150, 0] = 20.0, 30.0
    theta = np.zeros((201, n + 1))
    theta[:, 0] = theta[:, -1] = 0.3  # the end nodes: not counted
    theta[1, 1:-1] = _sines(n - 1, (3, 0.01), (5, 0.001))
    theta[i_b + 10, 1:-1] = _sines(n - 1, (5, 0.02), (2, 0.01))
    gap = np.full(201, -1e-3 * float(rod.R))
    gap[180] = 0.5 * float(rod.R)
    balance = np.zeros(201)
    balance[70] = -3e-7
    return SimpleNamespace(ts=ts, energies=energies, amplitude=amp, energy_balance=balance,
                           dissipated=np.linspace(0.0, 2e-5, 201),
                           observables=dict(normal_force=Nn * float(rod.w), axial_force=Fx, theta=theta, gap=gap))


def test_e6_full_reports_the_statistics_of_its_run_before_and_after_buckling(tmp_path, monkeypatch, capsys):
    """E6 in the full model runs μ = 0.3, ΔF = 5 N, 35 mm/s with held ends for 0.1 s (201 saves,
    the default step, not stopped), and reports from that run: the largest twist and shear
    shares, N/w and the axial force range before the amplitude passes 0.1 rad (interior nodes),
    the largest lift-off, the dominant modes before and after; its CSV has one row per save."""
    n = 8
    monkeypatch.setitem(exp3d.SIZES, "tiny", dict(exp3d.SIZES["tiny"], n=n))
    rod = jr.RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    calls = []

    def fake_run(model, q0, v0, t1, n_save, dt, **kw):
        calls.append(dict(n=model.n, control=model.control, mu=float(model.rod.mu_s), t1=t1, n_save=n_save, **kw,
                          dt_is_default=dt == default_step(model, q0),
                          length=float(q0.x[-1, 0] - q0.x[0, 0]), v_max=float(jnp.max(jnp.abs(v0.v)))))
        return _fake_e6_solution(model.n, rod)

    monkeypatch.setattr(exp3d, "run", fake_run)
    res = exp3d.e6_full(str(tmp_path), quick="tiny", progress=True)
    assert capsys.readouterr().out == f"  E6 (full model): {n} segments, 0.1 s\n"
    (c,) = calls
    assert c["length"] == pytest.approx(L * (1 - F / EA), rel=1e-12)  # pre-compressed to F⁰₆ + 5 N
    assert c["v_max"] == pytest.approx(35e-3, rel=1e-9)  # sine mode 6: node 2 of 8 at its crest
    assert {k: c[k] for k in ("n", "control", "mu", "t1", "n_save", "stop_on_buckle", "stop_when_stuck",
                              "dt_is_default")} == dict(n=n, control="force", mu=0.3, t1=0.1, n_save=201,
                                                        stop_on_buckle=False, stop_when_stuck=False, dt_is_default=True)
    assert res["model"] == "rod3d" and res["n_segments"] == n and "ΔF = 5 N" in res["case"]
    assert res["t_amplitude_0.1rad"] == pytest.approx(0.067, rel=1e-12)
    assert res["twist_over_total_max"] == pytest.approx(2e-4, rel=1e-9)
    assert res["shear_over_total_max"] == pytest.approx(5e-3, rel=1e-9)
    assert res["normal_force_over_w_before"] == pytest.approx([0.8, 1.3], rel=1e-12)
    assert res["axial_force_variation_before_over_F0cr"] == pytest.approx(0.5, rel=1e-9)
    assert res["axial_force_mean_before"] == pytest.approx(6.0, rel=1e-12)
    assert res["max_lift_off_gap_over_R"] == pytest.approx(0.5, rel=1e-12)
    assert res["max_theta"] == pytest.approx(0.15, rel=1e-12)
    assert (res["dominant_mode_before"], res["dominant_mode_after"]) == (3, 5)
    assert res["dominant_power_after"] == pytest.approx(0.8, rel=1e-9)  # 0.02² / (0.02² + 0.01²)
    assert res["energy_balance_max_J"] == pytest.approx(3e-7, rel=1e-12)
    assert res["dissipated_J"] == pytest.approx(2e-5, rel=1e-12)
    rows = _read(tmp_path / "e6_full_model.csv")
    assert list(rows[0]) == ["t", "bend", "twist", "shear", "kinetic", "gap", "amplitude"] and len(rows) == 201
    assert float(rows[134]["t"]) == pytest.approx(0.067) and float(rows[134]["amplitude"]) == pytest.approx(0.1005)
    assert float(rows[180]["gap"]) == pytest.approx(0.5 * R) and float(rows[50]["shear"]) == pytest.approx(5e-3)
    assert (tmp_path / "e6_full_model.png").stat().st_size > 0


def test_e6_full_without_buckling_counts_every_save_as_before(tmp_path, monkeypatch):
    """A run whose amplitude never reaches 0.1 rad has no buckling time, and every save after the
    first counts as "before buckling"."""
    monkeypatch.setitem(exp3d.SIZES, "tiny", dict(exp3d.SIZES["tiny"], n=8))
    rod = jr.RodChannel.reference(0.3)

    def fake_run(model, q0, v0, t1, n_save, dt, **kw):
        sol = _fake_e6_solution(model.n, rod)
        sol.amplitude = np.full(201, 0.05)
        sol.observables["normal_force"][150, 2] = 0.4 * float(rod.w)  # now before buckling
        return sol

    monkeypatch.setattr(exp3d, "run", fake_run)
    res = exp3d.e6_full(str(tmp_path), quick="tiny", progress=False)
    assert res["t_amplitude_0.1rad"] is None and res["max_theta"] == pytest.approx(0.05)
    assert res["normal_force_over_w_before"] == pytest.approx([0.4, 7.0])  # save 150 counts now


# ---------------------------------------------------------------- experiments.rod3d: rolling check


def test_rolling_check_reports_the_margin_by_hand_and_each_runs_creep(monkeypatch):
    """The margin is |EI k⁴ − F k² + w/R|·A·R/(μw) at F = F⁰₆ + ΔF (below 1: a stuck rod in the
    field model), the elastic roll r²f̂L/(2GJkR); each case (friction at the surface or the
    axis, each number of sweeps) is a load-controlled run from the offset R·A·sin(mπs/L) at
    rest, and its record gives the interior creep, whether all is stuck and the residual."""
    n, mode, A, dF = 8, 12, 1e-3, 20.0
    rod = jr.RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + dF
    s = np.arange(n + 1) / n
    ran = []

    def fake_run(model, q0, v0, t1, n_save, dt, **kw):
        where, sw = model.friction_at, model.friction_sweeps
        ran.append((where, sw))
        assert model.control == "load" and float(model.end_load) == pytest.approx(F, rel=1e-12) and model.n == n
        assert (t1, n_save, kw) == (0.01, 3, dict(stop_on_buckle=False, stop_when_stuck=False))
        assert dt == default_step(model, q0) and float(jnp.max(jnp.abs(v0.v))) == 0.0
        theta0 = np.asarray(wall_angle(q0.x))
        np.testing.assert_allclose(theta0, A * np.sin(mode * np.pi * s), rtol=0, atol=1e-12)
        delta = np.ones(n + 1)  # the end nodes: not counted
        delta[1:-1] = sw * (1e-4 * (np.arange(n - 1) - 1.0) if where == "surface" else np.full(n - 1, -3e-4))
        stuck = np.zeros(n + 1, bool)
        stuck[1:-1] = True
        if where == "axis":
            stuck[3] = False
        return SimpleNamespace(observables=dict(theta=np.stack([theta0, theta0, theta0 + delta]),
                                                friction_residual=sw * np.array([0.1, 0.3, 0.2])),
                               v_final=SimpleNamespace(stuck=stuck))

    monkeypatch.setattr(exp3d, "run", fake_run)
    res = exp3d.rolling_check(dF=dF, n=n, mu=0.3, mode=mode, amplitude=A, t1=0.01, sweeps=(1, 3))
    assert ran == [("surface", 1), ("surface", 3), ("axis", 1), ("axis", 3)]
    k = mode * math.pi / L
    margin = abs(EI * k**4 - F * k**2 + W / R) * A * R / (0.3 * W)
    assert res["margin_net_force_over_mu_N"] == pytest.approx(margin, rel=1e-6) and 0.3 < margin < 1
    assert res["elastic_roll"] == pytest.approx((D / 2) ** 2 * margin * 0.3 * W * L / (2 * GJ * k * R), rel=1e-6)
    assert {key: res[key] for key in ("dF", "n_segments", "mu", "mode", "amplitude_rad", "t1")} == dict(
        dF=dF, n_segments=n, mu=0.3, mode=mode, amplitude_rad=A, t1=0.01)
    for sw in (1, 3):
        # surface: interior creep (−1 … 5) × 1e-4 × sweeps; axis: −3e-4 × sweeps everywhere
        for where, creep, mean, all_stuck in (("surface", 5e-4, 2e-4, True), ("axis", 3e-4, -3e-4, False)):
            got = res[f"{where}, {sw} sweeps"]
            assert set(got) == {"max_dtheta", "mean_dtheta", "all_stuck", "friction_residual"}
            assert got["max_dtheta"] == pytest.approx(creep * sw, rel=1e-9)
            assert got["mean_dtheta"] == pytest.approx(mean * sw, rel=1e-9)
            assert got["all_stuck"] is all_stuck
            assert got["friction_residual"] == pytest.approx(0.3 * sw, rel=1e-9)


# ---------------------------------------------------------------- experiments.rod3d: cross-check


def _crosscheck(monkeypatch, label, v_field=0.02, failed_at=None, **kw):
    """`crosscheck_critical_velocity` at ΔF = 5 N with the field model's v₀* `v_field` and each
    3D run labelled buckled by `label(v0)` (v₀ read back from the batch's initial velocities)."""
    seen = dict(batches=[], field=[])

    def fake_field(rod, dF, **kwargs):
        seen["field"].append((float(rod.mu_s), dF, kwargs))
        return SimpleNamespace(root=jnp.asarray(v_field)), None

    def fake_batched(model, states, t1, n_save, dt, threshold, stop_on_buckle, stop_when_stuck):
        v0s = np.asarray(jnp.max(jnp.abs(states[1].v), axis=(1, 2)))
        seen["batches"].append(dict(v0s=v0s, model=model, t1=t1, n_save=n_save, threshold=threshold,
                                    stops=(stop_on_buckle, stop_when_stuck),
                                    dt_is_default=dt == default_step(model, exp3d._first(states))))
        result = np.zeros(len(v0s), np.int32)
        if failed_at is not None:
            result[failed_at] = RESULTS.nonfinite
        return SimpleNamespace(buckled=np.array([label(v) for v in v0s]), result=result)

    monkeypatch.setattr(jr.boundary, "critical_velocity", fake_field)
    monkeypatch.setattr(exp3d, "_batched", fake_batched)
    out = exp3d.crosscheck_critical_velocity([5.0], n=4, mu=0.3, t1=0.05, grid=5, rounds=2, **kw)
    return out, seen


def test_crosscheck_brackets_the_3d_boundary_by_zooming_grids(monkeypatch, capsys):
    """Five amplitudes from 0.4 to 2.5 × the field model's v₀*, then five inside the bracket they
    found: the bracket [largest stable, next] holds the 3D boundary and is 6.25^(1/16) wide; its
    ends were run once each (8 runs); the runs are load-controlled at F⁰₆ + ΔF, labelled at
    0.5 rad, stopped when buckled or stuck."""
    v_star = 0.026
    (r,), seen = _crosscheck(monkeypatch, lambda v: v > v_star, progress=True, friction_at="axis")
    lo, hi = r["rod3d_bracket"]
    assert lo < v_star < hi and hi / lo == pytest.approx(6.25 ** (1 / 16), rel=1e-9)
    assert r["rod3d"] == pytest.approx(math.sqrt(lo * hi), rel=1e-12)
    assert r["field"] == pytest.approx(0.02, rel=1e-12) and r["dF"] == 5.0
    assert r["monotonic"] and not r["every_tested_amplitude_buckled"] and r["rod3d_runs"] == 8
    assert r["smallest_buckled"] == pytest.approx(hi, rel=1e-12)
    assert r["smallest_tested"] == pytest.approx(0.4 * 0.02, rel=1e-12)
    assert (r["n_segments"], r["friction_at"], r["ends"]) == (4, "axis", "pinned")
    assert seen["field"] == [(0.3, 5.0, dict(model="field", rtol=1e-4, sensitivities=()))]
    first, second = seen["batches"]
    np.testing.assert_allclose(first["v0s"], np.geomspace(0.008, 0.05, 5), rtol=1e-9)
    np.testing.assert_allclose(second["v0s"], np.geomspace(0.02, 0.02 * 6.25**0.25, 5), rtol=1e-9)
    F = float(theory.reference_load(jr.RodChannel.reference(0.3))) + 5.0
    for b in (first, second):
        m = b["model"]
        assert (m.control, m.friction_at, m.ends, m.n) == ("load", "axis", "pinned", 4)
        assert float(m.end_load) == pytest.approx(F, rel=1e-12)
        assert (b["t1"], b["n_save"], b["threshold"], b["stops"], b["dt_is_default"]) == (0.05, 11, 0.5, (True, True), True)
    printed = capsys.readouterr().out.splitlines()
    assert printed == ["  cross-check ΔF = 5.0 N (axis), round 0: buckled [0, 0, 0, 1, 1]",
                       "  cross-check ΔF = 5.0 N (axis), round 1: buckled [0, 0, 0, 1, 1]"]


@pytest.mark.parametrize("v_star, lo, hi", [(0.003, 0.008 / 3, 0.008 / 3 * 3**0.25),  # all buckled: go down
                                            (0.06, 0.05, 0.05 * 3**0.25)])  # none buckled: go up
def test_crosscheck_moves_its_grid_past_a_boundary_outside_it(monkeypatch, v_star, lo, hi):
    """A first grid that buckled everywhere moves a factor 3 down (below its lowest amplitude); one
    that buckled nowhere moves a factor 3 up; the second grid then brackets the boundary."""
    (r,), _ = _crosscheck(monkeypatch, lambda v: v > v_star, progress=False)
    assert r["rod3d_bracket"] == pytest.approx([lo, hi], rel=1e-9) and r["monotonic"]
    assert r["smallest_tested"] == pytest.approx(min(lo, 0.008), rel=1e-9)


def test_crosscheck_without_a_bracket_reports_none_and_the_smallest_buckled(monkeypatch):
    """Every amplitude buckled in both rounds: no 3D value, every tested amplitude buckled, the
    smallest buckled is the smallest tested (0.4/3 × the field value)."""
    (r,), _ = _crosscheck(monkeypatch, lambda v: True, progress=False)
    assert r["rod3d"] is None and r["rod3d_bracket"] is None and r["every_tested_amplitude_buckled"]
    assert r["smallest_buckled"] == r["smallest_tested"] == pytest.approx(0.008 / 3, rel=1e-9)
    assert r["rod3d_runs"] == 9  # the second grid's top is the first grid's bottom


def test_crosscheck_reports_outcomes_that_are_not_monotonic(monkeypatch):
    """A buckled amplitude below a stable one: not monotonic; the smallest buckled is that one; the
    bracket is still [largest stable, next]."""
    odd = 0.008 * 6.25**0.25
    (r,), _ = _crosscheck(monkeypatch, lambda v: v > 0.026 or abs(v - odd) < 1e-9, progress=False)
    assert not r["monotonic"] and r["smallest_buckled"] == pytest.approx(odd, rel=1e-9)
    lo, hi = r["rod3d_bracket"]
    assert lo < 0.026 < hi


def test_crosscheck_with_a_stable_top_amplitude_does_not_bracket(monkeypatch):
    """Only the lowest amplitude buckled: the largest stable one is the grid's top, so there is no
    bracket to zoom into; the same grid is run again (5 runs), and the outcome is not monotonic."""
    (r,), seen = _crosscheck(monkeypatch, lambda v: v < 0.009, progress=False)
    assert r["rod3d"] is None and r["rod3d_bracket"] is None and not r["monotonic"]
    assert r["smallest_buckled"] == pytest.approx(0.008, rel=1e-9) and r["rod3d_runs"] == 5
    np.testing.assert_array_equal(seen["batches"][0]["v0s"], seen["batches"][1]["v0s"])


def test_crosscheck_stops_on_a_failed_run_naming_its_amplitude(monkeypatch):
    with pytest.raises(RuntimeError, match=r"cross-check ΔF = 5.0 N: the 3D runs at v0 = \[0.02\d*\] m/s failed "
                                           r"\(the state became non-finite"):
        _crosscheck(monkeypatch, lambda v: False, failed_at=2, progress=False)


# ---------------------------------------------------------------- paper3d helpers


def test_settings_are_a_copy_of_the_size_with_n_replaced():
    s = p3._settings("tiny", None)
    assert s == p3.SIZES["tiny"] and s is not p3.SIZES["tiny"]
    s["n"] = 99
    assert p3.SIZES["tiny"]["n"] == 8
    big = p3._settings(True, 12.0)
    assert big["n"] == 12 and type(big["n"]) is int and big["mus"] == p3.SIZES[True]["mus"]


def test_points_are_appended_to_the_csv_and_found_again_by_their_key(tmp_path):
    """A row added is written under the columns' header (missing columns empty) with the commit
    and the date; a new reader of the file finds it by its key, given as numbers or strings."""
    path = str(tmp_path / "points.csv")
    cols = ["case", "mu", "n", "value", "commit", "date"]
    pts = p3._Points(path, cols, lambda r: (r["case"], r["mu"], r["n"]))
    assert pts.rows == [] and pts.find("A", 0.3, 8) == []
    pts.add(dict(case="A", mu=0.3, n=8, value=1.5, ignored="x"))
    pts.add(dict(case="B", mu=0.3, n=8))
    with open(path) as fh:
        lines = fh.read().splitlines()
    assert lines[0] == "case,mu,n,value,commit,date" and len(lines) == 3
    again = p3._Points(path, cols, lambda r: (r["case"], r["mu"], r["n"]))
    assert again.rows == pts.rows
    (a,) = again.find("A", 0.3, 8)
    assert (a["value"], a["date"], a["commit"]) == ("1.5", datetime.date.today().isoformat(), p3._commit())
    assert again.find("B", "0.3", "8")[0]["value"] == "" and again.find("A", 0.3, 9) == []
    assert a["commit"] == "" or all(ch in "0123456789abcdef" for ch in a["commit"])


def test_best_prefers_converged_then_the_longest_horizon_then_the_widest_bracket():
    rows = [dict(result="2", t1="5.0", width="9"), dict(result="0", t1="0.5", width="4"),
            dict(result="0", t1="2.0", width=""), dict(result="0", t1="2.0", width="1.5")]
    assert p3._best(rows) is rows[3]
    assert p3._best(rows[:3]) is rows[2]
    assert p3._best(rows[:2]) is rows[1]
    assert p3._best(rows[:1]) is rows[0] and p3._best([]) is None
    narrow = dict(result="0", t1="2.0", width="0.5")  # any bracket is wider than none
    assert p3._best([rows[2], narrow]) is narrow and p3._best([narrow, rows[2]]) is narrow


def test_the_commit_recorded_is_the_checkouts_short_hash():
    """A point's `commit` column: `git rev-parse --short HEAD` of the checkout the package is in."""
    import subprocess

    here = os.path.dirname(os.path.abspath(p3.__file__))
    git = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=here)
    assert git.returncode == 0 and git.stdout.strip()  # the tests run in a checkout
    assert p3._commit() == git.stdout.strip()


def test_found_takes_the_best_row_of_a_point_on_at_least_the_horizon(tmp_path):
    pts = p3._e4_points(str(tmp_path / "e4.csv"))
    for t1, f, real in ((0.5, 9.0, 0), (2.0, 9.1, 0), (0.01, 8.0, 0), (5.0, 7.0, 1)):
        pts.add(dict(case="A", mu=0.3, realization=real, n=8, t1=t1, width=1.5, dF_star=f, result=0))
    assert p3._found(pts, 0.5, "A", 0.3, 0, 8)["dF_star"] == "9.1"
    assert p3._found(pts, 2.0, "A", 0.3, 0, 8)["dF_star"] == "9.1"  # a horizon equal to the setting's counts
    assert p3._found(pts, 3.0, "A", 0.3, 0, 8) is None
    assert p3._found(pts, 3.0, "A", 0.3, 1, 8)["dF_star"] == "7.0"
    assert p3._found(pts, 0.0, "B", 0.3, 0, 8) is None
    assert list(pts.rows[0]) == p3.E4_COLUMNS


def test_modes_give_the_two_largest_sine_modes_and_their_power_shares():
    theta = _sines(39, (7, 0.03), (2, -0.04), (11, 0.001))
    m, share, m2, share2 = p3._modes(theta)
    total = 0.03**2 + 0.04**2 + 0.001**2
    assert (m, m2) == (2, 7)
    assert share == pytest.approx(0.04**2 / total, rel=1e-9) and share2 == pytest.approx(0.03**2 / total, rel=1e-9)
    m, share, _, share2 = p3._modes(theta, 6)  # within the first six modes only mode 2 has power
    assert m == 2 and share == pytest.approx(1.0, rel=1e-9) and share2 < 1e-20


def test_theta_at_the_stop_is_the_3d_rods_interior_angle_or_the_field_models_state():
    ts = np.linspace(0.0, 1.0, 5)
    theta = np.arange(25.0).reshape(5, 5)
    sol = SimpleNamespace(observables=dict(theta=theta), ts=ts, t_stop=0.5)
    th, i = p3._theta_3d(sol)
    np.testing.assert_array_equal(th, theta[:, 1:-1])
    assert i == 2
    np.testing.assert_array_equal(p3._final_theta(sol), [11.0, 12.0, 13.0])
    sol.t_stop = 7.0  # past the last save: the last
    assert p3._theta_3d(sol)[1] == 4
    sol.t_stop = 0.6  # between saves: the next one
    assert p3._theta_3d(sol)[1] == 3
    field = SimpleNamespace(observables=None, q_final=jnp.array([0.1, 0.2]))
    np.testing.assert_array_equal(p3._final_theta(field), [0.1, 0.2])
    assert p3._final_theta(SimpleNamespace(observables={}, q_final=[3.0]))[0] == 3.0


def test_critical_load_passes_the_search_settings_and_times_it(monkeypatch):
    seen = []

    def fake(rod, amplitude, **kw):
        seen.append((float(rod.mu_s), amplitude, kw))
        return jnp.asarray(4.5), None

    monkeypatch.setattr(jr.boundary, "critical_load", fake)
    key = jax.random.key(3)
    r, sec = p3._critical_load(jr.RodChannel.reference(0.5), 2.0, "random-position", key, "rod3d", 8, 0.05,
                               (1.0, 9.0), 0.1, "bisection")
    assert float(r) == 4.5 and 0 <= sec < 5
    ((mu, amp, kw),) = seen
    assert (mu, amp) == (0.5, 2.0) and kw.pop("key") is key
    assert kw == dict(model="rod3d", perturbation="random-position", t1=0.05, bracket=(1.0, 9.0), rtol=0.1, n=8,
                      method="bisection", sensitivities=())


# ---------------------------------------------------------------- E4 with the 3D rod


def _root(root, lo=float("nan"), hi=float("nan"), evaluations=0, result=0):
    return SimpleNamespace(root=root, lo=lo, hi=hi, evaluations=evaluations, result=result)


def _same_key(a, b):
    return bool(np.array_equal(jax.random.key_data(a), jax.random.key_data(b)))


@pytest.mark.parametrize("case, realization", [("B", 1), ("C", 0)])
def test_e4_point_searches_the_field_model_then_the_3d_rod_around_it(monkeypatch, case, realization):
    """One E4 point: the field model's ΔF* to 1e-4 on (0.01, its top), then the 3D rod's by bisection
    to `rtol` on the field value ÷/× `width`, for the case's perturbation and realization's key;
    the row records both, the 3D bracket, runs, result and the time of both searches."""
    calls = []

    def fake(rod, amplitude, kind, key, model, n, t1, bracket, rtol, method=None):
        calls.append(dict(mu=float(rod.mu_s), amplitude=amplitude, kind=kind, key=key, model=model, n=n, t1=t1,
                          bracket=bracket, rtol=rtol, method=method))
        if model == "field":
            return _root(10.0), 1.2
        return _root(11.0, 10.5, 11.5, 7, 0), 2.0

    monkeypatch.setattr(e4m, "_critical_load", fake)
    row = e4m.e4_point(case, 0.5, realization, 8, t1=0.05, width=2.0, rtol=0.1)
    kind, amplitude = p3.E4_CASES[case]
    field, rod3d = calls
    for c in calls:
        assert (c["mu"], c["amplitude"], c["kind"], c["t1"]) == (0.5, amplitude, kind, 0.05)
        assert _same_key(c["key"], jax.random.fold_in(jax.random.key(0), realization))
    assert (field["model"], field["n"], field["bracket"], field["rtol"], field["method"]) == (
        "field", p3.FIELD_NODES[case], (0.01, p3.FIELD_TOP[case]), 1e-4, None)
    assert (rod3d["model"], rod3d["n"], rod3d["bracket"], rod3d["rtol"], rod3d["method"]) == (
        "rod3d", 8, (5.0, 20.0), 0.1, "bisection")
    assert row == dict(case=case, mu=0.5, realization=realization, n=8, t1=0.05, width=2.0, dF_star_field=10.0,
                       dF_star=11.0, lo=10.5, hi=11.5, runs=7, result=0, wall_s=3.2)


def test_e4_runs_each_missing_point_and_widens_a_bracket_that_missed(tmp_path, monkeypatch, capsys):
    """From an empty CSV (tiny: n = 8, μ = 0.3, one realization), E4 runs A, B and C once each;
    C's 3D ΔF* fell outside its bracket, so C is run again with the width squared, up to 1.5⁴;
    every run is a CSV row; the summary holds the converged points. Run again, nothing runs."""
    widths = []

    def fake_point(case, mu, realization, n, t1, width, rtol):
        widths.append((case, width))
        assert (mu, realization, n, t1, rtol) == (0.3, 0, 8, 0.05, 0.1)
        result = 2 if case == "C" else 0
        return dict(case=case, mu=float(mu), realization=realization, n=n, t1=t1, width=width,
                    dF_star_field=dict(A=9.0, B=12.0, C=7.0)[case], dF_star=dict(A=9.5, B=11.0, C=math.nan)[case],
                    lo=1.0, hi=2.0, runs=5, result=result, wall_s=3.0)

    monkeypatch.setattr(e4m, "e4_point", fake_point)
    res = e4m.e4(str(tmp_path / "e4"), quick="tiny", progress=True)
    assert widths == [("A", 1.5), ("B", 1.5), ("C", 1.5), ("C", 1.5**2), ("C", 1.5**4)]
    assert res == dict(n=8, width=1.5, points={"A mu=0.3": dict(rod3d=[9.5], field=[9.0]),
                                               "B mu=0.3": dict(rod3d=[11.0], field=[12.0])})
    rows = _read(tmp_path / "e4" / "rod3d_n8.csv")
    assert [(r["case"], float(r["width"]), r["result"]) for r in rows] == [
        ("A", 1.5, "0"), ("B", 1.5, "0"), ("C", 1.5, "2"), ("C", 2.25, "2"), ("C", 5.0625, "2")]
    assert all(r["date"] == datetime.date.today().isoformat() for r in rows)
    assert (tmp_path / "e4" / "rod3d_n8.png").stat().st_size > 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == "  E4 A, mu = 0.3, realization 0: 3D dF* = 9.5 N (5 runs, 3 s), field 9 N"
    assert len(printed) == 3
    widths.clear()
    assert e4m.e4(str(tmp_path / "e4"), quick="tiny", progress=False) == res and widths == []


# ---------------------------------------------------------------- E6C with the 3D rod


class _FakeScene:
    """Stands in for `jaxrod.scene.Scene`: records each scene; `run` returns `record(scene)`,
    `step` returns 1e-5 × (1 + dF/100)."""

    made = []
    record = None

    def __init__(self, rod, dF, perturbation, kind, n=None, mode=6, dt=None):
        self.rod, self.dF, self.perturbation, self.kind, self.n, self.mode, self.dt = (
            rod, dF, perturbation, kind, n, mode, dt)
        _FakeScene.made.append(self)

    def step(self):
        return 1e-5 * (1 + self.dF / 100)

    def run(self, t1, n_save):
        self.t1, self.n_save = t1, n_save
        return _FakeScene.record(self)


@pytest.fixture
def fake_scene(monkeypatch):
    import jaxrod.scene

    _FakeScene.made = []
    monkeypatch.setattr(jaxrod.scene, "Scene", _FakeScene)
    return _FakeScene


def _record_3d(n, before, at, t_stop=0.03, buckled=1):
    """A 3D run's record: θ of `before` modes at the first save and of `at` modes from `t_stop` on."""
    ts = np.linspace(0.0, 0.05, 11)
    theta = np.full((11, n + 1), 0.7)  # the end nodes: not counted
    theta[:, 1:-1] = _sines(n - 1, *at)
    theta[0, 1:-1] = _sines(n - 1, *before)
    return SimpleNamespace(observables=dict(theta=theta), ts=ts, t_stop=t_stop, buckled=buckled)


def test_e6c_searches_dF_star_then_runs_at_105_percent_and_at_40_N(tmp_path, monkeypatch, fake_scene):
    """E6C (μ = 0.9, random position 2 N/m, key 6): the field model's ΔF* on (1e-3, 300 N), the 3D
    rod's by bisection on it ÷/× 4; then a 3D run at 1.05 ΔF* and at 40 N, each a CSV row with the
    search, the dominant modes before and at the stop and their shares. Run again, it reads the
    CSV and searches nothing. (48 segments: 47 interior nodes resolve the 40 modes it reads.)"""
    calls = []

    def fake_search(rod, amplitude, kind, key, model, n, t1, bracket, rtol, method=None):
        calls.append((float(rod.mu_s), amplitude, kind, model, n, t1, bracket, rtol, method))
        assert _same_key(key, jax.random.key(6))
        return (_root(5.0), 0.5) if model == "field" else (_root(6.0, 5.8, 6.2, 9, 0), 4.0)

    monkeypatch.setattr(e6m, "_critical_load", fake_search)
    fake_scene.record = lambda sc: _record_3d(sc.n, [(2, 0.01)], [(4, 0.03), (6, 0.01)])
    res = e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48)
    assert calls == [(0.9, 2.0, "random-position", "field", None, 0.05, (1e-3, 300.0), 1e-4, None),
                     (0.9, 2.0, "random-position", "rod3d", 48, 0.05, (1.25, 20.0), 0.1, "bisection")]
    assert [(s.dF, s.kind, s.n, s.t1, s.n_save, float(s.rod.mu_s)) for s in fake_scene.made] == [
        (pytest.approx(6.3), "rod3d", 48, 0.05, 501, 0.9), (40.0, "rod3d", 48, 0.05, 501, 0.9)]
    assert all(type(s.perturbation).__name__ == "RandomForce" for s in fake_scene.made)
    share = 0.03**2 / (0.03**2 + 0.01**2)
    expected = dict(dF_star=6.0, dF_star_field=5.0, mode=4, share=pytest.approx(share), next_mode=6,
                    next_share=pytest.approx(1 - share))
    assert res == {"1.05 dF*": dict(dF=pytest.approx(6.3), **expected), "paper's 40 N": dict(dF=40.0, **expected),
                   "n": 48}
    rows = _read(tmp_path / "rod3d_random_position_n48.csv")
    assert list(rows[0]) == p3.E6_COLUMNS and [r["case"] for r in rows] == ["1.05 dF*", "paper's 40 N"]
    assert [(r["mode_before"], r["buckled"], r["t_stop"], r["search_runs"], r["dF_star_lo"], r["dF_star_hi"],
             r["search_result"]) for r in rows] == [("2", "1", "0.03", "9", "5.8", "6.2", "0")] * 2
    assert float(rows[0]["wall_s"]) >= 4.0 > float(rows[1]["wall_s"])  # the search's time once, on the first row
    monkeypatch.setattr(e6m, "_critical_load", None)  # not called again
    assert e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48) == res and len(fake_scene.made) == 2


def test_e6c_interrupted_after_its_first_case_runs_only_the_other(tmp_path, monkeypatch, fake_scene):
    """A CSV that holds the 1.05 ΔF* row but not the 40 N one (a run stopped between them): E6C
    searches again (ΔF* is not in the file for the missing case) and runs the 40 N case alone."""
    monkeypatch.setattr(e6m, "_critical_load", lambda rod, a, kind, key, model, *rest: (
        (_root(5.0), 0.5) if model == "field" else (_root(6.0, 5.8, 6.2, 9, 0), 4.0)))
    fake_scene.record = lambda sc: _record_3d(sc.n, [(2, 0.01)], [(4, 0.03), (6, 0.01)])
    first = e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48)
    path = tmp_path / "rod3d_random_position_n48.csv"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:2]) + "\n")  # the header and the 1.05 ΔF* row
    fake_scene.made = []
    again = e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48)
    assert [s.dF for s in fake_scene.made] == [40.0]
    assert again == first and [r["case"] for r in _read(path)] == ["1.05 dF*", "paper's 40 N"]


def test_e6c_records_a_failed_search_without_its_run_and_still_runs_40_N(tmp_path, monkeypatch, fake_scene):
    """A 3D search that failed (ΔF* not finite) is recorded on the 1.05 ΔF* row without a run, so
    that it is not searched again; the run at the paper's 40 N does not need ΔF* and is made."""
    monkeypatch.setattr(e6m, "_critical_load", lambda rod, a, kind, key, model, *rest: (
        (_root(5.0), 0.5) if model == "field" else (_root(math.nan, 1.25, 20.0, 4, 2), 3.0)))
    fake_scene.record = lambda sc: _record_3d(sc.n, [(2, 0.01)], [(4, 0.03), (6, 0.01)])
    res = e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48)
    assert [s.dF for s in fake_scene.made] == [40.0]
    assert set(res) == {"paper's 40 N", "n"} and math.isnan(res["paper's 40 N"]["dF_star"])
    assert res["paper's 40 N"]["mode"] == 4
    rows = _read(tmp_path / "rod3d_random_position_n48.csv")
    assert [(r["case"], r["dF"], r["search_result"], r["buckled"], r["wall_s"]) for r in rows] == [
        ("1.05 dF*", "nan", "2", "", "3.0"), ("paper's 40 N", "40.0", "2", "1", rows[1]["wall_s"])]
    assert float(rows[1]["wall_s"]) < 3.0  # the search's time is on the first row only
    # the failed search's row keeps what it found: its bracket, runs and the field's ΔF*
    assert [rows[0][k] for k in ("dF_star_lo", "dF_star_hi", "search_runs", "dF_star_field")] == ["1.25", "20.0", "4",
                                                                                                   "5.0"]
    monkeypatch.setattr(e6m, "_critical_load", None)  # not searched again
    again = e6m.e6c(str(tmp_path), quick="tiny", progress=False, n=48)
    assert set(again) == {"paper's 40 N", "n"} and len(fake_scene.made) == 1


# ---------------------------------------------------------------- E5 with the 3D rod


def test_e5_runs_each_model_at_105_percent_of_its_own_dF_star_on_e4s_points(tmp_path, monkeypatch, fake_scene,
                                                                             capsys):
    """E5 (tiny) on E4's CSV: the converged random-velocity point is run with the 3D rod at 1.05 ×
    its ΔF* (step of its search's top, field value × width) and with the field model at 1.05 × its
    own (step at its top, 100 N, on 499 nodes); the random-position point whose search failed is
    not run. The row records each model's dominant modes at the stop; the summary lists the
    buckled ones by μ."""
    e4_dir = tmp_path / "e4"
    e4_dir.mkdir()
    pts = p3._e4_points(str(e4_dir / "rod3d_n8.csv"))
    pts.add(dict(case="B", mu=0.3, realization=0, n=8, t1=0.05, width=1.5, dF_star_field=10.0, dF_star=11.0, result=0))
    pts.add(dict(case="C", mu=0.3, realization=0, n=8, t1=0.05, width=1.5, dF_star_field=7.0, dF_star="nan", result=2))
    e4_calls = []
    monkeypatch.setattr(e5m, "e4", lambda *a: e4_calls.append(a))

    def record(sc):
        if sc.kind == "rod3d":
            return _record_3d(sc.n, [(1, 0.01)], [(7, 0.05), (3, 0.02)], t_stop=0.04)
        return SimpleNamespace(observables={}, q_final=jnp.asarray(_sines(127, (3, 0.02), (9, 0.01))), buckled=1,
                               t_stop=0.05)

    fake_scene.record = record
    out = tmp_path / "e5"
    out.mkdir()
    clock = iter([100.0, 102.34, 200.0, 200.96])  # each model's run timed on its own
    monkeypatch.setattr(e5m, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    res = e5m.e5(str(out), quick="tiny", progress=True)
    assert e4_calls == [(str(e4_dir), "tiny", True, None, (0.3,))]
    steps, run3d, stepf, runf = fake_scene.made
    assert (steps.kind, steps.dF, steps.n, type(steps.perturbation).__name__) == ("rod3d", 15.0, 8, "RandomVelocity")
    assert float(steps.perturbation.amplitude) == 1.0
    assert (run3d.kind, run3d.dF, run3d.n, run3d.mode, run3d.dt) == (
        "rod3d", pytest.approx(11.55), 8, 6, pytest.approx(1.15e-5))
    assert (stepf.kind, stepf.dF, stepf.n) == ("field", 100.0, 499)
    assert (runf.kind, runf.dF, runf.n, runf.dt) == ("field", pytest.approx(10.5), 499, pytest.approx(2e-5))
    assert (run3d.t1, run3d.n_save, runf.t1, runf.n_save) == (0.05, 501, 0.05, 501)
    assert float(run3d.perturbation.amplitude) == pytest.approx(15e-3)
    assert _same_key(run3d.perturbation.key, jax.random.fold_in(jax.random.key(0), 0))
    (row,) = _read(out / "rod3d_n8.csv")
    assert list(row) == p3.E5_COLUMNS
    assert {k: row[k] for k in ("perturbation", "mu", "realization", "n", "t1", "dF_star", "buckled", "t_stop", "mode",
                                "second_mode", "field_dF_star", "field_buckled", "field_mode", "field_second_mode")} == dict(
        perturbation="random-velocity", mu="0.3", realization="0", n="8", t1="0.05", dF_star="11.0", buckled="1",
        t_stop="0.04", mode="7", second_mode="3", field_dF_star="10.0", field_buckled="1", field_mode="3",
        field_second_mode="9")
    assert float(row["share"]) == pytest.approx(0.05**2 / (0.05**2 + 0.02**2), rel=1e-9)
    assert float(row["field_share"]) == pytest.approx(0.8, rel=1e-9)
    assert (float(row["wall_s"]), float(row["field_wall_s"])) == (2.3, 1.0)
    assert res == {"n": 8, "random-velocity rod3d": {"mu=0.3": [7]}, "random-velocity field": {"mu=0.3": [3]},
                   "random-position rod3d": {"mu=0.3": []}, "random-position field": {"mu=0.3": []}}
    assert capsys.readouterr().out == "  E5 random-velocity, mu = 0.3, realization 0: 3D mode 7 (0.86), field mode 3 (0.80)\n"
    assert (out / "rod3d_n8.png").stat().st_size > 0
    fake_scene.made.clear()
    assert e5m.e5(str(out), quick="tiny", progress=False) == res and fake_scene.made == []


def test_modes_of_a_coarse_rod_are_counted_among_its_own_interior_nodes_only():
    """With fewer interior nodes than the 40 modes asked for, the count stops at the node count
    instead of aliasing: a mode-4 profile on 7 interior nodes (8 segments) is mode 4."""
    s = np.arange(1, 8) / 8
    m, share, _, _ = p3._modes(np.sin(4 * np.pi * s))
    assert m == 4 and share == pytest.approx(1.0, abs=1e-12)


def test_crosscheck_times_the_field_search_and_the_3d_runs_apart(monkeypatch):
    """Seconds of the field model's search (to 0.01 s) and of the 3D grids after it (to 0.1 s),
    from a clock that reads 100 s, then 101.23456 s after the search, then 104.56789 s at the end."""
    clock = iter([100.0, 101.23456, 104.56789])
    monkeypatch.setattr(exp3d, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    (r,), _ = _crosscheck(monkeypatch, lambda v: v > 0.026)
    assert r["seconds_field"] == 1.23 and r["seconds_rod3d"] == 3.3


def test_e1_critical_force_of_each_member_is_its_own_first_peak_past_the_frictionless_load(monkeypatch):
    """Two members with stand-in reactions: member 0 peaks at 10 N (save 3) and falls 30 %; member
    1 climbs to 13 N (save 6) and falls, after a 20 % dip below F⁰₆ (1.31 N) that is not buckling. Each
    member's critical force is its own first peak, at its own displacement."""
    F0 = float(theory.reference_load(jr.RodChannel.reference(0.3)))
    R = np.array([[0.0, 5.0, 8.0, 10.0, 7.0, 6.0, 11.0, 12.0, 12.0, 12.0, 12.0],
                  [0.0, 1.0, 0.8, 6.0, 9.0, 12.0, 13.0, 9.0, 9.0, 9.0, 9.0]])
    assert 1.0 < F0 < 5.0
    end_x = 3.0 - np.arange(11.0)[None, :] * np.array([[1e-4], [2e-4]])

    def batched(model, states, t1, n_save, dt, threshold, scheme=None):
        asked.append((dt, threshold, scheme))
        return SimpleNamespace(observables=dict(reaction=jnp.stack([jnp.zeros_like(jnp.asarray(R)), jnp.asarray(R)], -1),
                                                end_x=jnp.asarray(end_x)),
                               buckled=np.array([True, True]), n_steps=np.array([10, 10]),
                               energy_balance=jnp.zeros((2, 11)))

    asked = []
    monkeypatch.setattr(exp3d, "_batched", batched)
    res = exp3d.e1_curves(0.3, (10e-3, 30e-3), n=4, t1=0.01, n_save=11, dt=1e-4, scheme="verlet")
    assert asked == [(1e-4, 1.0, "verlet")]  # the scheme asked for, labelled at 1 rad
    np.testing.assert_array_equal(res["critical_force"], [10.0, 13.0])
    np.testing.assert_allclose(res["d_critical"], [3e-4, 1.2e-3], rtol=1e-12)
    assert res["peaked"].tolist() == [True, True]
    # without dt or dt_fraction: the scheme's default step at the first member's initial state
    asked.clear()
    exp3d.e1_curves(0.3, (10e-3, 30e-3), n=4, t1=0.01, n_save=11, scheme="verlet")
    model = Rod3D(jr.RodChannel.reference(0.3), 4, control="displacement", speed=1e-3)
    q, _ = model.initial_state(0.0, lateral_velocity=sine_velocity(model, 10e-3))
    assert asked[0][0] == pytest.approx(default_step(model, q, "verlet"), rel=1e-12)
