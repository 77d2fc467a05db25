"""Small contracts of the engine and its drivers that no larger test pins: the energy accounts of
one Verlet step, the sine shape, the save blocks, the 3D rod's kinetic terms and height, the
validity of a swept rod, the integrator's options, the experiments' table in `reproduce`, the
threshold of E1's field ramp, and the lock-up closed forms' name for a bad μ."""

from __future__ import annotations

import importlib
import inspect
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr


# ------------------------------------------------------------------ one Verlet step's accounts


class _Halves:
    """A stand-in model whose half steps are numbered: each kick adds 1 to v, each friction
    update doubles it, and each half step's impulse work is (lost, work in) = (v_after, 10·v_after)."""

    def kick(self, q, v, a, h):
        return v + 1.0

    def friction_update(self, friction, v_trial, v_prev, h, t, q, a):
        return 2.0 * v_trial

    def impulse_work(self, v_prev, v_trial, v_after, a, h):
        return {"friction": v_after}, 10.0 * v_after

    def drift(self, q, v, h):
        return q + h * v

    def accelerations(self, q, v, t):
        return jnp.zeros(())


def test_a_verlet_step_adds_the_losses_and_the_work_of_both_half_steps():
    q, v, a, (lost, work_in) = jr.ProjectedVerlet(0.1).step(_Halves(), jnp.asarray(0.0), jnp.asarray(0.0),
                                                           jnp.zeros(()), 0.0, 0.1)
    # first half: v = 2·(0 + 1) = 2; second half: v = 2·(2 + 1) = 6
    assert float(v) == 6.0 and float(q) == pytest.approx(0.2)
    assert float(lost["friction"]) == 8.0 and float(work_in) == 80.0


# ------------------------------------------------------------------ modal shapes, save blocks


def test_sine_shape_is_the_mode_at_the_interior_nodes():
    from jaxrod.modal import sine_shape

    got = np.asarray(sine_shape(5, 2))
    np.testing.assert_allclose(got, np.sin(np.pi * 2 * np.arange(1, 6) / 6), atol=1e-15)
    assert got.shape == (5,)
    single = sine_shape(5, 2.0, dtype=jnp.float32)  # in the dtype asked for, the mode number too
    assert single.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(single), got, atol=1e-6)


@pytest.mark.parametrize("intervals", [1, 7, 20, 40, 97, 200, 509, 800, 1024, 4 * 97])
def test_save_blocks_divide_the_intervals_near_a_twentieth(intervals):
    """The smallest divisor of the intervals at least ⌈intervals/20⌉, or, when that is more than 4×
    it (a prime count of intervals), the largest divisor below."""
    from jaxrod.simulate import BLOCKS, _block_size

    target = -(-intervals // BLOCKS)
    divisors = [b for b in range(1, intervals + 1) if intervals % b == 0]
    up = min(b for b in divisors if b >= target)
    expected = up if up <= 4 * target else max(b for b in divisors if b <= target)
    assert _block_size(intervals) == expected and intervals % _block_size(intervals) == 0


def test_a_prime_count_of_intervals_is_saved_in_blocks_of_one():
    from jaxrod.simulate import _block_size

    assert _block_size(509) == 1 and _block_size(97) == 1


# ------------------------------------------------------------------ the 3D rod's measures


@pytest.fixture(scope="module")
def rod3d_state():
    model = jr.Rod3D(jr.RodChannel.reference(0.3), 6)
    q, v = model.initial_state(0.0)
    return model, q, v


def test_rod3d_kinetic_terms_are_the_translational_and_rotational_energies(rod3d_state):
    model, q, v = rod3d_state
    vv = jnp.arange(21.0).reshape(7, 3) * 1e-3
    ww = jnp.arange(18.0).reshape(6, 3) * 1e-2
    terms = model.kinetic_terms(vv, ww)
    m, J = np.asarray(model.mass), np.asarray(model.inertia)
    kin = 0.5 * np.sum(m[:, None] * np.asarray(vv) ** 2)
    rot = 0.5 * np.sum(J[None, :] * np.asarray(ww) ** 2)
    assert set(terms) == {"kinetic", "rotational"}
    assert float(terms["kinetic"]) == pytest.approx(kin, rel=1e-14)
    assert float(terms["rotational"]) == pytest.approx(rot, rel=1e-14)
    moving = eqx.tree_at(lambda s: (s.v, s.w), v, (vv, ww))
    assert float(model.kinetic_energy(moving)) == pytest.approx(kin + rot, rel=1e-14)


def test_rod3d_height_is_zero_resting_on_the_bottom_and_the_lift_above_it(rod3d_state):
    model, q, v = rod3d_state
    a = model.accelerations(q, v)
    assert abs(float(model.observables(q, v, a)["height"])) < 1e-12
    lifted = eqx.tree_at(lambda s: s.x, q, q.x.at[3, 2].add(2e-4))
    assert float(model.observables(lifted, v, a)["height"]) == pytest.approx(2e-4, rel=1e-9)
    # `gap`: the largest distance of a node inside the clearance circle: −sag resting on the wall
    # (every node sunk into it under its weight), the lift less the sag where one node is lifted
    sag = float(model.static_sag())
    assert sag > 0 and float(model.observables(q, v, a)["gap"]) == pytest.approx(-sag, rel=1e-9)
    assert float(model.observables(lifted, v, a)["gap"]) == pytest.approx(2e-4 - sag, rel=1e-9)


# ------------------------------------------------------------------ a swept rod's validity


@pytest.mark.parametrize("field, value", [("L", -3.0), ("d", 0.0), ("E", jnp.nan), ("g", -9.81)])
def test_a_rod_with_a_bad_length_or_modulus_is_invalid_whatever_its_poisson_ratio(field, value):
    from jaxrod.sweeps.member import _valid

    rod = jr.RodChannel.reference(0.3)
    assert bool(_valid(rod, {}))
    bad = eqx.tree_at(lambda r: getattr(r, field), rod, jnp.asarray(value))
    assert not bool(_valid(bad, {}))
    assert not bool(_valid(bad, {"dF": 5.0, "amplitude": 1e-3}))


@pytest.mark.parametrize("changes, inputs, valid", [
    ({"rho_v": 0.0}, {}, False), ({"R": -1e-3}, {}, False), ({"E": jnp.inf}, {}, False),
    ({"nu": -1.0}, {}, False), ({"nu": -0.999}, {}, True), ({"nu": 0.5}, {}, False), ({"nu": 0.499}, {}, True),
    ({"mu_s": 0.3, "mu_d": 0.3}, {}, True), ({"mu_s": 0.3, "mu_d": 0.3 + 1e-12}, {}, False),
    ({"mu_d": 0.0}, {}, True), ({"mu_d": -1e-12}, {}, False), ({"mu_s": jnp.inf, "mu_d": 0.3}, {}, False),
    ({"mu_s": jnp.nan}, {}, False),
    ({}, {"dF": -20.0}, True), ({}, {"dF": jnp.inf}, False), ({}, {"dF": jnp.nan}, False),
    ({}, {"amplitude": 0.0}, True), ({}, {"amplitude": -1e-12}, False), ({}, {"amplitude": jnp.nan}, False),
], ids=lambda x: str(x))
def test_a_swept_member_is_valid_exactly_inside_the_physical_ranges(changes, inputs, valid):
    """Positive finite sizes, moduli, density, clearance and gravity; −1 < ν < 1/2 (open);
    0 ≤ μ_d ≤ μ_s, both finite; a finite ΔF of either sign; a finite amplitude ≥ 0."""
    from jaxrod.sweeps.member import _valid

    rod = jr.RodChannel.reference(0.3)
    for field, value in changes.items():
        rod = eqx.tree_at(lambda r, f=field: getattr(r, f), rod, jnp.asarray(value, float))
    p = {k: jnp.asarray(v, float) for k, v in inputs.items()}
    assert bool(_valid(rod, p)) == valid


# ------------------------------------------------------------------ integrators' options


def test_default_for_hands_its_options_to_the_integrator():
    from jaxrod.integrators import default_for

    model = jr.FieldModel.from_rod(jr.RodChannel.reference(0.3), 16, F=5.0)
    law = jr.Tanh(1e-3)
    integ = default_for(model, 1e-4, friction=law)
    assert integ.friction is law and integ.dt == 1e-4


# ------------------------------------------------------------------ reproduce's experiments


def test_reproduce_runs_each_experiment_by_its_own_name():
    from jaxrod import reproduce
    from jaxrod.experiments import e2, e3, e4, e5, e6
    from jaxrod.experiments.e1 import e1
    from jaxrod.experiments.helix import post_buckling
    from jaxrod.experiments.lockup import lockup

    assert reproduce._runners() == {"e1": e1, "e2": e2.e2, "e3": e3.e3, "e4": e4.e4, "e5": e5.e5, "e6": e6.e6,
                                    "helix": post_buckling, "lockup": lockup}


def test_reproduce_with_the_3d_rod_hands_the_folder_and_segments_to_each_part(monkeypatch):
    from jaxrod import reproduce
    from jaxrod.experiments.e3 import rod3d as e3r
    from jaxrod.experiments.e6 import rod3d as e6r

    calls = []
    monkeypatch.setattr(e3r, "e3", lambda out, quick, progress, n: calls.append(("e3", out, quick, progress, n)))
    monkeypatch.setattr(e6r, "e6c", lambda out, quick, progress, n: calls.append(("e6", out, quick, progress, n)))
    runners = reproduce._runners_3d(90)
    assert set(runners) == {"e3", "e4", "e5", "e6"}
    runners["e3"]("/tmp/x", True, False)
    runners["e6"]("/tmp/y", "tiny", True)
    assert calls == [("e3", "/tmp/x", True, False, 90), ("e6", "/tmp/y", "tiny", True, 90)]


# ------------------------------------------------------------------ E1's field ramp


def test_field_ramp_force_counts_buckling_at_the_threshold_it_is_given():
    """Pushed at 1 mm/s after a 30 mm/s kick, the field model (16 nodes, stepped at the ramp's
    stiffest, unloaded state) passes 0.05 rad before 0.5 rad, both below F_max = 12 N; no run reaches
    10 rad before F_max."""
    from jaxrod.experiments.e1_speed import field_ramp_force

    rod = jr.RodChannel.reference(0.0)
    low, default, high = (field_ramp_force(rod, 1e-3, (30e-3,), n=16, threshold=t) for t in (0.05, 0.5, 2.0))
    assert 0.0 < low[0] < default[0] < high[0] < 12.0


# ------------------------------------------------------------------ lock-up closed forms


def test_lockup_length_names_a_negative_friction_coefficient():
    from jaxrod.lockup.chain import lockup_length

    with pytest.raises(ValueError, match=r"^mu = -0\.2 is invalid: it must be finite and >= 0\.$"):
        lockup_length(0.019, 5.7e-4, 0.01, -0.2)
    assert math.isfinite(float(lockup_length(0.019, 5.7e-4, 0.01, 0.2)))


# ------------------------------------------------------------------ progress of a run


def test_a_run_reports_each_save_interval_and_whether_it_has_stopped(monkeypatch):
    """A buckling run (field model, 22 nodes: traced here with the recorder in place) reports
    save intervals 1..8 of 8, not stopped before it buckles and stopped from then on."""
    from jaxrod.integrators import progress

    ticks = []
    monkeypatch.setattr(progress, "tick", lambda done, total, stopped: ticks.append((int(done), int(total),
                                                                                      bool(stopped))))
    s = jr.Scene(jr.RodChannel.reference(0.3), 5.0, jr.SineVelocity(0.08, 6.0), "field", n=22)
    q0, v0 = s.initial_state()
    sol = jr.simulate(s.model(), s.integrator(), q0, v0, 0.21, n_save=9, throw=False,
                      options=jr.RunOptions(save_state=False, progress=True))
    assert bool(sol.buckled) and float(sol.t_buckle) < 0.21
    assert [t[:2] for t in ticks] == [(i, 8) for i in range(1, 9)]
    stopped = [t[2] for t in ticks]
    first = stopped.index(True)
    assert not any(stopped[:first]) and all(stopped[first:])
    assert first == int(np.ceil(float(sol.t_buckle) / (0.21 / 8))) - 1
    # inside a caller's jit the run reports from the compiled loop: the same intervals and flags
    host = list(ticks)
    ticks.clear()
    model, integ = s.model(), s.integrator()
    run = jax.jit(lambda q, v: jr.simulate(model, integ, q, v, 0.21, n_save=9, throw=False,
                                           options=jr.RunOptions(save_state=False, progress=True)).buckled)
    assert bool(run(q0, v0))
    assert ticks == host



def test_a_run_shown_in_blocks_raises_only_on_failure_and_only_when_asked():
    """With a progress bar (the run in blocks on the host) a successful run returns, `throw` or
    not; a run from a non-finite start returns its code with `throw=False` and raises the
    code's message with `throw=True`."""
    s = jr.Scene(jr.RodChannel.reference(0.3), 5.0, jr.SineVelocity(0.08, 6.0), "field", n=22)
    q0, v0 = s.initial_state()
    opts = jr.RunOptions(save_state=False, progress=True)
    for throw in (True, False):
        ok = jr.simulate(s.model(), s.integrator(), q0, v0, 0.21, n_save=9, throw=throw, options=opts)
        assert int(ok.result) == jr.RESULTS.successful
    q_nan = jax.tree_util.tree_map(lambda a: a * jnp.nan, q0)
    bad = jr.simulate(s.model(), s.integrator(), q_nan, v0, 0.21, n_save=9, throw=False, options=opts)
    assert int(bad.result) == jr.RESULTS.nonfinite
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"non-finite \(NaN or inf\)"):
        jr.simulate(s.model(), s.integrator(), q_nan, v0, 0.21, n_save=9, throw=True, options=opts)

def test_the_3d_step_bound_adds_the_wall_stiffness_only_where_gravity_presses_the_rod_on_it():
    """At rest on the bottom, the Hertz wall adds stiffness through the static sag of gravity:
    without gravity (or without the channel) the bound is the free rod's, lower than with both."""
    from jaxrod.rod3d.stiffness import frequency_bound

    rod = jr.RodChannel.reference(0.3)
    free = float(frequency_bound(jr.Rod3D(rod, 6, gravity=False, channel=False)))
    assert float(frequency_bound(jr.Rod3D(rod, 6, gravity=False))) == pytest.approx(free, rel=1e-14)
    assert float(frequency_bound(jr.Rod3D(rod, 6, channel=False))) == pytest.approx(free, rel=1e-14)
    assert float(frequency_bound(jr.Rod3D(rod, 6))) > free * (1 + 1e-4)


def test_a_3d_friction_pass_of_zero_length_keeps_the_stuck_flags_and_the_trial_records(rod3d_state):
    """At rest on the bottom with a small lateral trial velocity: a pass of h > 0 holds the nodes
    (static friction) and records its force; a pass of h = 0 changes neither flags nor records."""
    model, q, v = rod3d_state
    a = model.accelerations(q, v)
    moving = eqx.tree_at(lambda s: (s.v, s.stuck, s.force, s.residual, s.sweeps), v,
                         (v.v.at[1:-1, 1].set(1e-6), jnp.zeros_like(v.stuck), v.force + 7.0,
                          jnp.asarray(0.25, v.residual.dtype), jnp.asarray(9, v.sweeps.dtype)))
    law = jr.Coulomb()
    held = model.friction_update(law, moving, moving, 1e-4, 0.0, q, a)
    assert bool(jnp.any(held.stuck)) and not bool(jnp.all(held.force == moving.force))
    same = model.friction_update(law, moving, moving, 0.0, 0.0, q, a)
    assert not bool(jnp.any(same.stuck))
    np.testing.assert_array_equal(same.force, moving.force)
    assert float(same.residual) == 0.25 and int(same.sweeps) == 9


def test_a_sweeps_metadata_writes_numpy_scalars_and_paths_as_text(tmp_path):
    """A user's NumPy seed or a path object in a sweep's metadata is written (as its text), not
    a TypeError after the members have run."""
    import json
    import pathlib

    from jaxrod.sweeps.store import _dump_json

    _dump_json({"seed": np.int64(3), "out": pathlib.Path("a/b"), "mu": 0.3}, tmp_path / "meta.json")
    assert json.loads((tmp_path / "meta.json").read_text()) == {"seed": "3", "out": "a/b", "mu": 0.3}


def test_a_run_announces_its_compilation_once_per_model_and_integrator(monkeypatch):
    """The announcement before a run's first compiled call is keyed by the model's and the
    integrator's types, the size, the saves and the state's structure: the same field model with
    another integrator is another program and is announced again."""
    import importlib

    from jaxrod.integrators import progress

    sim = importlib.import_module("jaxrod.simulate")  # the module (`jaxrod.simulate` is also the function)
    said = []
    monkeypatch.setattr(progress, "compiling", lambda what, key: said.append((what, key)))

    class _Stop(Exception):
        pass

    def start(*a):
        raise _Stop

    monkeypatch.setattr(sim, "_start", start)
    s = jr.Scene(jr.RodChannel.reference(0.3), 5.0, jr.SineVelocity(0.08, 6.0), "field", n=16)
    q0, v0 = s.initial_state()
    for integ in (jr.ProjectedVerlet(1e-5), jr.ProjectedLeapfrog(1e-5)):
        with pytest.raises(_Stop):
            jr.simulate(s.model(), integ, q0, v0, 0.1, n_save=5, options=jr.RunOptions(progress=True))
    (w1, k1), (w2, k2) = said
    assert w1 == "FieldModel (16 nodes) with ProjectedVerlet" and w2 == "FieldModel (16 nodes) with ProjectedLeapfrog"
    assert k1 != k2 and k1[0] is k2[0] and k1[2:] == k2[2:]


def test_the_3d_rods_viscous_damping_removes_c_m_v2_per_second():
    """A half step without friction (v_after = v_trial = v_prev = u) of a rod with
    mass-proportional damping c loses c Σ m |u|² h [J], counted per node and component."""
    model = jr.Rod3D(jr.RodChannel.reference(0.3), 6, damping=50.0)
    q, v = model.initial_state(0.0)
    u = jnp.zeros((7, 3)).at[1:-1, 1].set(2e-3).at[1:-1, 0].set(-1e-3)
    moving = eqx.tree_at(lambda s: s.v, v, u)
    a = model.accelerations(q, moving)
    h = 1e-5
    lost, work_in = model.impulse_work(moving, moving, moving, a, h)
    expected = 50.0 * np.asarray(model.mass)[:, None] * np.asarray(u) ** 2 * h
    np.testing.assert_allclose(np.asarray(lost[0]), expected, rtol=1e-12, atol=1e-30)
    assert float(jnp.sum(lost[1])) == 0.0 and float(work_in) == 0.0  # no spin; a dead load does no work here


def test_the_3d_friction_pass_sweeps_until_converged_up_to_its_largest_count():
    """Nodes sliding every which way on the bottom, held within a step of 1 ms: one sweep leaves
    a large residual; up to 64 sweeps run until the residual is below `friction_tol` and record
    how many they took."""
    out = {}
    for sweeps in (1, 64):
        model = jr.Rod3D(jr.RodChannel.reference(0.3), 6, friction_sweeps=sweeps)
        q, v = model.initial_state(0.0)
        u = v.v.at[1:-1, 1].set(jnp.array([1e-3, -2e-3, 3e-3, -1e-3, 2e-3])).at[1:-1, 0].set(1e-3)
        moving = eqx.tree_at(lambda s: (s.v, s.stuck), v, (u, jnp.zeros_like(v.stuck)))
        out[sweeps] = model.friction_update(jr.Coulomb(), moving, moving, 1e-3, 0.0, q, model.accelerations(q, v))
    assert int(out[1].sweeps) == 1 and float(out[1].residual) > 0.1
    assert 1 < int(out[64].sweeps) < 64 and float(out[64].residual) <= float(model.friction_tol)


# ------------------------------------------------------------------ θ(s) of every model's state


@pytest.mark.parametrize("kind, size", [("mode", None), ("galerkin", 12), ("field", 23)])
def test_every_reduced_model_draws_its_state_as_theta_of_s(kind, size):
    """`field_of(q)` is (s, θ(s)): for the mode-6 state of amplitude A = 0.02 rad (one modal
    amplitude, or the nodes' values of A sin(6πs/L)), θ = A sin(6πs/L) at every point it returns
    (inside [0, L]), for a batch of states too."""
    rod = jr.RodChannel.reference(0.3)
    scene = jr.Scene(rod, 5.0, jr.SineVelocity(0.01, 6.0), kind, n=size)
    model, recipe = scene.model(), scene.recipe
    L, A = float(rod.L), 0.02
    if kind == "mode":
        q = jnp.asarray(A)
    elif kind == "galerkin":
        q = jnp.zeros(size).at[5].set(A)
    else:
        q = A * jnp.sin(6 * jnp.pi * jnp.arange(1.0, size + 1) / (size + 1))
    s, th = (np.asarray(a) for a in recipe.field_of(model, q))
    assert s.ndim == 1 and th.shape == s.shape
    assert s.size >= size if size else s.size > 100  # the nodes or quadrature points; 129 points for one mode
    assert 0.0 <= s.min() and s.max() <= L and np.all(np.diff(s) > 0)
    np.testing.assert_allclose(th, A * np.sin(6 * np.pi * s / L), atol=1e-12)
    _, both = recipe.field_of(model, jnp.stack([q, 2 * q]))
    np.testing.assert_allclose(np.asarray(both), [th, 2 * th], atol=1e-12)


def test_the_3d_rod_draws_its_state_as_its_nodes_wall_angles(rod3d_state):
    from jaxrod.rod3d import Rod3DRecipe

    model, q, v = rod3d_state
    off = 0.5 * float(model.rod.R) * jnp.sin(jnp.pi * jnp.arange(7.0) / 6)
    q2, _ = model.initial_state(0.0, lateral_offset=off)
    s, th = Rod3DRecipe().field_of(model, q2)
    np.testing.assert_allclose(np.asarray(s), np.linspace(0.0, float(model.rod.L), 7), atol=1e-15)
    np.testing.assert_array_equal(np.asarray(th), np.asarray(model.theta(q2.x)))
    assert float(jnp.max(jnp.abs(th))) > 0.1


# ------------------------------------------------------------------ small pieces of the models


def test_the_field_models_frictionless_loads_are_p5_with_the_discrete_wavenumbers():
    """F⁰_m = EI κ_m² + w/(R κ_m²) with κ_m² = (4/h²) sin²(mπ/(2(n+1))), h = L/(n+1): the continuous
    F⁰_m = EI (mπ/L)² + w L²/(R m²π²) as the nodes refine (second order in h)."""
    from jaxrod import theory

    rod = jr.RodChannel.reference(0.3)
    EI, w, R, L = (float(x) for x in (rod.EI, rod.w, rod.R, rod.L))
    errs = []
    for n in (31, 63):
        got = np.asarray(jr.FieldModel.from_rod(rod, n, F=5.0).frictionless_loads())
        h = L / (n + 1)
        k2 = 4 / h**2 * np.sin(np.arange(1, n + 1) * np.pi / (2 * (n + 1))) ** 2
        np.testing.assert_allclose(got, EI * k2 + w / (R * k2), rtol=1e-13)
        errs.append(got[5] / float(theory.frictionless_load(rod, 6)) - 1)
    assert abs(errs[1]) < abs(errs[0]) / 3.5 and abs(errs[1]) < 2e-3


def test_a_lateral_force_adds_its_acceleration_and_two_add_up():
    """`under_lateral_force(f)` adds f/(ρR) to every node's angular acceleration; a second force adds
    to the first; the tangent model keeps them."""
    rod = jr.RodChannel.reference(0.3)
    m = jr.FieldModel.from_rod(rod, 9, F=5.0)
    q, v = 0.01 * jnp.sin(jnp.arange(1.0, 10.0)), jnp.zeros(9)
    base = np.asarray(m.accelerations(q, v, 0.0))
    f, g = jnp.full(9, 0.2), jnp.linspace(-0.1, 0.1, 9)
    rhoR = float(rod.rho * rod.R)
    one = m.under_lateral_force(f)
    two = one.under_lateral_force(g)
    np.testing.assert_allclose(np.asarray(one.accelerations(q, v, 0.0)), base + 0.2 / rhoR, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(two.accelerations(q, v, 0.0)), base + np.asarray(f + g) / rhoR, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(two.acceleration(q, 0.0)), np.asarray(m.acceleration(q, 0.0)) + np.asarray(f + g) / rhoR,
                               rtol=1e-12)
    np.testing.assert_allclose(np.asarray(two.for_tangents().accelerations(q, v, 0.0)),
                               np.asarray(two.accelerations(q, v, 0.0)), rtol=0)
    assert two.rod is m.rod


def _as_subclass(cls, model):
    """`model` (an equinox module) rebuilt as its subclass `cls`, field by field: a user's variant."""
    import dataclasses

    return cls(**{f.name: getattr(model, f.name) for f in dataclasses.fields(model) if f.init})


def test_a_lateral_force_keeps_the_velocities_a_users_model_reads():
    """A user's per-node model whose accelerations read the velocities (here viscous damping, −3v)
    keeps them under a lateral force: its own accelerations at (q, v) plus the force's."""
    class Damped(jr.FieldModel):
        def accelerations(self, q, v, t):
            return super().accelerations(q, v, t) - 3.0 * v

    rod = jr.RodChannel.reference(0.3)
    base = jr.FieldModel.from_rod(rod, 8, F=2.0)
    m = _as_subclass(Damped, base)
    q, v = 0.01 * jnp.arange(8.0), jnp.linspace(-0.02, 0.02, 8)
    f = jnp.linspace(0.1, 0.8, 8)
    forced = m.under_lateral_force(f).accelerations(q, v, 0.0)
    expected = np.asarray(base.accelerations(q, v, 0.0)) - 3.0 * np.asarray(v) + np.asarray(f) / float(rod.rho * rod.R)
    np.testing.assert_allclose(np.asarray(forced), expected, rtol=1e-12)


def test_the_projected_verlet_step_hands_friction_the_position_and_forces_of_each_half_step():
    """A user's model may make its friction depend on where the rod is: `ProjectedVerlet.step` hands
    `friction_update` the position and accelerations the friction acts at — the step's start for the
    first half kick, its end (the position and accelerations it returns) for the second."""
    seen = []

    class Recorded(jr.FieldModel):
        def friction_update(self, friction, v_trial, v_prev, h, t, q=None, a=None):
            seen.append((q, a))
            return super().friction_update(friction, v_trial, v_prev, h, t, q, a)

    base = jr.FieldModel.from_rod(jr.RodChannel.reference(0.3), 8, F=2.0)
    m = _as_subclass(Recorded, base)
    q, v = 0.01 * jnp.sin(jnp.arange(1.0, 9.0)), jnp.linspace(-1.0, 1.0, 8)  # sliding [rad/s]
    a = m.accelerations(q, v, 0.0)
    q1, _, a1, _ = jr.integrators.ProjectedVerlet(dt=1e-4).step(m, q, v, a, 0.0, 1e-4)
    assert len(seen) == 2
    assert seen[0][0] is q and seen[0][1] is a
    np.testing.assert_array_equal(np.asarray(seen[1][0]), np.asarray(q1))
    np.testing.assert_array_equal(np.asarray(seen[1][1]), np.asarray(a1))
    assert not np.array_equal(np.asarray(q1), np.asarray(q))


def test_the_3d_rods_tangent_model_runs_its_friction_pass_in_float64_and_is_otherwise_the_same(rod3d_state):
    model, _, _ = rod3d_state
    t = model.for_tangents()
    assert t.friction_precision == "float64" and model.friction_precision != "float64"
    for a, b in zip(jax.tree_util.tree_leaves(model), jax.tree_util.tree_leaves(t)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_the_scheme_of_a_scene_is_its_models_choice_under_the_perturbation():
    from jaxrod.rod3d import Rod3DRecipe
    from jaxrod.scene import scheme_for

    sine = jr.SineVelocity(0.01, 6.0)
    assert scheme_for("rod3d", sine) == Rod3DRecipe().scheme_under(sine) is None
    assert scheme_for("field", sine) is None and scheme_for("mode", sine) is None
    noise = jr.RandomVelocity(0.015, jax.random.key(0))
    assert scheme_for("rod3d", noise) == Rod3DRecipe().scheme_under(noise) == "leapfrog"


@pytest.mark.parametrize("module", ["jaxrod", "jaxrod.integrators"])
def test_the_smooth_integrator_is_imported_on_first_use_and_other_names_are_refused(module):
    import importlib

    from jaxrod.integrators.smooth import DiffraxSmooth

    mod = importlib.import_module(module)
    assert mod.DiffraxSmooth is DiffraxSmooth
    with pytest.raises(AttributeError, match=rf"^module '{module}' has no attribute 'Nope'$"):
        getattr(mod, "Nope")


def test_the_default_step_is_the_schemes_own():
    """An explicit scheme's default step is half its stability limit; asking another scheme by
    name gives that scheme's."""
    from jaxrod.integrators import default_step

    m = jr.FieldModel.from_rod(jr.RodChannel.reference(0.3), 15, F=5.0)
    limit = 2.0 / float(m.max_frequency())
    assert default_step(m) == pytest.approx(0.5 * limit, rel=1e-12)
    assert default_step(m, scheme="leapfrog") == pytest.approx(jr.ProjectedLeapfrog.default_step(m, None), rel=1e-15)


def test_vector_components_subtract_componentwise():
    from jaxrod.rod3d.components import add, sub

    assert sub((1.0, 2.0, 3.0), (0.5, 4.0, -1.0)) == (0.5, -2.0, 4.0)
    assert add(sub((1.0, 2.0, 3.0), (0.5, 4.0, -1.0)), (0.5, 4.0, -1.0)) == (1.0, 2.0, 3.0)


def test_the_3d_friction_pass_counts_exactly_the_kinetic_energy_it_removes():
    """From a trial velocity (no kick before it: v_prev = v_trial), the friction pass's counted loss,
    translational and rotational, is the drop of the kinetic energy, ½m|v|² + ½J|ω|², exactly:
    sliding nodes on the bottom, spinning and translating, held or slowed by the contact's friction."""
    model = jr.Rod3D(jr.RodChannel.reference(0.3), 6)
    q, v = model.initial_state(0.0)
    u = v.v.at[1:-1, 1].set(jnp.array([1e-3, -2e-3, 3e-3, -1e-3, 2e-3])).at[1:-1, 0].set(1e-3)
    w = v.w.at[:, 0].set(jnp.linspace(-0.5, 0.5, 6))
    trial = eqx.tree_at(lambda s: (s.v, s.w, s.stuck), v, (u, w, jnp.zeros_like(v.stuck)))
    a = model.accelerations(q, trial)
    after = model.friction_update(jr.Coulomb(), trial, trial, 1e-3, 0.0, q, a)
    lost, _ = model.impulse_work(trial, trial, after, a, 1e-3)
    ke = lambda s: float(model.kinetic_energy(s))
    drop = ke(trial) - ke(after)
    assert drop > 0 and float(jnp.sum(lost[1])) != 0.0  # the spins changed too
    assert float(jnp.sum(lost[0]) + jnp.sum(lost[1])) == pytest.approx(drop, rel=1e-10)


def test_the_3d_rods_energy_terms_are_named_by_kind(rod3d_state):
    model, q, v = rod3d_state
    assert set(model.energy_terms(q, v)) == {"kinetic", "rotational", "stretch", "shear", "bend", "twist", "gravity",
                                            "contact"}


@pytest.mark.parametrize("n", range(1, 10))
def test_the_red_black_halves_are_as_long_as_the_even_nodes(n):
    """n + 1 nodes split into the even (red) and odd (black) ones, both padded to the red count."""
    from jaxrod.rod3d.contact import _split, colours

    M = colours(n)
    assert M == len(range(0, n + 1, 2))
    red, black = _split(jnp.arange(n + 1.0), M, fill=-1)
    np.testing.assert_array_equal(red, np.arange(0, n + 1, 2))
    np.testing.assert_array_equal(black, np.r_[np.arange(1, n + 1, 2), [-1] * (M - len(range(1, n + 1, 2)))])


def test_an_auxetic_rods_step_bound_is_its_torsional_frequency():
    """For ν = −0.8 the shear modulus G = E/(2(1 + ν)) = 2.5 E exceeds E: the highest frequency of a
    free rod segment is torsional, ω² = 4 GJ/(l₀ J_a) with J_a = ρ l₀ πd⁴/32 its polar inertia, so
    ω = 2√(G/ρ)/l₀ (above the axial 2√(E/ρ)/l₀)."""
    from jaxrod.rod3d.stiffness import frequency_bound

    rod = jr.RodChannel.reference(0.3, nu=-0.8)
    n = 6
    l0 = float(rod.L) / n
    E, rho = float(rod.E), float(rod.rho_v)
    G = E / (2 * (1 - 0.8))
    got = float(frequency_bound(jr.Rod3D(rod, n, gravity=False, channel=False)))
    assert got == pytest.approx(2 * math.sqrt(G / rho) / l0, rel=1e-12)
    assert got > 2 * math.sqrt(E / rho) / l0 * 1.5


def test_the_pushed_end_of_the_3d_rod_does_the_work_of_its_reaction_times_its_speed():
    """Displacement control: the rod compressed by 2 N, its end pushed in at 1 mm/s; in a step of
    h the driven end puts h × (the reaction the load cell reads) × (its speed) into the rod [J]."""
    model = jr.Rod3D(jr.RodChannel.reference(0.3), 6, control="displacement", speed=1e-3)
    q, v = model.initial_state(2.0)
    a = model.accelerations(q, v, 0.0)
    reaction = float(model.observables(q, v, a, 0.0)["reaction"][1])
    assert reaction == pytest.approx(2.0, rel=1e-9) and float(v.v[-1, 0]) == -1e-3
    _, work_in = model.impulse_work(v, v, v, a, 1e-5)
    assert float(work_in) == pytest.approx(1e-5 * reaction * 1e-3, rel=1e-12)


def test_a_3d_rod_without_a_channel_starts_on_the_axis_and_one_in_a_channel_on_its_bottom():
    """Straight states: without a channel the nodes lie on the x axis (z = 0); in the channel
    the rod rests on the bottom wall, z = −(R + its sag into the wall under its weight)."""
    rod = jr.RodChannel.reference(0.3)
    free = jr.Rod3D(rod, 6, channel=False, gravity=False, control="force")
    q, _ = free.initial_state(0.0)
    assert not np.asarray(q.x[:, 1:]).any()
    held = jr.Rod3D(rod, 6)
    q, _ = held.initial_state(0.0)
    np.testing.assert_allclose(np.asarray(q.x[:, 2]), -(float(rod.R) + float(held.static_sag())), rtol=1e-12)
    assert float(held.static_sag()) > 0


def test_a_step_past_the_limit_is_flagged_unless_the_caller_checked_it():
    """`integrate` at 1.5× the stability limit (a few steps, still finite): the result code is
    `step_limit`; with `check_step_limit=False` (the caller checked the concrete model) it is not."""
    from jaxrod.perturbations import SineVelocity

    s = jr.Scene(jr.RodChannel.reference(0.3), 2.0, SineVelocity(1e-3), kind="field", n=16)
    model, (q0, v0) = s.model(), s.initial_state()
    limit = float(jr.ProjectedVerlet(1.0).step_limit(model))
    integ = jr.ProjectedVerlet(1.5 * limit)
    codes = [int(integ.integrate(model, q0, v0, 3 * limit, 2, jr.RunOptions(), check_step_limit=c).result)
             for c in (True, False)]
    assert codes == [int(jr.RESULTS.step_limit), int(jr.RESULTS.successful)]


def test_bisection_halves_in_log_space_unless_told_otherwise():
    """`jaxrod.boundary.roots.bisection` on a label: one halving of [0.1, 10] takes the geometric
    midpoint 1 by default and the arithmetic one 5.05 with `geometric=False`."""
    from jaxrod.boundary.roots import bisection

    r = bisection(lambda x: x > 0.5, 0.1, 10.0, rtol=0.0, max_iter=1)
    assert (float(r.lo), float(r.hi)) == (0.1, pytest.approx(1.0, rel=1e-15))
    r = bisection(lambda x: x > 0.5, 0.1, 10.0, rtol=0.0, max_iter=1, geometric=False)
    assert (float(r.lo), float(r.hi)) == (0.1, pytest.approx(5.05, rel=1e-15))


def test_a_ramp_load_by_hand_before_during_and_after_its_ramp():
    """`RampLoad(10, 20, t_start=1, t_end=3)`: 10 N until 1 s, linear to 20 N at 3 s, then held;
    a ramp of zero length is a step at its time (the start value at it, the end value after)."""
    ramp = jr.RampLoad(10.0, 20.0, 1.0, 3.0)
    ts = jnp.array([0.0, 1.0, 1.5, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(jax.vmap(ramp)(ts), [10.0, 10.0, 12.5, 15.0, 20.0, 20.0], rtol=1e-15)
    step = jr.RampLoad(10.0, 20.0, 2.0, 2.0)
    np.testing.assert_array_equal(jax.vmap(step)(jnp.array([1.0, 2.0, 2.5])), [10.0, 10.0, 20.0])
    assert [float(x) for x in ramp.extremes()] == [10.0, 20.0]


@pytest.mark.parametrize("kind", ["random-velocity", "random-position", "random-shape"])
def test_a_random_perturbation_made_without_a_key_is_the_one_of_key_0(kind):
    """`make_perturbation` documents `key` as defaulting to `jax.random.key(0)`: the perturbation
    made without one is that one, and not another key's."""
    from jaxrod.registry import make_perturbation

    def leaves(p):
        return [np.asarray(jax.random.key_data(x) if jnp.issubdtype(x.dtype, jax.dtypes.prng_key) else x)
                for x in jax.tree_util.tree_leaves(p)]

    default, zero, one = (leaves(make_perturbation(kind, 0.01, **kw))
                          for kw in ({}, {"key": jax.random.key(0)}, {"key": jax.random.key(1)}))
    assert all(np.array_equal(a, b) for a, b in zip(default, zero, strict=True))
    assert not all(np.array_equal(a, b) for a, b in zip(default, one, strict=True))


def test_the_far_load_does_work_on_the_far_end_node_alone():
    """`external_energy` of a rod against the far load F_far (a dead load on node 0 along +x, into
    the rod: potential −F_far·x₀): moving the far end axially by d changes it by −F_far·d; moving
    the next node axially changes nothing (no gravity or body force along the axis)."""
    from jaxrod.rod3d import Rod3D
    from jaxrod.rod3d.energy import external_energy

    model = Rod3D(jr.RodChannel.reference(0.3), 4, control="displacement", speed=1e-3, far_load=2.0, ends="pinned")
    q, _ = model.initial_state(0.0)
    E0 = float(external_energy(model, q.x))
    far = float(external_energy(model, q.x.at[0, 0].add(1e-3))) - E0
    next_node = float(external_energy(model, q.x.at[1, 0].add(1e-3))) - E0
    assert far == pytest.approx(-2.0 * 1e-3, rel=1e-9)
    assert abs(next_node) < 1e-12


# ------------------------------------------------------------------ a sweep's members from its inputs


def test_a_sweeps_inputs_expand_to_members_by_grid_or_zip():
    """`grid`: every combination, the first input varying slowest (its shape is the inputs' lengths
    in order); `zip`: members side by side, length-1 inputs repeated, scalars alone make one member.
    Every value becomes a float (integers included)."""
    from jaxrod.sweeps.run import _expand

    flat, shape, names = _expand({"dF": [1, 2, 3], "amplitude": [0.1, 0.2]}, "grid")
    assert shape == (3, 2) and names == ("dF", "amplitude")
    assert flat["dF"].tolist() == [1.0, 1.0, 2.0, 2.0, 3.0, 3.0]
    assert flat["amplitude"].tolist() == [0.1, 0.2] * 3
    assert flat["dF"].dtype == np.float64
    flat, shape, _ = _expand({"dF": 5, "amplitude": 0.1}, "zip")
    assert shape == (1,) and {k: a.tolist() for k, a in flat.items()} == {"dF": [5.0], "amplitude": [0.1]}
    flat, shape, _ = _expand({"dF": [1.0, 2.0, 3.0], "mu": 0.3, "amplitude": [0.2]}, "zip")
    assert shape == (3,) and flat["mu"].tolist() == [0.3] * 3 and flat["amplitude"].tolist() == [0.2] * 3
    flat["mu"][0] = 9.0  # each input is its own array, not a view of the broadcast one
    assert flat["mu"].tolist() == [9.0, 0.3, 0.3]


# ------------------------------------------------------------------ the boundary searches' settings


def test_each_model_and_perturbation_gets_its_documented_search_method():
    """Newton on the exact solution for the single mode under a sine velocity, whatever was asked;
    otherwise the asked method, by default the departure rate for the reduced models and label
    bisection for the 3D rod and for the single mode under a random perturbation. Anything else
    is refused, naming the argument."""
    from jaxrod.boundary.search import _method_of

    for p in ("sine", "random-position", "random-velocity", "random-shape"):
        assert _method_of(None, "field", p) == _method_of(None, "galerkin", p) == "departure"
        assert _method_of(None, "rod3d", p) == "bisection"
        assert _method_of("departure", "rod3d", p) == "departure"
        assert _method_of("bisection", "field", p) == "bisection"
        assert _method_of("bisection", "mode", p) == ("exact" if p == "sine" else "bisection")
    assert _method_of(None, "mode", "random-position") == "bisection"
    assert _method_of("departure", "mode", "random-shape") == "departure"
    with pytest.raises(ValueError, match=r"^method = 'newton' is invalid: expected one of \('departure', 'bisection'\)"):
        _method_of("newton", "field", "sine")


def test_a_searched_rods_parameters_keep_its_static_excess_over_the_dynamic_coefficient():
    """The searches see a rod as flat parameters with μ_d = `mu` and μ_s = `mu` + `mu_excess`:
    back from them it is the same rod, and moving `mu` moves both coefficients together."""
    from jaxrod.boundary.search import _params_of, _rod_of

    rod = jr.RodChannel.reference(0.3).with_friction(0.5, 0.3)
    p = _params_of(rod, dF=4.0)
    assert float(p["mu"]) == 0.3 and float(p["mu_excess"]) == pytest.approx(0.2, rel=1e-12) and p["dF"] == 4.0
    back = _rod_of(type(rod), p)
    for f in ("L", "d", "E", "rho_v", "nu", "R", "g", "mu_s", "mu_d"):
        assert float(getattr(back, f)) == pytest.approx(float(getattr(rod, f)), rel=1e-15), f
    moved = _rod_of(type(rod), {**p, "mu": 0.4})
    assert (float(moved.mu_d), float(moved.mu_s)) == pytest.approx((0.4, 0.6), rel=1e-12)


def test_a_physical_number_given_as_an_int_is_a_float_leaf_and_an_unknown_result_code_is_named():
    from jaxrod._numerics import float_leaf
    from jaxrod._results import RESULTS

    for x in (3, [1, 2], np.int32(7), True, 2.5):
        assert float_leaf(x).dtype == jnp.dtype("float64")
        assert not float_leaf(x).weak_type  # a Python number does not follow another operand's precision
    assert float_leaf(jnp.ones(2, jnp.float32)).dtype == jnp.dtype("float32")  # a floating array keeps its dtype
    for module in ("params", "perturbations", "scene", "loads", "theory", "models.single_mode", "lockup.closed_forms"):
        source = inspect.getsource(importlib.import_module(f"jaxrod.{module}"))
        assert "isinstance(x, (int, float))" not in source, f"jaxrod.{module} writes its own float converter"
    assert RESULTS.describe(99) == "unknown result code 99"
    assert RESULTS.describe(jnp.asarray(RESULTS.successful)) == RESULTS.messages[RESULTS.successful]
