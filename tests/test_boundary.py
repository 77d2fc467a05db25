import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import boundary as bd
from jaxrod import theory as th
from jaxrod.cli import main

ROD = jr.RodChannel.reference(mu=0.3)


@pytest.mark.parametrize("dF", [1.0, 5.0, 20.0])
def test_single_mode_critical_velocity_is_p6_in_few_evaluations(dF):
    F = th.frictionless_load(ROD, 6) + dF
    k, f = th.stiffness(ROD, 6, F), th.friction_amplitude(ROD)
    v_p6 = float(ROD.R * th.velocity_intercept(k, f))
    res, sens = bd.critical_velocity(ROD, dF, model="mode", bracket=(v_p6 / 2.7, 3.6 * v_p6),
                                     sensitivities=("mu", "dF"))
    assert int(res.result) == 0
    assert float(res.root) == pytest.approx(v_p6, rel=1e-6)
    assert int(res.evaluations) <= 8
    # bisection to the same tolerance needs many more evaluations
    g = lambda v: bd.single_mode_indicator(v / ROD.R, k, f, f)
    bis = bd.bisection(g, v_p6 / 2.7, 3.6 * v_p6, rtol=1e-6)
    assert float(bis.root) == pytest.approx(v_p6, rel=1e-6)
    assert int(bis.evaluations) >= 2 * int(res.evaluations)
    # IFT sensitivities against the analytic derivatives of v = R f / sqrt(-k):
    # f is proportional to mu, and dk/dF = -omega^2/rho
    om2 = (6 * math.pi / 3.0) ** 2
    assert float(sens["mu"]) == pytest.approx(v_p6 / 0.3, rel=1e-5)
    dv_dk = float(ROD.R * f / 2 * (-k) ** -1.5)
    assert float(sens["dF"]) == pytest.approx(dv_dk * (-om2 / float(ROD.rho)), rel=1e-5)


def test_single_mode_ift_gives_dAdotcr_df():
    k, f = -9.0, 1.7

    def g2(x, p):
        return bd.single_mode_indicator(x, p["k"], p["f"], p["f"])

    vc = float(th.velocity_intercept(k, f))
    res = bd.safeguarded_newton(lambda x: g2(x, {"k": k, "f": f}), vc / 2.7, 3.6 * vc)
    sens = bd.implicit_sensitivities(g2, res.root, {"k": jnp.asarray(k), "f": jnp.asarray(f)})
    assert float(sens["f"]) == pytest.approx(1 / math.sqrt(-k), rel=1e-5)  # dȦcr/df = 1/sqrt|k|
    assert float(sens["k"]) == pytest.approx(f / 2 * (-k) ** -1.5, rel=1e-5)


@pytest.mark.parametrize("v_mm", [7.5, 15.0])
def test_single_mode_critical_load_is_p7(v_mm):
    v0 = v_mm * 1e-3
    F0 = th.frictionless_load(ROD, 6)
    dF_p7 = float(th.critical_load_velocity(ROD, 6, v0 / ROD.R) - F0)
    res, sens = bd.critical_load(ROD, v0, model="mode", bracket=(dF_p7 / 2.7, 3.6 * dF_p7),  # a factor 9.7, asymmetric
                                 sensitivities=("mu", "amplitude", "R"))
    assert int(res.result) == 0
    assert float(res.root) == pytest.approx(dF_p7, rel=1e-6)
    assert int(res.evaluations) <= 8
    # P7: dF* = rho f^2/(omega^2 Adot0^2) with f ∝ mu: d/dmu = 2 dF*/mu, d/dv0 = -2 dF*/v0
    assert float(sens["mu"]) == pytest.approx(2 * dF_p7 / 0.3, rel=1e-5)
    assert float(sens["amplitude"]) == pytest.approx(-2 * dF_p7 / v0, rel=1e-5)
    assert abs(float(sens["R"])) < 1e-6 * dF_p7  # R f and F - F0 do not depend on R


def test_invalid_bracket_is_reported():
    g = lambda x: x - 10.0
    r = bd.safeguarded_newton(g, 1.0, 2.0)
    assert int(r.result) == bd.ROOT_RESULTS.invalid_bracket


# the Galerkin case (9 s) is slow: the field case checks the same search by default
@pytest.mark.parametrize("model,dF", [("field", 2.0), pytest.param("field", 12.0, marks=pytest.mark.slow),
                                      pytest.param("galerkin", 5.0, marks=pytest.mark.slow)])
def test_departure_root_is_the_label_boundary_in_few_runs(model, dF):
    """The departure search against label bisection of the same runs (an independent use of the
    label only), and its IFT sensitivity against a finite difference of two root solves."""
    n = 32 if model == "field" else 12
    res, sens = bd.critical_velocity(ROD, dF, model=model, n=n, rtol=1e-6, sensitivities=("mu",))
    assert int(res.result) == 0
    assert float(res.lo) <= float(res.root) <= float(res.hi)
    dt = jr.scene.Scene(ROD, dF, kind=model, n=n).step()
    label = lambda v: bd.crossing_state(jr.scene.Scene(ROD, dF, jr.SineVelocity(v, 6.0), model, n, 6, dt))[1]
    bis = jax.jit(lambda: bd.bisection(label, 1e-4, 1.0, rtol=1e-8))()
    assert int(bis.result) == 0
    assert float(res.root) == pytest.approx(float(bis.root), rel=1e-6)
    # from the wide bracket, with no prediction: well under bisection to the same tolerance for
    # the field model; the Galerkin model leaves the marginal state slowly (u/δ falls from 86 to
    # 3 s⁻¹ near its root), and the search is then about as costly as bisection
    same = jax.jit(lambda: bd.bisection(label, 1e-4, 1.0, rtol=1e-6))()
    if model == "field":
        assert 3 * int(res.evaluations) <= 2 * int(same.evaluations)
    else:
        assert int(res.evaluations) <= int(same.evaluations)
    h = 1e-3
    kw = dict(model=model, n=n, dt=dt, rtol=1e-10, sensitivities=())
    up, _ = bd.critical_velocity(ROD.with_friction(0.3 + h), dF, **kw)
    dn, _ = bd.critical_velocity(ROD.with_friction(0.3 - h), dF, **kw)
    fd = (float(up.root) - float(dn.root)) / (2 * h)
    assert float(sens["mu"]) == pytest.approx(fd, rel=2e-3)


@pytest.mark.parametrize("dF", [1.0, 2.0])
def test_field_critical_velocity_against_a_finer_label_bisection(dF):
    """The product's number: the field model's v₀* (64 nodes, its default step, the departure
    search) against a reference computed here by another method at another resolution — label
    bisection (buckled or not) with twice the nodes and half the step — within 1 % (measured
    −0.39 % at ΔF = 1 N, −0.61 % at 2 N; 32 nodes were +0.3 % and −2.7 % off the 64-node value).
    At ΔF = 1 N the single-mode theory P6 holds too: within 1 % of it (measured −0.51 %)."""
    res, _ = bd.critical_velocity(ROD, dF, model="field", n=64, rtol=1e-6, sensitivities=())
    assert int(res.result) == 0
    dt = jr.scene.Scene(ROD, dF, kind="field", n=64).step() / 2
    label = lambda v: bd.crossing_state(jr.scene.Scene(ROD, dF, jr.SineVelocity(v, 6.0), "field", 128, 6, dt))[1]
    ref = jax.jit(lambda: bd.bisection(label, 1e-2, 0.2, rtol=1e-4))()
    assert int(ref.result) == 0
    assert float(res.root) == pytest.approx(float(ref.root), rel=0.01)
    if dF == 1.0:
        F = th.frictionless_load(ROD, 6) + dF
        p6 = float(ROD.R * th.velocity_intercept(th.stiffness(ROD, 6, F), th.friction_amplitude(ROD)))
        assert float(res.root) == pytest.approx(p6, rel=0.01)


def test_critical_load_of_a_random_position_scene_splits_its_labels():
    """ΔF* of a random force pulse (±2 N/m for 1 ms, 48 field nodes) found by the search, checked
    by plain runs of the scene, independent of the search: 2 % below it the rod sticks (stable),
    2 % above it buckles (measured ΔF* = 8.46 N, in 17 runs)."""
    key = jax.random.key(4)
    pert = jr.registry.make_perturbation("random-position", 2.0, 6, key)
    dt = jr.scene.Scene(ROD, 100.0, pert, "field", n=48).step()
    res, _ = bd.critical_load(ROD, 2.0, model="field", perturbation="random-position", n=48, dt=dt, key=key,
                              sensitivities=())
    assert int(res.result) == 0 and 1.0 < float(res.root) < 50.0
    for share, buckled in ((0.98, False), (1.02, True)):
        sol = jr.scene.Scene(ROD, share * float(res.root), pert, "field", n=48, dt=dt).run(t1=2.0, save_state=False)
        assert bool(sol.buckled) == buckled, share
        assert bool(sol.stuck[-1]) == (not buckled)


@pytest.mark.slow  # 11 s; tests/test_single_mode.py checks the smooth law against the sharp one by default
def test_smooth_law_continuation_converges_to_the_sharp_root():
    k, f = -4.0, 2.0
    vc = float(th.velocity_intercept(k, f))
    eps = [1e-1, 1e-2, 1e-3]
    roots = bd.continuation(lambda x, e: bd.smooth_single_mode_indicator(x, k, f, e), eps, vc / 3, 3 * vc)
    err = [abs(float(r.root) / vc - 1) for r in roots]
    print("eps -> relative error of the smooth-law root:", dict(zip(eps, err)))
    assert all(int(r.result) == 0 for r in roots)
    assert err[0] > err[1] > err[2] and err[2] < 1e-3


def test_cli_boundary_and_critical_load_json(capsys):
    assert main(["boundary", "--model", "mode", "--dF", "1:20:3", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [set(r) for r in rows] == [{"dF", "v0_star", "evaluations", "result"}] * 3
    for r in rows:
        F = th.frictionless_load(ROD, 6) + r["dF"]
        p6 = float(ROD.R * th.velocity_intercept(th.stiffness(ROD, 6, F), th.friction_amplitude(ROD)))
        assert r["v0_star"] == pytest.approx(p6, rel=1e-6) and r["result"] == "converged"
    assert main(["critical-load", "--model", "mode", "--mu", "0.1:0.4:3", "--amplitude", "0.015", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [set(r) for r in rows] == [{"mu", "dF_star", "evaluations", "result"}] * 3
    ratios = [r["dF_star"] / r["mu"] ** 2 for r in rows]  # P7: dF* ∝ mu^2
    np.testing.assert_allclose(ratios, ratios[0], rtol=1e-5)
    assert main(["critical-load", "--model", "field", "--n", "16", "--mu", "0.2:0.4:2", "--perturbation",
                 "random-velocity", "--amplitude", "0.015", "--realizations", "2", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {"mu", "dF_star", "evaluations", "result", "dF_star_std"} <= set(rows[0])


@pytest.mark.slow  # 14 s of optax iterations through the field model
def test_worst_case_perturbation_beats_the_sine_field():
    from jaxrod.worst_case import worst_case_velocity

    r = worst_case_velocity(ROD, 5.0, n=24, norm="l2", steps=8, n_random=6)
    assert r["sine_result"] == 0
    assert r["norm_worst"] < r["norm_sine"]
    assert r["norm_worst"] <= r["random_norms"].min() + 1e-12  # multi-start keeps the best
    assert r["indicator"](1.01 * r["norm_worst"]) > 0  # 1 % above: buckles
    assert r["indicator"](0.99 * r["norm_worst"]) <= 0  # 1 % below: does not
    assert r["single_mode_prediction"] > 0 and r["single_mode_prediction_mode"] >= 6


def test_static_friction_above_dynamic_is_kept_by_the_search():
    """A rod with μ_s = 0.6 > μ_d = 0.3 starting from rest with a random shape (field model, 24
    nodes): the search used to rebuild it with μ_s = μ_d, so both rods had the same critical load.
    Static friction holds the resting rod a little longer: its ΔF* lies above the μ_s = μ_d one,
    and it is a label boundary of the rod it was asked about (3 % below straight, 3 % above
    buckled at the search's horizon)."""
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    equal = jr.RodChannel.reference(0.3)
    sticky = equal.with_friction(0.6, 0.3)
    kw = dict(perturbation="random-shape", model="field", n=24, rtol=1e-4, sensitivities=())
    f_eq = float(bd.critical_load(equal, 2e-3, **kw)[0].root)
    f_st = float(bd.critical_load(sticky, 2e-3, **kw)[0].root)
    assert f_st > 1.002 * f_eq
    pert = make_perturbation("random-shape", 2e-3, 6, jax.random.key(0))
    labels = [bool(Scene(sticky, f * f_st, pert, "field", n=24).run(t1=0.5, save_state=False).buckled)
              for f in (0.97, 1.03)]
    assert labels == [False, True]


def test_list_loads_and_a_zero_tolerance_on_the_command_line(capsys):
    assert main(["boundary", "--model", "mode", "--dF", "5,20", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["dF"] for r in rows] == [5.0, 20.0]
    with pytest.raises(SystemExit) as exc:
        main(["boundary", "--rtol", "0"])
    assert exc.value.code == 2 and "--rtol" in capsys.readouterr().err


def test_single_mode_indicator_calls_a_state_held_by_static_friction_stable():
    """μ_s > μ_d: a mode at rest at A₀ between f_d/|k| and f_s/|k| is held (the exact solution
    keeps it stuck), so the indicator must be ≤ 0 there (it measured A against f_d/|k| and called
    it buckled); beyond f_s/|k| it runs away (> 0). With μ_s = μ_d nothing changes."""
    k, f_s, f_d = -4.0, 3.0, 2.0  # f_d/|k| = 0.5, f_s/|k| = 0.75
    held = bd.single_mode_indicator(0.0, k, f_s, f_d, A0=0.6)
    A, _, stuck, _, _ = jr.exact_solution(0.6, 0.0, k, f_s, f_d, 5.0)
    assert bool(stuck) and float(A) == pytest.approx(0.6)
    assert float(held) <= 0.0
    assert float(bd.single_mode_indicator(0.0, k, f_s, f_d, A0=0.8)) > 0.0
    same = bd.single_mode_indicator(0.3, k, 2.0, 2.0)
    A, *_ = jr.exact_solution(0.0, 0.3, k, 2.0, 2.0, 10.0 / 2.0)
    assert float(same) == pytest.approx(float(A) / 0.5 - 1.0, rel=1e-12)


def test_curve_by_continuation_equals_independent_searches():
    """Searched along the loads from predictions, or each from the wide bracket: the same roots
    (to the tolerance), with fewer runs per point along the curve."""
    dFs = [2.0, 3.0, 4.5, 7.0]
    kw = dict(model="field", n=32, dt=jr.scene.Scene(ROD, 7.0, kind="field", n=32).step(), rtol=1e-6,
              sensitivities=())
    along, _ = bd.boundary_curve(ROD, dFs, **kw)
    alone, _ = bd.boundary_curve(ROD, dFs, continuation=False, **kw)
    assert (np.asarray(along.result) == 0).all() and (np.asarray(alone.result) == 0).all()
    np.testing.assert_allclose(along.root, alone.root, rtol=2e-6)
    assert np.asarray(along.root).tolist() == sorted(np.asarray(along.root).tolist(), reverse=True)
    assert np.mean(along.evaluations[1:]) < np.mean(alone.evaluations[1:])
    # each search's first run at 1.02 x its prediction: 35 runs in all here (measured; 43 when
    # it starts at 2.02 x, the first load's search then taking 13 runs instead of 7)
    assert int(np.sum(along.evaluations)) <= 36


def test_label_bisection_seeded_by_the_field_model_finds_the_plain_bisection_root():
    """`boundary_curve` by label bisection on a model other than the field model (the 3D rod's
    default) starts at the field model's boundary: on the Galerkin model its bracket overlaps the
    bracket of a bisection over the whole range, of the same runs, in fewer of them, at two loads
    searched at once (one compiled search)."""
    kw = dict(model="galerkin", n=6, method="bisection", rtol=1e-3, bracket=(1e-4, 1.0), sensitivities=())
    seeded, _ = bd.boundary_curve(ROD, [2.0, 8.0], **kw)
    plain, _ = bd.boundary_curve(ROD, [2.0, 8.0], continuation=False, **kw)
    assert np.all(np.asarray(seeded.result) == 0) and np.all(np.asarray(plain.result) == 0)
    assert np.all(np.asarray(seeded.lo) < np.asarray(plain.hi)) and np.all(np.asarray(plain.lo) < np.asarray(seeded.hi))
    assert np.all(np.asarray(seeded.evaluations) < np.asarray(plain.evaluations))


def test_critical_load_by_label_bisection_seeded_by_the_field_model_finds_the_plain_bisection_root():
    """`critical_load_curve` by label bisection on a model other than the field model (the 3D
    rod's default) starts at the field model's ΔF* of the same perturbation and key: on the
    Galerkin model under E4's sine velocity (two μ, two realizations: four points, one per
    device in turn) its bracket overlaps the bracket of a bisection over the whole range, in
    fewer runs, at the same step (by default the seeded search resolves its step at its first
    bracket's top, the plain one at 60 N: this model's ΔF* moves 1.5 % between the two). (The
    Galerkin model of 6 modes has no ΔF* in the bracket under E4's random perturbations.)"""
    dt = jr.scene.Scene(ROD, 60.0, kind="galerkin", n=6).step()
    kw = dict(model="galerkin", n=6, dt=dt, method="bisection", rtol=1e-2, bracket=(0.05, 60.0), t1=0.5,
              perturbation="sine", realizations=2, seed=3, sensitivities=())
    seeded, _ = bd.critical_load_curve([0.2, 0.3], 0.015, **kw)
    plain, _ = bd.critical_load_curve([0.2, 0.3], 0.015, seeded=False, **kw)
    assert np.asarray(seeded.root).shape == (2, 2)
    assert np.all(np.asarray(seeded.result) == 0) and np.all(np.asarray(plain.result) == 0)
    assert np.all(np.asarray(seeded.lo) < np.asarray(plain.hi)) and np.all(np.asarray(plain.lo) < np.asarray(seeded.hi))
    assert np.sum(np.asarray(seeded.evaluations)) < np.sum(np.asarray(plain.evaluations))
