import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr


def test_reference_rod_derived_quantities():
    rod = jr.RodChannel.reference()
    d, E, rho_v, nu = 1.5e-3, 77e9, 6450.0, 0.33
    A = math.pi * d**2 / 4
    I = math.pi * d**4 / 64
    # PHYSICS.md quotes EI = 1.9135e-2 N m^2, rho = 1.1398e-2 kg/m, w = 0.1118 N/m.
    assert float(rod.EI) == pytest.approx(1.9135e-2, rel=2e-4)
    assert float(rod.rho) == pytest.approx(1.1398e-2, rel=2e-4)
    assert float(rod.w) == pytest.approx(0.1118, rel=5e-4)
    assert float(rod.N) == pytest.approx(float(rod.w))
    assert float(rod.area) == pytest.approx(A)
    assert float(rod.EA) == pytest.approx(E * A)
    assert float(rod.GJ) == pytest.approx(E / (2 * (1 + nu)) * 2 * I)
    assert float(rod.rho) == pytest.approx(rho_v * A)
    assert float(rod.mu_s) == 0.3 and float(rod.mu_d) == 0.3


@pytest.mark.parametrize(
    "field, value, fragment",
    [
        ("L", 0.0, "> 0"),
        ("L", -1.0, "> 0"),
        ("L", float("nan"), "finite"),
        ("d", 0.0, "> 0"),
        ("E", float("inf"), "finite"),
        ("E", -77e9, "> 0"),
        ("rho_v", 0.0, "> 0"),
        ("R", -5e-3, "> 0"),
        ("R", float("inf"), "finite"),
        ("g", 0.0, "> 0"),
        ("nu", 0.5, "(-1, 0.5)"),
        ("nu", -1.0, "(-1, 0.5)"),
        ("nu", 0.7, "(-1, 0.5)"),
        ("mu_s", -0.1, ">= 0"),
        ("mu_d", -0.1, ">= 0"),
    ],
)
def test_bad_input_names_field_value_and_range(field, value, fragment):
    with pytest.raises(ValueError) as err:
        jr.RodChannel.reference(**{field: value})
    msg = str(err.value)
    assert f"RodChannel.{field}" in msg
    assert repr(value) in msg
    assert fragment in msg


BAD = [("L", 0.0), ("L", float("nan")), ("d", -1e-3), ("E", float("inf")), ("rho_v", 0.0), ("R", -5e-3),
       ("g", 0.0), ("nu", 0.5), ("nu", -1.0), ("mu_s", -0.1), ("mu_d", -0.1), ("mu_s", float("nan")), ("mu_d", 0.5)]


def test_the_traced_validity_is_the_constructions_check():
    """`RodChannel.valid` (for traced values: sweeps, the models' `check`) refuses exactly what the
    construction refuses (one definition of a valid rod), member by member under vmap."""
    good = jr.RodChannel.reference(mu=0.3)
    fields = ("L", "d", "E", "rho_v", "nu", "R", "g", "mu_s", "mu_d")
    for field, value in BAD:
        with pytest.raises(ValueError):
            jr.RodChannel.reference(mu=0.3, **{field: value})
    values = {f: jnp.asarray([float(getattr(good, f))] * (len(BAD) + 1)) for f in fields}
    for i, (field, value) in enumerate(BAD):
        values[field] = values[field].at[i].set(value)
    valid = jax.jit(jax.vmap(lambda v: jr.RodChannel(**v).valid()))(values)
    assert valid.tolist() == [False] * len(BAD) + [True]
    assert bool(jr.FieldModel.from_rod(good, 8, dF=1.0).check())


def test_dynamic_above_static_friction_is_rejected():
    with pytest.raises(ValueError, match=r"RodChannel.mu_d = 0.5 .*\[0, mu_s\].*0.3"):
        jr.RodChannel.reference(mu_s=0.3, mu_d=0.5)


def test_unknown_override_is_rejected():
    with pytest.raises(ValueError, match="unknown field"):
        jr.RodChannel.reference(EI=1.0)


def test_leaves_are_arrays_and_vmappable():
    rod = jr.RodChannel.reference()
    leaves = jax.tree_util.tree_leaves(rod)
    assert len(leaves) == 9 and all(isinstance(x, jax.Array) for x in leaves)
    # Traced values skip the host-side checks; vmapping over a leaf works without errors.
    mus = jnp.linspace(0.0, 1.0, 5)
    f = jax.vmap(lambda mu: jr.theory.friction_amplitude(rod.with_friction(mu)))(mus)
    np.testing.assert_allclose(f, 4 * mus * float(rod.w) / (math.pi * float(rod.rho) * 5.125e-3))
