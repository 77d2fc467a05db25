"""A model and a perturbation defined here, outside `jaxrod/`, and registered by name, run through
`Scene`, a sweep, a boundary search and the command line without any change to the package
(docs/extending.md is this file, explained).

The model: `n` beads at the rod's nodes, each the single-mode oscillator of mode `mode` with the
pointwise friction bound μN/(ρR) and no coupling. Under a uniform lateral velocity every bead
moves alike, so the critical speed is the closed form R·f/√(−k) (P6 with the bead's bound f),
an answer none of jaxrod's models gives.
"""

import json
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import registry, theory
from jaxrod.cli import main
from jaxrod.modal import dominant_mode
from jaxrod.models.dof import AbstractDOFModel
from jaxrod.models.recipe import AbstractRecipe
from jaxrod.perturbations import AbstractPerturbation


class Beads(AbstractDOFModel):
    """`n` uncoupled beads at the nodes s_j = jL/(n + 1), each `Ä = −k A − f sgn(Ȧ)` with k of
    sine mode `mode` (P3) and f = μN/(ρR) [rad/s²]. The physics only: six methods."""

    rod: jr.RodChannel
    k: jnp.ndarray
    n: int = eqx.field(static=True)

    def acceleration(self, q, t):
        return -self.k * q

    def friction_bounds(self, t):
        scale = self.rod.N / (self.rod.rho * self.rod.R)
        return self.rod.mu_s * scale, self.rod.mu_d * scale

    def kinetic_energy(self, v):
        return 0.5 * jnp.sum(v * v)

    def energy_terms(self, q, v, t):
        return {"kinetic": self.kinetic_energy(v), "potential": 0.5 * self.k * jnp.sum(q * q)}

    def max_frequency(self, q=None):
        return jnp.sqrt(jnp.maximum(self.k, 0.0))

    def sample_points(self):
        return jnp.arange(1, self.n + 1, dtype=self.rod.L.dtype) * self.rod.L / (self.n + 1)


class BeadsRecipe(AbstractRecipe):
    """How a problem is posed for `Beads`: built at the load's modal stiffness, 8 beads unless
    given, 1e-4 s steps, boundary searches by the departure rate, read as a field at the beads."""

    model_class: ClassVar[type] = Beads
    size_name: ClassVar[str] = "beads"
    min_size: ClassVar[int] = 1
    search_method: ClassVar[str] = "departure"

    def build(self, rod, F, size, mode):
        return Beads(rod, theory.stiffness(rod, mode, F), size)

    def default_size(self, rod, F, perturbation):
        return 8

    def step(self, model, rod, F, scheme_step):
        return 1e-4

    def field_of(self, model, q):
        return model.sample_points(), q

    def dominant_mode(self, model, q):
        return dominant_mode(q)


class UniformVelocity(AbstractPerturbation):
    """A lateral velocity `amplitude` [m/s], the same at every point."""

    amplitude: jnp.ndarray = eqx.field(converter=lambda x: jnp.asarray(x, float))

    @classmethod
    def from_settings(cls, amplitude, mode, key, duration):
        return cls(amplitude)

    def fields(self, model):
        s = model.sample_points()
        return jnp.zeros_like(s), self.amplitude + 0.0 * s


@pytest.fixture(scope="module")
def registered():
    registry.register_model("beads", BeadsRecipe())
    registry.register_perturbation("uniform-velocity", UniformVelocity)
    yield
    registry._MODELS.pop("beads")
    registry._PERTURBATIONS.pop("uniform-velocity")


ROD = jr.RodChannel.reference(mu=0.3)
DF = 5.0  # N above F⁰₆


def _closed_form():
    """R·f/√(−k): the uniform speed below which every bead sticks before it escapes [m/s]."""
    F = float(theory.reference_load(ROD)) + DF
    k = float(theory.stiffness(ROD, 6, F))
    f = float(ROD.N / (ROD.rho * ROD.R)) * 0.3
    return float(ROD.R) * f / math.sqrt(-k)


def test_a_registered_model_runs_in_a_scene_on_either_side_of_its_closed_form(registered):
    v_star = _closed_form()
    below, above = (jr.Scene(ROD, DF, registry.make_perturbation("uniform-velocity", a * v_star), kind="beads")
                    .run(t1=1.0, n_save=11) for a in (0.9, 1.1))
    assert not bool(below.buckled) and bool(below.stuck[-1])
    assert bool(above.buckled)
    assert int(jr.Scene(ROD, DF, kind="beads").size()) == 8


def test_a_registered_model_sweeps_and_its_boundary_search_finds_the_closed_form(registered):
    v_star = _closed_form()
    spec = jr.SweepSpec(model="beads", perturbation="uniform-velocity", mu=0.3, dF=DF, t1=1.0)
    res = jr.sweep(spec, {"amplitude": np.array([0.9, 1.1]) * v_star}, progress=False)
    assert res.outputs["buckled"].tolist() == [False, True] and res.outputs["result"].tolist() == [0, 0]
    root, _ = jr.critical_velocity(ROD, DF, model="beads", perturbation="uniform-velocity", rtol=1e-6,
                                   t1=1.0, sensitivities=())
    # the departure search brackets the label's root; the closed form is the root of the exact motion
    assert abs(float(root.root) / v_star - 1) < 2e-3


def test_a_registered_model_and_perturbation_are_choices_of_the_command_line(registered, capsys):
    v_star = _closed_form()
    code = main(["simulate", "--model", "beads", "--perturbation", "uniform-velocity", "--mu", "0.3",
                 "--dF", str(DF), "--amplitude", str(1.1 * v_star), "--t1", "1.0", "--json"])
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and out["model"] == "beads" and out["buckled"] and out["n"] == 8


def test_the_library_takes_a_recipe_object_that_no_name_was_registered_for(registered):
    """Strings are for the edge: `Scene`, `SweepSpec` and the boundary searches take the recipe
    itself; a recipe class never registered (`Unnamed`) runs the same answers as the named one."""

    class Unnamed(BeadsRecipe):
        pass

    assert registry.name_of(Unnamed()) == "Unnamed" and registry.name_of(BeadsRecipe()) == "beads"
    v_star = _closed_form()
    pert = UniformVelocity(1.1 * v_star)
    named = jr.Scene(ROD, DF, pert, kind="beads").run(t1=1.0, n_save=11)
    mine = jr.Scene(ROD, DF, pert, kind=Unnamed()).run(t1=1.0, n_save=11)
    assert bool(mine.buckled) and np.array_equal(np.asarray(mine.amplitude), np.asarray(named.amplitude))
    spec = jr.SweepSpec(model=Unnamed(), perturbation="uniform-velocity", mu=0.3, dF=DF, t1=1.0)
    assert spec.to_json()["model"] == "Unnamed"
    res = jr.sweep(spec, {"amplitude": np.array([0.9, 1.1]) * v_star}, progress=False)
    assert res.outputs["buckled"].tolist() == [False, True]
    root, _ = jr.critical_velocity(ROD, DF, model=Unnamed(), perturbation="uniform-velocity", rtol=1e-6,
                                   t1=1.0, sensitivities=())
    assert abs(float(root.root) / v_star - 1) < 2e-3
