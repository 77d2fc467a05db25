"""Bad input gets one clear line naming the argument, its value and the valid range.

Each case triggers a validation error with a cheap call (the check runs before any work) and
compares the WHOLE message with the one the input calls for, so that a changed word, value or
bound in a message fails here, not only a changed exception type."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import distributed, model_choice, registry, theory, worst_case
from jaxrod.integrators import ImplicitLeapfrog, ProjectedLeapfrog, ProjectedVerlet, default_step
from jaxrod.integrators.exact import Exact
from jaxrod.integrators.explicit import SplitLinearFriction, SymplecticEuler
from jaxrod.lockup import closed_forms, laws, push, staircase, verdict
from jaxrod.models.field import FieldModel, FieldRecipe
from jaxrod.models.galerkin import GalerkinModel
from jaxrod.models.single_mode import SingleMode
from jaxrod.perturbations import UserState, scene_noise
from jaxrod.registry import make_perturbation
from jaxrod.reproduce import reproduce
from jaxrod.rod3d import Rod3D
from jaxrod.scene import Scene
from jaxrod.simulate import simulate
from jaxrod.sweeps.run import sweep
from jaxrod.sweeps.spec import PARAMETERS, ROD_FIELDS, SweepSpec


def _rod(**kw):
    return jr.RodChannel.reference(**kw)


def _field(n=8):
    return FieldModel.from_rod(_rod(), n, dF=0.0)


def _raises_exactly(exc, call, expected):
    """`call()` raises `exc` with exactly the one-line message `expected`."""
    assert "\n" not in expected
    with pytest.raises(exc, match="^" + re.escape(expected) + "$") as info:
        call()
    assert "\n" not in str(info.value)


REF_FIELDS = "['E', 'L', 'R', 'd', 'g', 'mu_d', 'mu_s', 'nu', 'rho_v']"

PARAMS = {
    "L-negative": (lambda: _rod(L=-1.0), "RodChannel.L = -1.0 m is invalid: it must be finite and > 0."),
    "d-zero": (lambda: _rod(d=0.0), "RodChannel.d = 0.0 m is invalid: it must be finite and > 0."),
    "E-inf": (lambda: _rod(E=np.inf), "RodChannel.E = inf Pa is invalid: it must be finite and > 0."),
    "rho_v-negative": (lambda: _rod(rho_v=-2.0),
                       "RodChannel.rho_v = -2.0 kg/m^3 is invalid: it must be finite and > 0."),
    "R-nan": (lambda: _rod(R=np.nan), "RodChannel.R = nan m is invalid: it must be finite and > 0."),
    "g-zero": (lambda: _rod(g=0.0), "RodChannel.g = 0.0 m/s^2 is invalid: it must be finite and > 0."),
    "L-array-one-bad": (lambda: _rod(L=np.array([1.0, -1.0])),
                        "RodChannel.L = [ 1. -1.] m is invalid: it must be finite and > 0."),
    "nu-at-upper-bound": (lambda: _rod(nu=0.5),
                          "RodChannel.nu = 0.5 is invalid: Poisson's ratio must lie in (-1, 0.5)."),
    "nu-at-lower-bound": (lambda: _rod(nu=-1.0),
                          "RodChannel.nu = -1.0 is invalid: Poisson's ratio must lie in (-1, 0.5)."),
    "mu_s-negative": (lambda: _rod(mu=-0.1),
                      "RodChannel.mu_s = -0.1 is invalid: a friction coefficient must be finite and >= 0."),
    "mu_d-negative": (lambda: _rod(mu_d=-0.1),
                      "RodChannel.mu_d = -0.1 is invalid: a friction coefficient must be finite and >= 0."),
    "mu_d-above-mu_s": (lambda: _rod(mu=0.25, mu_d=0.5),
                        "RodChannel.mu_d = 0.5 is invalid: the dynamic coefficient must lie in [0, mu_s] "
                        "with mu_s = 0.25."),
    "reference-unknown-field": (lambda: _rod(foo=1.0, bar=2.0),
                                "RodChannel.reference got unknown field(s) ['bar', 'foo']; valid fields are "
                                + REF_FIELDS + "."),
}


@pytest.mark.parametrize("call, expected", PARAMS.values(), ids=PARAMS.keys())
def test_rod_channel_rejects_each_bad_field_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


SCENE = {
    "mode-zero": (lambda: Scene(_rod(), 0.0, mode=0), "mode = 0 is invalid: expected an int >= 1."),
    "field-n-below-4": (lambda: Scene(_rod(), 0.0, kind="field", n=3),
                        "n = 3 is invalid for the field model: expected an int >= 4 (nodes)."),
    "galerkin-n-zero": (lambda: Scene(_rod(), 0.0, kind="galerkin", n=0),
                        "n = 0 is invalid for the galerkin model: expected an int >= 1 (modes)."),
    "dt-negative": (lambda: Scene(_rod(), 0.0, dt=-1e-3), "dt = -0.001 is invalid: expected a float > 0 [s]."),
    "kind-unknown": (lambda: Scene(_rod(), 0.0, kind="nope"),
                     None),  # filled in the test: the registered names
}


@pytest.mark.parametrize("call, expected", SCENE.values(), ids=SCENE.keys())
def test_scene_rejects_each_bad_setting_naming_it_its_value_and_range(call, expected):
    if expected is None:
        expected = f"model = 'nope' is invalid: expected one of {registry.model_names()}."
    _raises_exactly(ValueError, call, expected)


def test_registry_rejects_bad_names_and_classes_naming_them():
    class NotAModel:
        pass

    class NotARecipe(FieldRecipe):
        model_class = NotAModel

    _raises_exactly(ValueError, lambda: registry.register_model(" padded", FieldRecipe()),
                    "model name = ' padded' is invalid: expected a non-empty string without spaces.")
    _raises_exactly(ValueError, lambda: registry.register_perturbation("", UserState),
                    "perturbation name = '' is invalid: expected a non-empty string without spaces.")
    _raises_exactly(TypeError, lambda: registry.register_model("m", 3),
                    "model 'm': expected an AbstractRecipe instance (the model's recipe), got 3.")
    _raises_exactly(TypeError, lambda: registry.register_model("m", FieldModel),
                    "model 'm': FieldModel is a model class; register its recipe, an AbstractRecipe instance "
                    "(docs/extending.md).")
    _raises_exactly(TypeError, lambda: registry.register_model("m", NotARecipe()),
                    "model 'm': NotARecipe.model_class = NotAModel is not a subclass of jaxrod.AbstractModel.")
    _raises_exactly(TypeError, lambda: registry.register_perturbation("p", 3),
                    "perturbation 'p': expected a class, got 3.")
    _raises_exactly(TypeError, lambda: registry.register_perturbation("p", NotAModel),
                    "perturbation 'p': NotAModel is not a subclass of AbstractPerturbation.")
    _raises_exactly(ValueError, lambda: SweepSpec(model="nope"),
                    f"SweepSpec.model = 'nope' is invalid: expected one of {registry.model_names()}.")
    _raises_exactly(ValueError, lambda: registry.perturbation_class("nope"),
                    f"perturbation = 'nope' is invalid: expected one of {registry.perturbation_names()}.")
    _raises_exactly(ValueError, lambda: registry.name_of_model(NotAModel),
                    f"model class {NotAModel!r} is not registered.")
    assert "m" not in registry.model_names() and "p" not in registry.perturbation_names()


def test_perturbations_reject_a_bad_grid_integrator_or_settings_naming_them():
    s = jnp.linspace(0.0, 3.0, 5)
    _raises_exactly(ValueError, lambda: scene_noise(jax.random.PRNGKey(0), 1.0, s, 3.0, grid=1),
                    "grid = 1 is invalid: expected an int >= 2 (segments) or None.")
    force = make_perturbation("random-position", 1.0, 6, jax.random.PRNGKey(0))
    _raises_exactly(TypeError, lambda: force.initial_state(_field(), None),
                    "RandomForce needs the run's fixed-step integrator (e.g. ProjectedVerlet) to integrate its "
                    "forcing phase; got NoneType.")
    _raises_exactly(TypeError, lambda: UserState.from_settings(1.0, 6, None, 1e-3),
                    "UserState is given as a state, not from a scene's settings.")


MODELS = {
    "field-n_nodes": (lambda: FieldModel.from_rod(_rod(), 3, dF=0.0),
                      "FieldModel.n_nodes = 3 is invalid: expected an int >= 4."),
    "field-operator": (lambda: FieldModel.from_rod(_rod(), 8, dF=0.0, operator="fem"),
                       "FieldModel.operator = 'fem' is invalid: expected one of ('fd', 'spectral')."),
    "field-threshold": (lambda: FieldModel.from_rod(_rod(), 8, dF=0.0, threshold=0.0),
                        "FieldModel.threshold = 0.0 is invalid: expected > 0 rad."),
    "field-no-load": (lambda: FieldModel.from_rod(_rod(), 8),
                      "FieldModel.from_rod needs exactly one of F and dF."),
    "field-both-loads": (lambda: FieldModel.from_rod(_rod(), 8, F=1.0, dF=0.0),
                         "FieldModel.from_rod needs exactly one of F and dF."),
    "galerkin-n_modes": (lambda: GalerkinModel.from_rod(_rod(), 0, dF=0.0),
                         "GalerkinModel.n_modes = 0 is invalid: expected an int >= 1."),
    "galerkin-n_quad": (lambda: GalerkinModel.from_rod(_rod(), 4, dF=0.0, n_quad=4),
                        "GalerkinModel.n_quad = 4 is invalid: expected an int > n_modes = 4."),
    "galerkin-no-load": (lambda: GalerkinModel.from_rod(_rod(), 4),
                         "GalerkinModel.from_rod needs exactly one of F and dF."),
    "single-k-nan": (lambda: SingleMode(k=np.nan, f_s=1.0, f_d=1.0),
                     "SingleMode.k = nan is invalid: it must be finite."),
    "single-f_s-negative": (lambda: SingleMode(k=1.0, f_s=-1.0, f_d=0.0),
                            "SingleMode.f_s = -1.0 is invalid: it must be finite and >= 0."),
    "single-f_d-inf": (lambda: SingleMode(k=1.0, f_s=1.0, f_d=np.inf),
                       "SingleMode.f_d = inf is invalid: it must be finite and >= 0."),
    "single-f_d-above-f_s": (lambda: SingleMode(k=1.0, f_s=1.0, f_d=2.0),
                             "SingleMode.f_d = 2.0 is invalid: it must lie in [0, f_s] with f_s = 1.0."),
    "single-no-load": (lambda: SingleMode.from_rod(_rod()),
                       "SingleMode.from_rod needs exactly one of F and dF."),
}


@pytest.mark.parametrize("call, expected", MODELS.values(), ids=MODELS.keys())
def test_models_reject_each_bad_argument_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


@pytest.mark.parametrize("make, size, smallest", [
    (lambda k: FieldModel.from_rod(_rod(), k, dF=0.0), lambda m: m.n_nodes, 4),
    (lambda k: GalerkinModel.from_rod(_rod(), k, dF=0.0), lambda m: m.n_modes, 1),
], ids=["field-nodes", "galerkin-modes"])
def test_models_accept_the_smallest_size_their_range_allows(make, size, smallest):
    """The edge of each range the messages above state is inside it: 4 nodes, 1 mode."""
    assert size(make(smallest)) == smallest


def test_models_without_sample_points_say_which_and_why():
    single = SingleMode(k=1.0, f_s=1.0, f_d=1.0)
    _raises_exactly(TypeError, single.sample_points,
                    "SingleMode takes no field perturbation: it has no sample points (for SingleMode use "
                    "jaxrod.perturbations.project_to_mode).")


INTEGRATORS = {
    "verlet-dt-zero": (lambda: ProjectedVerlet(0.0), "ProjectedVerlet.dt = 0.0 is invalid: expected a float > 0."),
    "leapfrog-dt-negative": (lambda: ProjectedLeapfrog(-1e-3),
                             "ProjectedLeapfrog.dt = -0.001 is invalid: expected a float > 0."),
    "verlet-dt-string": (lambda: ProjectedVerlet("1e-3"),
                         "ProjectedVerlet.dt = '1e-3' is invalid: expected a float > 0."),
    "implicit-beta": (lambda: ImplicitLeapfrog(1e-3, beta=1.5),
                      "ImplicitLeapfrog.beta = 1.5 is invalid: expected a float in [0, 1]."),
    "implicit-beta-negative": (lambda: ImplicitLeapfrog(1e-3, beta=-0.25),
                               "ImplicitLeapfrog.beta = -0.25 is invalid: expected a float in [0, 1]."),
    "implicit-gamma-negative": (lambda: ImplicitLeapfrog(1e-3, gamma=-0.1),
                                "ImplicitLeapfrog.gamma = -0.1 is invalid: expected a finite float >= 0."),
    "implicit-gamma-inf": (lambda: ImplicitLeapfrog(1e-3, gamma=float("inf")),
                           "ImplicitLeapfrog.gamma = inf is invalid: expected a finite float >= 0."),
    "euler-dt": (lambda: SymplecticEuler(0.0), "SymplecticEuler.dt = 0.0 is invalid: expected a float > 0."),
    "split-dt": (lambda: SplitLinearFriction(-1.0),
                 "SplitLinearFriction.dt = -1.0 is invalid: expected a float > 0."),
    "scheme-unknown": (lambda: default_step(_field(), scheme="rk4"),
                       "scheme = 'rk4' is invalid: expected one of ('leapfrog', 'verlet', 'implicit')."),
}


@pytest.mark.parametrize("call, expected", INTEGRATORS.values(), ids=INTEGRATORS.keys())
def test_integrators_reject_each_bad_setting_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


def test_integrators_name_the_model_they_cannot_run():
    m = _field()
    q = jnp.zeros(m.n_nodes)
    _raises_exactly(TypeError, lambda: ImplicitLeapfrog(1e-3).kick(m, q, q, q, 1e-3, 1e-3),
                    "ImplicitLeapfrog needs a model with implicit_kick; FieldModel has none (use "
                    "ProjectedLeapfrog or ProjectedVerlet).")
    _raises_exactly(TypeError, lambda: Exact().integrate(m, q, q, 1.0, 2),
                    "Exact integrates only SingleMode models, got FieldModel.")


SIMULATE = {
    "t1-zero": (dict(t1=0.0, n_save=2), "t1 = 0.0 is invalid: expected a finite float > 0 [s]."),
    "t1-inf": (dict(t1=float("inf"), n_save=2), "t1 = inf is invalid: expected a finite float > 0 [s]."),
    "n_save-one": (dict(t1=1.0, n_save=1), "n_save = 1 is invalid: expected an int >= 2."),
    "n_save-float": (dict(t1=1.0, n_save=2.0), "n_save = 2.0 is invalid: expected an int >= 2."),
}


@pytest.mark.parametrize("kw, expected", SIMULATE.values(), ids=SIMULATE.keys())
def test_simulate_rejects_a_bad_horizon_or_save_count_naming_it(kw, expected):
    m = _field()
    q = jnp.zeros(m.n_nodes)
    _raises_exactly(ValueError, lambda: simulate(m, ProjectedVerlet(1e-6), q, q, **kw), expected)


def test_simulate_rejects_a_step_above_the_stability_limit_naming_the_limit():
    m = _field()
    q = jnp.zeros(m.n_nodes)
    limit = float(np.min(np.asarray(ProjectedVerlet(1.0).step_limit(m))))
    expected = (f"ProjectedVerlet.dt = 1.0 s is above the stability limit 2/ω_max = {limit:.4g} s for this "
                "model; use a smaller dt.")
    _raises_exactly(ValueError, lambda: simulate(m, ProjectedVerlet(1.0), q, q, 1.0, n_save=2), expected)


CLOSED_FORMS = {
    "EI-negative": (lambda: closed_forms.force_unit(-1.0, 1.0, 1.0),
                    "EI = -1.0 N*m^2 is invalid: it must be finite and > 0."),
    "w-zero": (lambda: closed_forms.length_unit(1.0, 0.0, 1.0), "w = 0.0 N/m is invalid: it must be finite and > 0."),
    "r-inf": (lambda: closed_forms.force_unit(1.0, 1.0, np.inf), "r = inf m is invalid: it must be finite and > 0."),
    "F-zero": (lambda: closed_forms.helix_pitch(1.0, 0.0), "F = 0.0 N is invalid: it must be finite and > 0."),
    "EI-zero-pitch": (lambda: closed_forms.helix_pitch(0.0, 1.0), "EI = 0.0 N*m^2 is invalid: it must be finite and > 0."),
    "F-negative-wall": (lambda: closed_forms.helical_wall_force(-1.0, 1.0, 1.0, 1.0),
                        "F = -1.0 N is invalid: it must be finite and >= 0."),
    "f_in-nan": (lambda: closed_forms.transfer(np.nan, 1.0, 1.0, 0.0),
                 "f_in = nan is invalid: it must be not NaN and >= 0."),
    "x-negative": (lambda: closed_forms.transfer(1.0, -1.0, 1.0, 0.0),
                   "x = -1.0 is invalid: it must be finite and >= 0."),
    "variant": (lambda: closed_forms.helical_onset(1.0, 1.0, 1.0, "euler"),
                "variant = 'euler' is invalid: choose one of ['chen', 'wu_juvkam_wold']."),
    "law-both-zero": (lambda: closed_forms.transfer(1.0, 1.0, 0.0, 0.0),
                      "(a, b) = (0.0, 0.0) is invalid: the wall-force law w_c = w (a + b f²) needs finite a, b "
                      ">= 0, not both zero."),
    "law-negative": (lambda: closed_forms.transfer_length(1.0, 2.0, -1.0, 1.0),
                     "(a, b) = (-1.0, 1.0) is invalid: the wall-force law w_c = w (a + b f²) needs finite a, b "
                     ">= 0, not both zero."),
    "straight-w": (lambda: closed_forms.straight_transfer(1.0, 1.0, -1.0, 0.3),
                   "w = -1.0 N/m is invalid: it must be finite and > 0."),
}


@pytest.mark.parametrize("call, expected", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_lockup_closed_forms_reject_each_bad_argument_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


_N = np.linspace(0.0, 1.0, 10)
LOCKUP = {
    "laws-shapes": (lambda: laws.helix_against_laws(np.zeros(4), np.zeros(4), np.ones(4), 0.1, 1.0, 1.0, 0.1, 0.3, 1.0),
                    "theta, wall_force have shapes (4,), (4,): expected (5,) for 4 segments of axial_force."),
    "windows": (lambda: verdict.verdict(_N, _N, _N, criterion=verdict.Criterion(windows=1)),
                "Criterion.windows = 1 is invalid: expected an int >= 2."),
    "lock-slide": (lambda: verdict.verdict(_N, _N, _N, criterion=verdict.Criterion(lock=0.5, slide=0.5)),
                   "Criterion.lock, slide = 0.5, 0.5 are invalid: expected 0 <= lock < slide <= 1."),
    "settle": (lambda: verdict.verdict(_N, _N, _N, criterion=verdict.Criterion(settle=0.0)),
               "Criterion.settle = 0.0 is invalid: expected a finite float > 0."),
    "max_helix_angle": (lambda: verdict.verdict(_N, _N, _N, criterion=verdict.Criterion(max_helix_angle=float("inf"))),
                        "Criterion.max_helix_angle = inf is invalid: expected a finite float > 0."),
    "record-shapes": (lambda: verdict.verdict(_N, _N[:9], _N),
                      "push, far, f_in have shapes (10,), (9,), (10,): expected equal 1D records of at least 10 saves."),
    "push-still": (lambda: verdict.verdict(np.zeros(10), _N, _N),
                   "push goes from 0 to 0 m and does not advance: expected the entry's advance over a loading phase."),
    "push-back": (lambda: verdict.verdict(np.linspace(2e-3, 1e-3, 10), _N, _N),
                  "push goes from 0.002 to 0.001 m and does not advance: expected the entry's advance over a loading "
                  "phase."),
    "push_rod-mu_L": (lambda: push.push_rod(0.0, 0.1, 0.3),
                      "mu_L_over_ell = 0.0 is invalid: expected a finite number > 0."),
    "push_rod-r-slender": (lambda: push.push_rod(1.0, 0.5, 0.3),
                           "r_over_ell = 0.5 is invalid: expected 0 < r/ell < 0.5 (a slender helix)."),
    "push_rod-mu-nan": (lambda: push.push_rod(1.0, 0.1, float("nan")),
                        "mu = nan is invalid: expected a finite number > 0."),
    "push-F_max": (lambda: push.push(_rod(), 0.0, 1.0), "F_max = 0.0 N is invalid: expected a finite number > 0."),
    "push-rate": (lambda: push.push(_rod(), 1.0, -1.0), "rate = -1.0 N/s is invalid: expected a finite number > 0."),
    "inject-F_far": (lambda: push.inject(_rod(), -1.0, 1.0, 1.0),
                     "F_far = -1.0 N is invalid: expected a finite number >= 0."),
    "inject-speed": (lambda: push.inject(_rod(), 0.0, 0.0, 1.0),
                     "speed = 0.0 m/s is invalid: expected a finite number > 0."),
    "lanes-empty-mus": (lambda: push.inject_lanes(_rod(), [], [], 1.0, 1.0),
                        "mus = [] is invalid: expected a non-empty 1D array of friction "
                        "coefficients."),
    "lanes-far-load": (lambda: push.inject_lanes(_rod(), [0.3], [-1.0], 1.0, 1.0),
                       "far_loads[0] = -1.0 is invalid: expected a finite number >= 0."),
    "lanes-speed": (lambda: push.inject_lanes(_rod(), [0.3], [0.0], 0.0, 1.0),
                    "speed = 0.0 m/s is invalid: expected a finite number > 0."),
    "lanes-2d-mus": (lambda: push.inject_lanes(_rod(), [[0.3]], [0.0], 1.0, 1.0),
                     "mus = [[0.3]] is invalid: expected a non-empty 1D array of friction coefficients."),
    "lanes-cap": (lambda: push.inject_lanes(_rod(), [0.3], [0.0], 1.0, 1.0, n=8, cap=-2.0),
                  "cap = -2.0 is invalid: expected a finite number > 0."),
    "staircase-f_c": (lambda: staircase.staircase(_rod(), [0.3], [0.0], 1.0, f_c=0.0),
                      "f_c = 0.0 F0 is invalid: expected a finite number > 0."),
    "staircase-empty-mus": (lambda: staircase.staircase(_rod(), np.zeros((1, 2)), 0.0, 1.0),
                            "mus = [[0.0, 0.0]] is invalid: expected a non-empty 1D array of friction "
                            "coefficients."),
}


@pytest.mark.parametrize("call, expected", LOCKUP.values(), ids=LOCKUP.keys())
def test_lockup_drivers_reject_each_bad_argument_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


def _r3(**kw):
    return Rod3D(_rod(), 4, **kw)


ROD3D = {
    "n_segments": (lambda: Rod3D(_rod(), 3), "Rod3D.n_segments = 3 is invalid: expected an int >= 4."),
    "ends": (lambda: _r3(ends="hinged"),
             "Rod3D.ends = 'hinged' is invalid: expected one of ('pinned', 'fork', 'clamped', 'free')."),
    "control": (lambda: _r3(control="speed"),
                "Rod3D.control = 'speed' is invalid: expected one of ('force', 'load', 'displacement')."),
    "friction_at": (lambda: _r3(friction_at="wall"),
                    "Rod3D.friction_at = 'wall' is invalid: expected one of ('surface', 'axis')."),
    "friction_precision": (lambda: _r3(friction_precision="float16"),
                           "Rod3D.friction_precision = 'float16' is invalid: expected one of ('float32', 'float64')."),
    "far_load-under-force": (lambda: _r3(far_load=1.0),
                             "Rod3D.far_load is only for control='displacement' with held ends, not "
                             "control='force', ends='pinned'."),
    "far_load-free-ends": (lambda: _r3(far_load=1.0, control="displacement", ends="free"),
                           "Rod3D.far_load is only for control='displacement' with held ends, not "
                           "control='displacement', ends='free'."),
    "friction_sweeps": (lambda: _r3(friction_sweeps=0),
                        "Rod3D.friction_sweeps = 0 is invalid: expected an int >= 1."),
    "speed-nan": (lambda: _r3(speed=np.nan), "Rod3D.speed = nan m/s is invalid: it must be finite."),
    "damping-negative": (lambda: _r3(damping=-1.0),
                         "Rod3D.damping = -1.0 1/s is invalid: it must be finite and >= 0."),
    "contact_stiffness-zero": (lambda: _r3(contact_stiffness=0.0),
                               "Rod3D.contact_stiffness = 0.0 N/m^2.5 is invalid: it must be finite and > 0."),
    "rotary_scale-below-1": (lambda: _r3(rotary_scale=0.5),
                             "Rod3D.rotary_scale = 0.5 is invalid: it must be finite and >= 1."),
}


@pytest.mark.parametrize("call, expected", ROD3D.values(), ids=ROD3D.keys())
def test_rod3d_rejects_each_bad_argument_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


def test_rod3d_says_it_has_no_sample_points():
    _raises_exactly(TypeError, lambda: _r3().from_samples(jnp.zeros(5)),
                    "Rod3D has no coordinates per sample point: a lateral field becomes a state through "
                    "Rod3D.perturbed_state (UserState fields are not available with the 3D rod).")


SPEC = {
    "n-below-field-min": (lambda: SweepSpec(model="field", n=3),
                          "SweepSpec.n = 3 is invalid for model 'field': expected an int >= 4 nodes."),
    "n-zero-mode": (lambda: SweepSpec(model="mode", n=0),
                    "SweepSpec.n = 0 is invalid for model 'mode': expected an int >= 1."),
    "t1-zero": (lambda: SweepSpec(t1=0.0), "SweepSpec.t1 = 0.0 is invalid: expected > 0 s."),
    "rod-unknown": (lambda: SweepSpec(rod={"Q": 1.0}),
                    f"SweepSpec.rod has unknown field(s) ['Q']; valid: {ROD_FIELDS}."),
    "perturbation-unknown": (lambda: SweepSpec(perturbation="kick"),
                             f"SweepSpec.perturbation = 'kick' is invalid: expected one of "
                             f"{registry.perturbation_names()}."),
}


@pytest.mark.parametrize("call, expected", SPEC.values(), ids=SPEC.keys())
def test_sweep_spec_rejects_each_bad_field_naming_it_its_value_and_range(call, expected):
    _raises_exactly(ValueError, call, expected)


_S = SweepSpec()
SWEEP = {
    "unknown-parameter": (dict(inputs={"dF": 1.0, "zeta": 1.0}),
                          f"unknown sweep parameter(s) ['zeta']; valid names: {PARAMETERS}."),
    "empty": (dict(inputs={}), "inputs is empty: give at least one swept parameter."),
    "mu-and-mu_s": (dict(inputs={"mu": 0.3, "mu_s": 0.4}), "give either 'mu' or 'mu_s'/'mu_d', not both."),
    "input-2d": (dict(inputs={"dF": [[1.0, 2.0]]}),
                 "input 'dF' has shape (1, 2): expected a scalar or a 1-D array."),
    "zip-unequal": (dict(inputs={"dF": [1.0, 2.0], "mu": [0.1, 0.2, 0.3]}, combine="zip"),
                    "zipped inputs must have equal lengths (or length 1); got dF: 2, mu: 3"),
    "combine": (dict(inputs={"dF": 1.0}, combine="outer"),
                "combine = 'outer' is invalid: expected 'grid' or 'zip'."),
    "members-past-end": (dict(inputs={"dF": [1.0, 2.0]}, members=range(0, 3)),
                         "members = range(0, 3) is invalid: expected a contiguous range within [0, 2)."),
    "members-strided": (dict(inputs={"dF": [1.0, 2.0]}, members=range(0, 2, 2)),
                        "members = range(0, 2, 2) is invalid: expected a contiguous range within [0, 2)."),
}


@pytest.mark.parametrize("kw, expected", SWEEP.values(), ids=SWEEP.keys())
def test_sweep_rejects_bad_inputs_before_any_member_runs_naming_them(kw, expected):
    _raises_exactly(ValueError, lambda: sweep(_S, **kw), expected)


def test_sweep_rejects_a_spec_of_another_type_naming_the_type():
    _raises_exactly(TypeError, lambda: sweep({"model": "field"}, {"dF": 1.0}), "spec must be a SweepSpec, got dict.")


MISC = {
    "critical_loads-kind": (lambda: theory.critical_loads(_rod(), 3, 0.01, kind="energy"),
                            "kind = 'energy' is invalid: expected 'velocity' or 'position'."),
    "critical_loads-n_modes": (lambda: theory.critical_loads(_rod(), 0, 0.01),
                               "n_modes = 0 is invalid: expected an int >= 1."),
    "choose_model-perturbation": (lambda: model_choice.choose_model("kick", 1.0, 0.3),
                                  f"perturbation = 'kick' is invalid: expected one of {tuple(model_choice.RULES)} "
                                  "(those measured)."),
    "choose_model-dF": (lambda: model_choice.choose_model("sine", float("nan"), 0.3),
                        "dF = nan is invalid: expected a finite load [N]."),
    "choose_model-mu": (lambda: model_choice.choose_model("sine", 1.0, -0.1),
                        "mu = -0.1 is invalid: expected a finite friction coefficient >= 0."),
    "field_norm": (lambda: worst_case.field_norm(jnp.ones(3), "l1"),
                   "norm = 'l1' is invalid: expected 'l2' or 'max'."),
    "reproduce-model": (lambda: reproduce("e1", model="beam"),
                        "model = 'beam' is invalid: expected one of ('field', 'rod3d')."),
    "reproduce-n": (lambda: reproduce("e1", model="rod3d", n=3),
                    "n = 3 is invalid: expected an int >= 4 (segments of the 3D rod)."),
    "coordinator_address": (lambda: distributed.initialize("localhost"),
                            "coordinator_address = 'localhost' is invalid: expected HOST:PORT with a port in "
                            "1..65535."),
    "coordinator_port": (lambda: distributed.initialize("localhost:70000"),
                         "coordinator_address = 'localhost:70000' is invalid: expected HOST:PORT with a port in "
                         "1..65535."),
    "num_processes": (lambda: distributed.initialize("h:1", 0),
                      "num_processes = 0 is invalid: expected an int >= 1."),
    "process_id-past-count": (lambda: distributed.initialize("h:1", 2, 2),
                              "process_id = 2 is invalid: expected an int with 0 <= process_id < num_processes = 2."),
    "process_id-negative": (lambda: distributed.initialize(None, None, -1),
                            "process_id = -1 is invalid: expected an int with 0 <= process_id < num_processes."),
}


@pytest.mark.parametrize("call, expected", MISC.values(), ids=MISC.keys())
def test_theory_model_choice_reproduce_and_distributed_reject_bad_arguments_naming_them(call, expected):
    _raises_exactly(ValueError, call, expected)


SWEEP_SETTINGS = {
    "chunk_size-zero": (dict(chunk_size=0), "chunk_size = 0 is invalid: expected an int >= 1."),
    "scheduling": (dict(scheduling="queue"), "scheduling = 'queue' is invalid: expected 'pool' or 'chunk'."),
    "lanes-zero": (dict(lanes=0), "lanes = 0 is invalid: expected an int >= 1."),
    "refill_every-float": (dict(refill_every=1.5), "refill_every = 1.5 is invalid: expected an int >= 1."),
}


@pytest.mark.parametrize("kw, expected", SWEEP_SETTINGS.values(), ids=SWEEP_SETTINGS.keys())
def test_sweep_rejects_bad_scheduling_settings_naming_them(kw, expected):
    spec = SweepSpec(model="mode", t1=0.01, dt=1e-4)
    _raises_exactly(ValueError, lambda: sweep(spec, {"dF": 1.0}, **kw), expected)


@pytest.mark.parametrize("dt", [1.0, 0.0, -1e-4])
def test_sweep_rejects_a_step_outside_zero_to_the_members_limit_naming_the_limit(dt):
    """Above the limit, and 0 or below (a step of 0 is not "the default step": that is `None`)."""
    spec = SweepSpec(model="field", n=8, dt=dt)
    rod = _rod()
    m = FieldModel.from_rod(rod, 8, dF=5.0)
    limit = float(ProjectedVerlet(1.0).step_limit(m))
    _raises_exactly(ValueError, lambda: sweep(spec, {"dF": 5.0}),
                    f"SweepSpec.dt = {dt!r} s is invalid for model 'field': the scheme's step limit is {limit:.4g} s; "
                    f"use 0 < dt < {limit:.4g} s.")


def test_a_3d_sweep_under_a_random_perturbation_is_held_to_the_explicit_schemes_limit():
    """The 3D rod runs its implicit scheme (no step limit) only under perturbations measured
    adequate for it; under a random velocity its scenes run the explicit leapfrog, so a given
    step of 1 s is refused against that scheme's limit (below a millisecond at 4 segments)."""
    import re

    spec = SweepSpec(model="rod3d", n=4, perturbation="random-velocity", dt=1.0)
    with pytest.raises(ValueError) as err:
        sweep(spec, {"dF": 5.0}, progress=False)
    m = re.fullmatch(r"SweepSpec\.dt = 1\.0 s is invalid for model 'rod3d': the scheme's step limit is (\S+) s; "
                     r"use 0 < dt < (\S+) s\.", str(err.value))
    assert m and m.group(1) == m.group(2) and 0 < float(m.group(1)) < 1e-3, str(err.value)


def test_sweep_rejects_a_sweep_whose_every_member_has_a_bad_rod():
    _raises_exactly(ValueError, lambda: sweep(SweepSpec(model="mode"), {"L": [-1.0, 0.0]}),
                    "no member of the sweep has valid rod parameters (the first: RodChannel.L = -1.0 m is invalid: "
                    "it must be finite and > 0.)")


def test_other_entry_points_reject_unknown_names_listing_the_valid_ones():
    from jaxrod.boundary.search import METHODS, critical_velocity
    from jaxrod.experiments.e3.rod3d import label_3d
    from jaxrod.reproduce import EXPERIMENTS

    _raises_exactly(ValueError, lambda: critical_velocity(_rod(), 1.0, model="field", method="newton"),
                    f"method = 'newton' is invalid: expected one of {METHODS}.")
    assert METHODS == ("departure", "bisection")
    _raises_exactly(ValueError, lambda: reproduce(["e1", "e9"], out="unused"),
                    f"unknown experiment(s) ['e9'] for model 'field': expected {EXPERIMENTS} or 'all'.")
    _raises_exactly(ValueError, lambda: reproduce("e1", out="unused", model="rod3d"),
                    "unknown experiment(s) ['e1'] for model 'rod3d': expected ('e3', 'e4', 'e5', 'e6').")
    _raises_exactly(ValueError, lambda: label_3d(_rod(), 4, 1e-4, 0.01, scheme="rk4"),
                    "scheme = 'rk4' is invalid: expected one of ('leapfrog', 'verlet', 'implicit').")
