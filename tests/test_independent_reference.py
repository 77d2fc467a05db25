"""jaxrod's field model against an independent reference of P1 (`tests/independent/field_p1.py`:
plain NumPy, spectral collocation, Moreau–Jean trapezoidal steps with the friction problem
solved exactly each step), and the reference itself against exact results.

The committed reference values and each comparison's tolerance come from
`studies/reference/field_p1.py` (`results/reference/field_p1.json`): tolerance = Richardson
estimates of both schemes' errors at n = 64 from their measured changes to 2n and dt/2.
"""

import json
import math
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from independent.field_p1 import FieldP1, Rod, noise_field

ROOT = pathlib.Path(__file__).parent.parent
DATA = json.loads((ROOT / "results" / "reference" / "field_p1.json").read_text())
Q = DATA["quantities"]
N, RTOL, T1 = DATA["n"], DATA["rtol"], DATA["t1"]
DRAWS = np.loadtxt(ROOT / "tests" / "independent" / "random_force_key0.txt")
f64 = lambda x: jnp.asarray(x, jnp.float64)


def _jaxrod():
    from jaxrod import RodChannel
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    return RodChannel, Scene, make_perturbation


# -- the reference against exact results --------------------------------------------------------

def _mode6(model):
    return np.sin(6 * math.pi * model.s / model.rod.L)


@pytest.mark.parametrize("dF", [2.0, -1.308061255253151])  # loaded past F⁰₆ (grows), unloaded (oscillates)
def test_reference_mode6_follows_trapezoidal_solution_of_P3_exactly(dF):
    """Frictionless mode 6: the run is the trapezoidal rule's exact discrete solution for k₆ of P3
    (round-off), and that converges to cosh(λt) / cos(ωt) at second order."""
    rod = Rod(mu=0.0)
    k6 = float(rod.k(6, rod.F0(6) + dF))
    A0, steps, errs = 1e-3, 200, []
    for h in (1e-4, 5e-5):
        model = FieldP1(rod, rod.F0(6) + dF, 32, h)
        q, v = A0 * _mode6(model), np.zeros(32)
        for _ in range(steps * int(round(1e-4 / h))):
            q, v = model.step(q, v)
        a = q @ _mode6(model) / (_mode6(model) @ _mode6(model))
        n = steps * int(round(1e-4 / h))
        if k6 < 0:
            lam = math.sqrt(-k6)
            z = (1 + h * lam / 2) / (1 - h * lam / 2)
            discrete, exact = A0 * (z**n + z**-n) / 2, A0 * math.cosh(lam * n * h)
        else:
            om = math.sqrt(k6)
            discrete, exact = A0 * math.cos(n * 2 * math.atan(h * om / 2)), A0 * math.cos(om * n * h)
        assert a == pytest.approx(discrete, rel=1e-9, abs=1e-15)
        assert np.max(np.abs(q - a * _mode6(model))) < 1e-12  # no other mode is excited
        errs.append(abs(a - exact))
    assert 3.9 < errs[0] / errs[1] < 4.1  # second order


def test_reference_independent_coulomb_blocks_stop_exactly():
    """With no stiffness (k = 0) every node is a Coulomb block: v(t) = v₀ − f t, stopping at
    t = v₀/f after sliding v₀²/(2f), exactly when the stop falls on a step."""
    rod, h = Rod(mu=0.3), 1e-4
    model = FieldP1(rod, 0.0, 16, h, k=np.zeros(16))
    f = model.f
    K = np.arange(1, 17) * 3
    sign = np.where(np.arange(16) % 2 == 0, 1.0, -1.0)
    res = model.run(np.zeros(16), sign * f * h * K, t1=1.0, threshold=10.0)
    assert res.stuck and res.steps == K.max()
    assert np.all(res.v == 0.0)
    np.testing.assert_allclose(res.q, sign * (f * h * K) ** 2 / (2 * f), rtol=1e-12)


def test_reference_holds_mode6_shape_exactly_up_to_the_nodal_stick_line():
    """A mode-6 shape at rest under load is held iff |k₆|A·max_j|sin(6πs_j/L)| ≤ f (P1's stick
    condition at every node; P6's A_cr = f/|k| at the crest)."""
    rod = Rod(mu=0.3)
    model = FieldP1(rod, rod.F0(6) + 2.0, 64, 1e-4)
    limit = model.f / abs(float(rod.k(6, model.F))) / np.max(np.abs(_mode6(model)))
    held = model.run(0.999 * limit * _mode6(model), np.zeros(64))
    assert held.stuck and held.steps == 0
    moved = model.run(1.001 * limit * _mode6(model), np.zeros(64), t1=1e-3)
    assert not moved.stuck and np.any(moved.v != 0.0)


def test_reference_friction_step_meets_the_set_valued_law_and_matches_gauss_seidel():
    """The active-set friction solution satisfies v = v_free + W r, r_j ∈ −f Sgn(v_j) exactly
    (to round-off) and equals projected Gauss–Seidel's."""
    rod = Rod(mu=0.3)
    model = FieldP1(rod, rod.F0(6) + 5.0, 64, 2e-4)
    rng = np.random.default_rng(1)
    for scale in (0.02, 0.1, 0.5):
        vf = rng.uniform(-1, 1, 64) * scale
        v, r = model.friction_impulse(vf)
        np.testing.assert_allclose(v, vf + model.W @ r, atol=1e-12)
        slip = v != 0.0
        np.testing.assert_allclose(r[slip], -model.f * np.sign(v[slip]), rtol=1e-14)
        assert np.all(np.abs(r[~slip]) <= model.f * (1 + 1e-12))
        v_pgs, _ = model._pgs(vf)
        np.testing.assert_allclose(v, v_pgs, atol=1e-10)


def test_reference_random_force_field_is_jaxrods_from_the_committed_draws():
    """The committed draws give the same force field at the nodes as jaxrod's scene noise (key 0)."""
    from jaxrod.perturbations import scene_noise

    s = FieldP1(Rod(), 0.0, N, 1e-4).s
    ours = noise_field(DRAWS, 2.0, s, 3.0, N)
    theirs = np.asarray(scene_noise(jax.random.key(0), f64(2.0), f64(s), f64(3.0), 500, modes=N))
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


# -- jaxrod against the committed reference values ----------------------------------------------

def _gap(name, value):
    """(|jaxrod − reference|, the tolerance, a message) of the committed quantity `name`."""
    q = Q[name]
    return abs(value - q["reference"]), q["tolerance"], (
        f"{name}: jaxrod {value:.6g} vs reference {q['reference']:.6g}, tolerance {q['tolerance']:.3g}")


@pytest.mark.parametrize("dF", DATA["loads_dF"])
def test_jaxrod_sine_critical_velocity_matches_reference(dF):
    from jaxrod.boundary import critical_velocity

    RodChannel, Scene, make_perturbation = _jaxrod()
    rod = RodChannel.reference(mu=DATA["mu"])
    dt = Scene(rod, f64(dF), make_perturbation("sine", 1.0), n=N).step()
    r, _ = critical_velocity(rod, f64(dF), n=N, dt=dt, rtol=RTOL, sensitivities=())
    gap, tol, msg = _gap(f"v0_star_dF{dF:g}_mu{DATA['mu']:g}", float(r.root))
    assert gap <= tol, msg


def test_jaxrod_random_position_critical_load_matches_reference():
    from jaxrod.boundary import critical_load

    RodChannel, Scene, make_perturbation = _jaxrod()
    rod = RodChannel.reference(mu=DATA["mu"])
    rp = DATA["random_position"]
    dt = Scene(rod, f64(100.0), make_perturbation("random-position", 1.0), n=N).step()
    r, _ = critical_load(rod, f64(rp["amplitude_N_per_m"]), perturbation="random-position", n=N, dt=dt,
                         rtol=RTOL, sensitivities=())
    gap, tol, msg = _gap(f"dF_star_random_position_mu{DATA['mu']:g}", float(r.root))
    assert gap <= tol, msg


def test_jaxrod_stability_map_column_matches_reference():
    """The map's column at ΔF = 4.81 N: the searched boundary v₀* for μ = 0.1, 0.3, 0.6 and the
    16 labels at μ = 0.3 (identical except within the v₀* tolerance of the boundary)."""
    from jaxrod.boundary import critical_velocity, crossing_state

    RodChannel, Scene, make_perturbation = _jaxrod()
    col = DATA["map_column"]
    dF = col["dF"]
    dt = Scene(RodChannel.reference(mu=max(col["mus"])), f64(col["dt_from_load"]), n=N).step()
    for mu in col["mus"]:
        r, _ = critical_velocity(RodChannel.reference(mu=mu), f64(dF), n=N, dt=dt, rtol=RTOL, sensitivities=())
        gap, tol, msg = _gap(f"v0_star_dF{dF:.4g}_mu{mu:g}", float(r.root))
        assert gap <= tol, msg
    rod = RodChannel.reference(mu=DATA["mu"])
    labels = "".join(str(int(crossing_state(Scene(rod, f64(dF), make_perturbation("sine", f64(v)), n=N, dt=dt), T1)[1]))
                     for v in col["v0"])
    ref_labels = Q[f"map_column_dF{dF:.4g}_mu{DATA['mu']:g}"]["reference"]
    star = Q[f"v0_star_dF{dF:.4g}_mu{DATA['mu']:g}"]
    near = lambda v: abs(v - star["reference"]) <= star["tolerance"]
    assert all(a == b or near(v) for v, a, b in zip(col["v0"], labels, ref_labels)), (labels, ref_labels)


MATCHED = json.loads((ROOT / "results" / "reference" / "rod3d_matched.json").read_text())


@pytest.mark.parametrize("row", [r for r in MATCHED["rows"] if r["segments"] == 60], ids=lambda r: f"dF{r['dF']:g}")
def test_jaxrod_field_at_the_3d_rods_nodes_matches_reference(row):
    """At the 59 interior nodes of the 60-segment 3D rod (the resolution of the 3D rod's v₀* check,
    tests/test_rod3d_loaded.py): jaxrod's field model's v₀* against the reference's, within both
    schemes' Richardson estimates (studies/reference/rod3d_matched.py)."""
    from jaxrod.boundary import critical_velocity

    RodChannel, Scene, make_perturbation = _jaxrod()
    rod = RodChannel.reference(mu=MATCHED["mu"])
    n, dF = row["nodes"], row["dF"]
    dt = Scene(rod, f64(dF), make_perturbation("sine", 1.0), n=n).step()
    r, _ = critical_velocity(rod, f64(dF), n=n, dt=dt, rtol=MATCHED["rtol"], sensitivities=())
    v = float(r.root)
    assert abs(v - row["reference"]) <= row["tolerance"], (v, row["reference"], row["tolerance"])
    assert v == pytest.approx(row["field"], rel=2 * MATCHED["rtol"])  # the committed table is this code's


# -- the reference reproduces its committed values -----------------------------------------------

@pytest.mark.slow
def test_reference_reproduces_committed_values():
    """Rerun the reference at (n, dt) of the committed values (about 20 s)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("field_p1_study", ROOT / "studies" / "reference" / "field_p1.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    values = study.reference_values(N, DATA["reference_dt"])
    for name, v in values.items():
        if isinstance(v, str):
            assert v == Q[name]["reference"]
        else:
            assert v == pytest.approx(Q[name]["reference"], rel=2 * RTOL)
    for row in MATCHED["rows"]:
        if row["segments"] == 60:
            v = study.critical_velocity(study.Rod(mu=MATCHED["mu"]), row["dF"], row["nodes"], row["reference_dt"],
                                        t1=MATCHED["t1"], threshold=MATCHED["threshold"], rtol=MATCHED["rtol"])[0]
            assert v == pytest.approx(row["reference"], rel=2 * MATCHED["rtol"])

