"""Contracts of the engine that a user reads directly: what a sweep does with each of its inputs,
the field model's exact linear flow and its energy breakdown, the 3D rod's scheme choice, and the
one-line errors that name what was wrong."""

import math
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.modal import sine_basis
from jaxrod.perturbations import RandomForce, SineVelocity
from jaxrod.models.field import FieldRecipe
from jaxrod.rod3d import Rod3D, Rod3DRecipe
from jaxrod.sweeps import SweepSpec, sweep

ROD = jr.RodChannel.reference(mu=0.3)
MODE = SweepSpec(model="mode", perturbation="sine", t1=0.3)  # the cheapest sweep to compile


def test_sweeping_a_rod_field_gives_what_fixing_it_in_the_spec_gives():
    """A swept RodChannel field (here R) reaches each member's rod: member i equals the sweep
    whose spec fixes R at the i-th value."""
    radii = [0.008, 0.02]
    swept = sweep(MODE, {"R": radii, "dF": [5.0]}, progress=False)
    for i, R in enumerate(radii):
        fixed = sweep(SweepSpec(model="mode", perturbation="sine", t1=0.3, rod={"R": R}), {"dF": [5.0]},
                      progress=False)
        for k in ("buckled", "max_theta", "t_stop", "result"):
            np.testing.assert_allclose(swept.outputs[k][i], fixed.outputs[k][0], rtol=1e-12, err_msg=k)
    # and the two radii are different rods (the check above would pass on one rod twice)
    assert swept.outputs["max_theta"][0] != swept.outputs["max_theta"][1]


def test_position_perturbation_duration_reaches_the_members():
    """SweepSpec.duration is how long the random forces act: a longer push moves the rod further."""
    out = []
    for duration in (1e-3, 4e-3):
        spec = SweepSpec(model="mode", perturbation="random-position", amplitude=5.0, duration=duration, t1=0.05)
        out.append(sweep(spec, {"dF": [5.0], "realization": [0]}, seed=1, progress=False).outputs)
    assert (out[0]["result"] == jr.RESULTS.successful).all() and (out[1]["result"] == jr.RESULTS.successful).all()
    assert out[1]["max_theta"][0] > 2.0 * out[0]["max_theta"][0]


@pytest.mark.parametrize("name", ["amplitude", "dF"])
def test_a_member_with_a_non_finite_amplitude_or_load_is_flagged_and_the_rest_run(name):
    vals = [0.01, float("nan")] if name == "amplitude" else [5.0, float("nan")]
    res = sweep(MODE, {name: vals}, progress=False)
    assert res.outputs["result"].tolist() == [jr.RESULTS.successful, jr.RESULTS.invalid_input]


def test_sweep_refuses_a_spec_that_is_not_a_sweep_spec_naming_its_type():
    with pytest.raises(TypeError, match=r"spec must be a SweepSpec, got dict\."):
        sweep({"model": "mode"}, {"dF": [5.0]}, progress=False)


def test_field_linear_flow_is_the_exact_flow_of_each_mode():
    """θ'' = −k_m θ per sine mode: after h, a_m = a cos ωh + (b/ω) sin ωh, b_m = b cos ωh − aω sin ωh
    (ω = √k_m, hyperbolic where k_m < 0), checked on a load that makes the first modes unstable."""
    n = 9
    m = jr.FieldModel.from_rod(ROD, n, dF=2.0)
    k = np.asarray(m.modal_stiffness(0.0))
    assert (k < 0).any() and (k > 0).any()
    rng = np.random.default_rng(0)
    a0, b0 = rng.normal(size=n), rng.normal(size=n)
    S = np.asarray(sine_basis(n))
    h = 3e-4
    q, v = m.linear_flow(jnp.asarray(S @ a0), jnp.asarray(S @ b0), 0.0, h)
    w = np.sqrt(k.astype(complex))
    a1 = (a0 * np.cos(w * h) + b0 * np.sin(w * h) / w).real
    b1 = (b0 * np.cos(w * h) - a0 * w * np.sin(w * h)).real
    np.testing.assert_allclose(np.asarray(q), S @ a1, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.asarray(v), S @ b1, rtol=1e-9, atol=1e-12)


def test_field_energy_breakdown_names_its_terms_and_gravity_is_half_w_r_theta_squared():
    """energy_terms: kinetic, bending, gravity, load; a uniform θ has gravity energy
    ½ w R ∫θ² ds = ½ w R h Σθ² and no kinetic energy at rest."""
    m = jr.FieldModel.from_rod(ROD, 15, dF=5.0)
    q = jnp.full(15, 0.1)
    terms = m.energy_terms(q, jnp.zeros(15), 0.0)
    assert set(terms) == {"kinetic", "bending", "gravity", "load"}
    assert float(terms["kinetic"]) == 0.0
    h = float(ROD.L) / 16
    assert float(terms["gravity"]) == pytest.approx(0.5 * float(ROD.w) * float(ROD.R) * h * 15 * 0.01, rel=1e-12)


def test_3d_rod_runs_leapfrog_under_a_perturbation_not_measured_for_its_implicit_scheme():
    assert Rod3DRecipe().scheme_under(SineVelocity(0.01)) is None  # implicit_3d: its own implicit default
    assert not RandomForce.implicit_3d
    assert Rod3DRecipe().scheme_under(RandomForce.from_settings(1.0, 6, jax.random.key(0), 1e-3)) == "leapfrog"
    # and its scene steps at that scheme's default step (half the explicit limit), not the implicit one
    from jaxrod.integrators import default_step

    force = RandomForce.from_settings(1.0, 6, jax.random.key(0), 1e-3)
    scene = jr.Scene(ROD, 5.0, force, kind="rod3d", n=60)
    explicit, implicit = default_step(scene.model(), scheme="leapfrog"), default_step(scene.model())
    assert scene.step() == explicit < 0.5 * implicit


def test_a_model_without_nodes_is_budgeted_as_one_node():
    recipe = FieldRecipe()  # the recipes' default budget
    assert recipe.bytes_per_member(None) == recipe.bytes_per_member(1)
    assert recipe.bytes_per_member(2) > recipe.bytes_per_member(1)


def test_galerkin_from_rod_names_the_two_load_arguments_it_needs_one_of():
    with pytest.raises(ValueError, match=r"^GalerkinModel\.from_rod needs exactly one of F and dF\.$"):
        jr.GalerkinModel.from_rod(ROD, 4)


def test_an_unknown_attribute_of_the_package_is_an_attribute_error_naming_it():
    with pytest.raises(AttributeError, match=r"^module 'jaxrod' has no attribute 'no_such_thing'$"):
        jr.no_such_thing  # noqa: B018


def test_a_traced_rod_without_a_step_is_refused_naming_scene_dt():
    def step(E):
        return jr.Scene(rod=jr.RodChannel.reference(mu=0.3, E=E), dF=5.0, kind="field", n=8).step()

    with pytest.raises(ValueError, match=r"^Scene\.dt must be given explicitly when the rod's stiffness parameters "
                                         r"are traced \(e\.g\. vmapped over EI, rho or R\): the step is a static setting\."):
        jax.jit(step)(2e11)
    assert math.isfinite(step(2e11))


def test_a_single_mode_scenes_field_grid_steps_at_0_4_of_its_stability_limit():
    """A field perturbation for the single mode is drawn on a field grid of `n_grid` nodes; its
    step `grid_dt` defaults to 0.4 of that grid's explicit limit 2/ω_max (the limit as the
    integrator states it), and a given `grid_dt` is taken as it is."""
    from jaxrod.models.field import FieldModel

    pert = RandomForce.from_settings(2.0, 6, jax.random.key(0), 1e-3)
    scene = jr.Scene(ROD, 5.0, pert, kind="mode", n_grid=32)
    grid, integrator = scene._grid()
    assert isinstance(grid, FieldModel) and grid.n_nodes == 32
    limit = float(np.min(np.asarray(jr.ProjectedVerlet(1.0).step_limit(grid))))
    assert integrator.dt == pytest.approx(0.4 * limit, rel=1e-12)
    assert jr.Scene(ROD, 5.0, pert, kind="mode", n_grid=32, grid_dt=1e-6)._grid()[1].dt == 1e-6


def test_critical_load_curve_member_is_the_search_with_its_documented_key():
    """Point (i, r) of `critical_load_curve` is `critical_load` with key fold_in(key(seed), i·R + r)."""
    from jaxrod import boundary as bd

    dt = jr.Scene(ROD, 7.0, kind="field", n=12).step()
    kw = dict(perturbation="random-velocity", model="field", n=12, dt=dt, rtol=1e-4, t1=1.0, bracket=(1e-2, 400.0),
              sensitivities=())
    curve, _ = bd.critical_load_curve([0.2, 0.4], 0.1, realizations=2, seed=7, **kw)
    assert np.asarray(curve.root).shape == (2, 2) and (np.asarray(curve.result) == 0).all()
    key = jax.random.fold_in(jax.random.key(7), 1 * 2 + 0)
    one, _ = bd.critical_load(jr.RodChannel.reference(mu=0.4), 0.1, key=key, **kw)
    assert float(curve.root[1, 0]) == pytest.approx(float(one.root), rel=1e-9)
    assert float(curve.root[1, 0]) != pytest.approx(float(curve.root[1, 1]), rel=1e-6)  # the keys differ


def test_critical_load_curve_searches_the_rod_with_its_overrides():
    """`rod_overrides` change the rod of every point (here a channel of half the clearance):
    each point is `critical_load` on `RodChannel.reference(mu, **rod_overrides)`, not on the
    reference rod (single mode, exact: no resolution to share)."""
    from jaxrod import boundary as bd

    kw = dict(model="mode", rtol=1e-9, bracket=(1e-3, 400.0), sensitivities=())
    R = 0.5 * float(ROD.R)
    curve, _ = bd.critical_load_curve([0.2, 0.4], 0.02, rod_overrides={"R": R}, **kw)
    for i, mu in enumerate((0.2, 0.4)):
        narrow, _ = bd.critical_load(jr.RodChannel.reference(mu=mu, R=R), 0.02, **kw)
        wide, _ = bd.critical_load(jr.RodChannel.reference(mu=mu), 0.02, **kw)
        assert float(curve.root[i, 0]) == pytest.approx(float(narrow.root), rel=1e-9)
        assert float(narrow.root) != pytest.approx(float(wide.root), rel=1e-3)


def test_critical_load_curve_gives_every_point_its_iteration_budget():
    """`max_iter` bounds the search of each point: with 2 iterations and a tolerance no search
    meets in 2, every point stops at `max_iterations` after the runs `critical_load` makes with
    the same budget; with the default budget the same points converge."""
    from jaxrod import boundary as bd

    kw = dict(model="mode", rtol=1e-12, bracket=(1e-3, 400.0), sensitivities=())
    capped, _ = bd.critical_load_curve([0.2, 0.4], 0.02, max_iter=2, **kw)
    one, _ = bd.critical_load(jr.RodChannel.reference(mu=0.4), 0.02, max_iter=2, **kw)
    assert (np.asarray(capped.result) == int(bd.ROOT_RESULTS.max_iterations)).all()
    assert int(capped.evaluations[1, 0]) == int(one.evaluations) == 4
    full, _ = bd.critical_load_curve([0.2, 0.4], 0.02, **kw)
    assert (np.asarray(full.result) == int(bd.ROOT_RESULTS.converged)).all()


def test_boundary_curve_is_silent_unless_asked_for_progress(capfd):
    from jaxrod import boundary as bd

    kw = dict(model="field", n=12, dt=jr.Scene(ROD, 7.0, kind="field", n=12).step(), rtol=1e-3, t1=0.5,
              sensitivities=())
    bd.boundary_curve(ROD, [3.0, 4.0], **kw)
    quiet = capfd.readouterr()
    assert quiet.out == "" and quiet.err == ""
    bd.boundary_curve(ROD, [3.0, 4.0], progress=True, **kw)
    assert capfd.readouterr().err != ""


def test_critical_load_started_at_its_root_confirms_it_in_fewer_runs():
    """`start`, a first guess of ΔF* [N], is where the search runs first: started at the root found
    without it, the search lands on the same root in fewer runs."""
    from jaxrod import boundary as bd

    kw = dict(model="field", n=12, dt=jr.Scene(ROD, 7.0, kind="field", n=12).step(), rtol=1e-6, t1=1.0,
              sensitivities=())
    cold, _ = bd.critical_load(ROD, 0.02, **kw)
    warm, _ = bd.critical_load(ROD, 0.02, start=float(cold.root) * 1.001, **kw)
    assert int(cold.result) == 0 and int(warm.result) == 0
    assert float(warm.root) == pytest.approx(float(cold.root), rel=1e-5)
    assert int(warm.evaluations) < int(cold.evaluations)


def test_a_sweep_refuses_to_resume_into_a_folder_of_another_sweep_saying_why(tmp_path):
    path = str(tmp_path / "sweep")
    sweep(MODE, {"dF": [5.0]}, seed=1, path=path, progress=False)
    with pytest.raises(ValueError, match="^" + re.escape(
            f"{path!r} holds a different sweep (its spec, inputs, seed or resolution differ); refusing to mix "
            "results. Use another path or delete it.") + "$"):
        sweep(MODE, {"dF": [5.0]}, seed=2, path=path, progress=False)


def test_galerkin_linear_flow_is_the_exact_flow_of_each_mode():
    """The Galerkin model's coordinates are the modal amplitudes: after h, a_m = a cos ωh + (b/ω)
    sin ωh, b_m = b cos ωh − aω sin ωh with ω = √k_m of its own modal stiffness (hyperbolic where
    k_m < 0, the unstable modes at ΔF = 2 N)."""
    m = jr.Scene(ROD, 2.0, jr.SineVelocity(0.01, 6.0), "galerkin", n=10).model()
    k = np.asarray(m.modal_stiffness(0.0))
    assert (k < 0).any() and (k > 0).any()
    rng = np.random.default_rng(1)
    a0, b0 = rng.normal(size=10), rng.normal(size=10)
    h = 3e-4
    q, v = m.linear_flow(jnp.asarray(a0), jnp.asarray(b0), 0.0, h)
    w = np.sqrt(k.astype(complex))
    np.testing.assert_allclose(np.asarray(q), (a0 * np.cos(w * h) + b0 * np.sin(w * h) / w).real, rtol=1e-9)
    np.testing.assert_allclose(np.asarray(v), (b0 * np.cos(w * h) - a0 * w * np.sin(w * h)).real, rtol=1e-9)


def test_galerkin_friction_acceleration_is_the_projected_sliding_friction():
    """Sliding everywhere in one direction (a positive mode-1 velocity), the friction law gives
    f_d = μ_d N/(ρR) along the velocity at every quadrature point (the ODE subtracts it); projected on
    the modes, mode m gets f_d ∫ sin(mπs/L) over ∫ sin²: 4 f_d/(mπ) for odd m, 0 for even m."""
    m = jr.Scene(ROD, 2.0, jr.SineVelocity(0.01, 6.0), "galerkin", n=6).model()
    _, f_d = m.friction_bounds(0.0)
    f_d = float(np.max(np.asarray(f_d)))
    got = np.asarray(m.friction_acceleration(jr.Coulomb(), jnp.zeros(6).at[0].set(1.0), 0.0))
    want = [4 * f_d / (mm * np.pi) if mm % 2 else 0.0 for mm in range(1, 7)]
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=2e-3 * f_d)


def test_the_documented_defaults_of_the_3d_rod_and_the_galerkin_model():
    """`Rod3D`'s wall is elastic unless asked (contact damping 0: energy conserved at μ = 0) and
    it has 100 segments unless given; the Galerkin model integrates its friction on
    max(64, 8·n_modes) midpoints."""
    from jaxrod.models.galerkin import GalerkinModel

    assert float(Rod3D(ROD, 4).contact_damping) == 0.0
    assert Rod3D(ROD).n == 100
    assert [GalerkinModel.from_rod(ROD, k, dF=1.0).n_quad for k in (1, 8, 9, 20)] == [64, 64, 72, 160]


class _Seen(Exception):
    """Raised by a stand-in for a search: what the driver handed it."""


def test_a_load_search_without_n_takes_the_nodes_its_perturbation_needs_at_the_largest_load(monkeypatch):
    """`critical_load` with no `n`/`dt`: the scene's resolution at the bracket's top load under the
    perturbation searched — for a random velocity the nodes of the scene's noise grid, more than a
    sine's — and its step. (The search is replaced by a stand-in that stops at its first scene.)"""
    from jaxrod.boundary import search as S
    from jaxrod.registry import make_perturbation

    def stand_in(scene_of, *args, **kwargs):
        raise _Seen(scene_of(jnp.asarray(0.0)))

    monkeypatch.setattr(S, "_search", stand_in)
    probe = lambda p: jr.Scene(ROD, 100.0, make_perturbation(p, 1.0, 6), kind="field")
    assert probe("random-velocity").size() > probe("sine").size()
    for p in ("random-velocity", "sine"):
        with pytest.raises(_Seen) as seen:
            jr.boundary.critical_load(ROD, 0.01, perturbation=p, bracket=(0.05, 100.0), sensitivities=())
        scene = seen.value.args[0]
        assert (scene.n, scene.dt) == (probe(p).size(), probe(p).step()), p


def test_a_curve_searched_at_once_without_n_takes_the_resolution_of_its_largest_load(monkeypatch):
    """`boundary_curve(continuation=False)` with no `n`/`dt` searches every load with the field
    nodes and step of the scene at its largest load (one compiled search)."""
    from jaxrod.boundary import curves as S

    def stand_in(rod, dF, **kw):
        raise _Seen(kw["n"], kw["dt"])

    monkeypatch.setattr(S, "critical_velocity", stand_in)
    with pytest.raises(_Seen) as seen:
        jr.boundary.boundary_curve(ROD, [3.0, 40.0, 7.0], continuation=False, sensitivities=())
    top = jr.Scene(ROD, 40.0, kind="field")
    assert seen.value.args == (top.size(), top.step()) and top.size() != jr.Scene(ROD, 3.0, kind="field").size()


def _counting_builds(monkeypatch, kind):
    """Count the constructions of `kind`'s model through its recipe (`build`)."""
    from jaxrod import registry

    cls = type(registry.recipe(kind))
    build, calls = cls.build, []
    monkeypatch.setattr(cls, "build", lambda self, *args: calls.append(args) or build(self, *args))
    return calls


@pytest.mark.parametrize("kind,n,pert", [("mode", None, jr.RandomVelocity(0.01, jax.random.key(1))),
                                         ("galerkin", 8, SineVelocity(0.01)), ("field", 16, SineVelocity(0.01)),
                                         ("rod3d", 6, SineVelocity(0.01))])
def test_a_scene_resolves_into_a_problem_building_its_model_once(monkeypatch, kind, n, pert):
    calls = _counting_builds(monkeypatch, kind)
    problem = jr.Scene(ROD, 5.0, pert, kind=kind, n=n).resolve()
    assert len(calls) == 1
    assert isinstance(problem.model, jr.registry.model_class(kind)) and problem.integrator.dt > 0
    assert problem.options.buckle_threshold == 0.5 and problem.options.save_state


def test_a_scene_run_and_the_simulate_command_build_the_model_once(monkeypatch, capsys):
    from jaxrod.cli import main

    calls = _counting_builds(monkeypatch, "field")
    scene = jr.Scene(ROD, 5.0, SineVelocity(0.01), kind="field", n=16)
    sol = scene.run(t1=0.01, n_save=3)
    assert len(calls) == 1 and int(sol.result) == 0
    again = scene.resolve().run(t1=0.01, n_save=3)
    np.testing.assert_array_equal(np.asarray(again.amplitude), np.asarray(sol.amplitude))
    calls.clear()
    assert main(["simulate", "--model", "field", "--n", "16", "--t1", "0.01", "--json"]) == 0
    assert len(calls) == 1 and '"model": "field"' in capsys.readouterr().out


def test_a_forced_model_forwards_every_member_of_the_interface_to_its_inner_model():
    """`under_lateral_force` wraps a per-DOF model: every method and property of `AbstractModel`
    is the inner model's (a new interface member is forwarded without a hand-written list), but
    the accelerations, which add the force."""
    from jaxrod.models.base import AbstractModel
    from jaxrod.models.dof import _Forced

    members = {k for k, v in vars(AbstractModel).items()
               if not k.startswith("_") and (callable(v) or isinstance(v, property))}
    assert members <= set(vars(_Forced)) and not _Forced.__abstractmethods__
    inner = jr.GalerkinModel.from_rod(ROD, 4, dF=5.0)
    force = jnp.linspace(0.0, 1.0, inner.sample_points().shape[0])
    forced = inner.under_lateral_force(force)
    q, v = jnp.full(4, 0.01), jnp.full(4, 0.2)
    extra = inner.from_samples(force / (ROD.rho * ROD.R))
    np.testing.assert_allclose(forced.accelerations(q, v, 0.0), inner.accelerations(q, v, 0.0) + extra, rtol=1e-12)
    for name in ("kinetic_energy", "amplitude"):
        assert float(getattr(forced, name)(v)) == float(getattr(inner, name)(v))
    np.testing.assert_array_equal(forced.friction_acceleration(jr.Tanh(1e-3), v, 0.0),  # Galerkin's own projection
                                  inner.friction_acceleration(jr.Tanh(1e-3), v, 0.0))
    assert (forced.autonomous, forced.resolved_modes) == (inner.autonomous, inner.resolved_modes)
