"""The 3D rod's step limit 2/ω_max in closed form (`jaxrod.rod3d.stiffness.frequency_bound`)
against the highest frequency measured by power iteration on M⁻¹H (Hessian-vector products of
the potential by AD, an independent computation): never below it, and within 0.5 %; and the
step it gives is stable, where a step 5 % above the measured limit is not."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import theory
from jaxrod.rod3d import Rod3D, step_limit
from jaxrod.rod3d.stiffness import frequency_bound, power_max_frequency

ROD = jr.RodChannel.reference(0.3)
F0 = float(theory.reference_load(ROD))
STIFF_WALL = 1e3 * float(ROD.w / (1e-3 * ROD.R) ** 1.5)  # 1000× the default Hertz constant
CASES = {  # name: (Rod3D keywords, axial force of the straight state [N], lateral offset [m])
    "channel, compressed": (dict(control="load", end_load=F0 + 5.0), F0 + 5.0, 0.0),
    "free rod, tension": (dict(control="load", end_load=-50.0, channel=False), -50.0, 0.0),
    "stiff wall, clamped": (dict(control="force", preload=F0, ends="clamped", contact_stiffness=STIFF_WALL), F0, 0.0),
    "channel, offset 2 mm": (dict(control="load", end_load=F0 + 5.0), F0 + 5.0, 2e-3),
}
measured = eqx.filter_jit(power_max_frequency)


def _case(n, name):
    kw, F, offset = CASES[name]
    model = Rod3D(ROD, n, **kw)
    s = jnp.linspace(0.0, 1.0, n + 1)
    q0, _ = model.initial_state(F, lateral_offset=offset * jnp.sin(3 * jnp.pi * s) if offset else None)
    return model, q0


def _ratio(n, name):
    """The closed-form bound over the measured highest frequency, and the case."""
    model, q0 = _case(n, name)
    om = float(measured(model, q0, 400))
    return float(frequency_bound(model, q0)) / om, model, q0


# one case by default (a power-iteration compilation each); all four here and at 30–500 segments in `slow`
@pytest.mark.parametrize("name", ["channel, compressed", pytest.param("free rod, tension", marks=pytest.mark.slow),
                                  pytest.param("stiff wall, clamped", marks=pytest.mark.slow),
                                  pytest.param("channel, offset 2 mm", marks=pytest.mark.slow)])
def test_the_closed_form_bounds_the_measured_frequency_at_12_segments(name):
    ratio, model, q0 = _ratio(12, name)
    assert 1.0 <= ratio < 1.005, (name, ratio)
    # traced (under jit) it gives the same number, and the default state is the straight one
    assert float(jax.jit(frequency_bound)(model, q0)) == pytest.approx(float(frequency_bound(model, q0)), rel=1e-12)
    if CASES[name][2] == 0.0 and name != "stiff wall, clamped":
        assert float(frequency_bound(model)) == pytest.approx(float(frequency_bound(model, q0)), rel=1e-3)
    assert step_limit(model, q0) == pytest.approx(2.0 / float(frequency_bound(model, q0)), rel=1e-15)


@pytest.mark.slow  # about 4 × 5 compilations of the power iteration, 1–2 min
@pytest.mark.parametrize("n", [30, 60, 120, 240, 500])
def test_the_closed_form_bounds_the_measured_frequency_for_30_to_500_segments(n):
    ratios = {name: _ratio(n, name)[0] for name in CASES}
    assert all(1.0 <= r < 1.005 for r in ratios.values()), ratios


@pytest.mark.slow  # two compiled 3D runs, ~40 s
def test_the_step_it_gives_is_stable_and_a_larger_one_is_not():
    """A free frictionless rod in space, kicked with random node velocities: at 0.98 of the
    closed-form limit its energy stays bounded over 4000 steps (the largest energy of the last
    quarter of the run within 2× that of the first: near the limit leapfrog's energy swings by
    up to 1/(1 − (ωh/2)²) ≈ 25× about its conserved shadow), at 1.05 of the measured limit the
    highest mode grows by orders of magnitude."""
    model = Rod3D(ROD.with_friction(0.0), 12, channel=False, ends="free", gravity=False)
    q0, v0 = model.initial_state(0.0)
    key = jax.random.PRNGKey(1)
    v0 = eqx.tree_at(lambda v: v.v, v0, 1e-3 * jax.random.normal(key, v0.v.shape))
    om = float(measured(model, q0, 400))

    def energy_growth(dt):
        integ = jr.integrators.default_for(model, dt)  # unchecked: `simulate` refuses a step above the limit
        opts = jr.RunOptions(stop_when_stuck=False, buckle_threshold=1e9, save_state=False)
        sol = eqx.filter_jit(integ.integrate)(model, q0, v0, 4000 * dt, 41, opts, check_step_limit=False)
        E = sum(np.asarray(e) for e in sol.energies.values())
        return np.max(E[-10:]) / np.max(E[:10]) if np.all(np.isfinite(E)) else np.inf

    stable, unstable = energy_growth(0.98 * step_limit(model, q0)), energy_growth(1.05 * 2.0 / om)
    print(f"energy growth at 0.98 of the bound's limit {stable:.3g}, at 1.05 of the measured limit {unstable:.3g}")
    assert stable < 2.0
    assert unstable > 1e3


def test_the_models_highest_frequency_is_the_bound_at_the_state_it_is_given():
    """`Rod3D.max_frequency(q)` is `frequency_bound` at `q`: pressed 1 mm into the wall (the Hertz
    contact stiffer than at the straight state's sag) it is higher than at the default state."""
    model, q0 = _case(12, "channel, compressed")
    pressed = eqx.tree_at(lambda q: q.x, q0, q0.x.at[:, 2].add(-1e-3))
    assert float(model.max_frequency(pressed)) == float(frequency_bound(model, pressed))
    assert float(model.max_frequency(pressed)) > 1.002 * float(model.max_frequency())  # 0.5 %: shear dominates
    assert float(model.max_frequency()) == float(frequency_bound(model))
    # the explicit step limit 2/ω_max is taken at the state given, too
    assert step_limit(model, pressed) == pytest.approx(2.0 / float(frequency_bound(model, pressed)), rel=1e-15)
    assert step_limit(model, pressed) < step_limit(model) / 1.002


@pytest.mark.parametrize("beta", [0.0, 0.1, 0.2, 0.25, 0.5])
def test_the_implicit_schemes_step_limit_is_explicit_at_beta_0_and_gone_from_a_quarter(beta):
    """`ImplicitLeapfrog(beta=β)` is stable up to 2/(ω_max √(1 − 4β)) for β < ¼: the explicit
    leapfrog's limit at β = 0, √(1/0.6) and √5 times it at 0.1 and 0.2; none from β = ¼."""
    model, _ = _case(12, "channel, compressed")
    limit = float(jr.ImplicitLeapfrog(1e-6, beta=beta).step_limit(model))
    explicit = float(jr.ProjectedLeapfrog(1e-6).step_limit(model))
    assert explicit == pytest.approx(step_limit(model), rel=1e-12)
    if beta >= 0.25:
        assert limit == float("inf")
    else:
        assert limit == pytest.approx(explicit / np.sqrt(1.0 - 4.0 * beta), rel=1e-12)
