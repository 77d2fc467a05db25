"""The 3D rod's friction pass against the material-frame formulas it replaces: the tangent inverse
mass W of every contact, and the spin and velocity an impulse gives, from a brute-force sum over
the segments' material frames (gₐ = Q uₐ, J⁻¹ = diag(1/J₁, 1/J₂, 1/J₃) with held components 0)
for rotated directors, every end condition and friction at the contact point or the axis; in
float64 to rounding, and in float32 (the default `friction_precision`) to float32's rounding."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D
from jaxrod.rod3d.contact import FIELDS, friction_pass, friction_table
from jaxrod.rod3d.so3 import exp_so3


def _state(model, seed=0):
    """A straight rod displaced along the wall (e_r varies node by node), its segments turned by
    random rotations of up to ~0.5 rad (d₃ no longer along x), and positive normal forces."""
    rng = np.random.default_rng(seed)
    n = model.n
    q, v = model.initial_state(lateral_offset=0.4 * model.rod.R * np.sin(np.linspace(0, 3, n + 1)))
    Q = jnp.einsum("jab,jbc->jac", q.Q, exp_so3(jnp.asarray(rng.normal(0, 0.3, (n, 3)))))
    N = jnp.asarray(rng.uniform(0.5, 2.0, n + 1))
    return q.x, Q, N, v


def _natural(table, name, n):
    """Field `name` of the per-colour table in node order."""
    i = FIELDS.index(name)
    even, odd = table
    return np.stack([np.asarray(even[i]), np.asarray(odd[i])], 1).reshape(-1)[: n + 1]


def _slip(i, x, Q, v, w, r):
    """The tangential velocity (t₁, t₂) of interior node i's contact point [m/s]: the node's
    velocity plus each of its two segments' half share of ω × r_c (material spins `w`, directors
    `Q`, arm `r` [m]), from the material-frame formula."""
    x, Q, v, w = (np.asarray(a) for a in (x, Q, v, w))
    e1, e2 = x[i, 1:] / np.hypot(x[i, 1], x[i, 2])
    t1, t2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, -e2, e1])
    u = [r * np.array([0.0, e2, -e1]), r * t1]
    return np.array([v[i] @ t + sum(0.5 * (w[j] @ (Q[j] @ ua)) for j in (i - 1, i)) for t, ua in zip((t1, t2), u)])


def _reference_W(model, x, Q):
    """W from the material-frame formula, node by node."""
    n = model.n
    held_n, held_s = (np.asarray(a) for a in model.held())
    m, J = np.asarray(model.mass), np.asarray(model.inertia)
    r = 0.5 * float(model.rod.d) if model.friction_at == "surface" else 0.0
    x, Q = np.asarray(x), np.asarray(Q)
    out = np.zeros((n + 1, 3))
    for i in range(n + 1):
        rad = np.hypot(x[i, 1], x[i, 2])
        e1, e2 = x[i, 1] / rad, x[i, 2] / rad
        u = [r * np.array([0.0, e2, -e1]), r * np.array([1.0, 0.0, 0.0])]  # r_c × t₁, r_c × t₂
        W = np.diag([(~held_n[i, 0]) / m[i], 0.0])
        W[1, 1] = ((~held_n[i, 1]) * e2**2 + (~held_n[i, 2]) * e1**2) / m[i]
        segments = [j for j in (i - 1, i) if 0 <= j < n]
        c = 1.0 / len(segments)
        for j in segments:
            g = [Q[j] @ ua for ua in u]
            Jinv = np.where(held_s[j], 0.0, 1.0 / J)
            for a in range(2):
                for b in range(2):
                    W[a, b] += c**2 * np.sum(Jinv * g[a] * g[b])
        if np.linalg.det(W) <= 0:  # nothing can move the point: inert
            W = np.eye(2)
        out[i] = W[0, 0], W[0, 1], W[1, 1]
    return out


# the relative error each precision is held to: float64 to rounding, float32 to a few of its ulps;
# and a velocity change's absolute error (float32 rounds the pass's velocities at the scale of v,
# ~1e-3 m/s here)
RTOL = {"float64": 1e-12, "float32": 2e-6}
ATOL_V = {"float64": 1e-18, "float32": 2e-9}


@pytest.mark.parametrize("precision", ["float64", "float32"])
@pytest.mark.parametrize("ends", ["pinned", "fork", "clamped"])
@pytest.mark.parametrize("friction_at", ["surface", "axis"])
def test_tangent_inverse_mass_matches_the_material_frame_sum(ends, friction_at, precision):
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 9, ends=ends, friction_at=friction_at, friction_precision=precision)
    x, Q, N, _ = _state(model)
    table = friction_table(model, x, Q, N)
    assert table[0].dtype == jnp.dtype(precision)
    ref = _reference_W(model, x, Q)
    tol = RTOL[precision]
    for k, name in enumerate(("W11", "W12", "W22")):
        np.testing.assert_allclose(_natural(table, name, model.n), ref[:, k], rtol=tol, atol=tol * ref.max())


@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_one_impulse_moves_the_node_and_spins_its_segments_as_the_material_frame_says(precision):
    """A single active contact, no others: the pass's impulse p (whatever the law made of it)
    changes the node's velocity by p₁t₁/m + p₂t₂/m and each adjacent segment's material spin by
    c J⁻¹ Σₐ pₐ gₐ, gₐ = Q uₐ; the contact point then moves as W p predicts. Every other node
    and segment keeps its velocity and spin exactly, in float32 too (the pass adds its changes
    to the float64 state)."""
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 9, ends="fork", friction_precision=precision)
    tol = RTOL[precision]
    x, Q, N, v = _state(model, seed=1)
    i = 4
    N = jnp.zeros_like(N).at[i].set(1.5)
    table = friction_table(model, x, Q, N)
    rng = np.random.default_rng(2)
    v0 = jnp.asarray(rng.normal(0, 1e-3, (model.n + 1, 3)))
    w0 = jnp.asarray(rng.normal(0, 1e-1, (model.n, 3)))
    h = 1e-5
    v1, w1, *_ = jax.jit(lambda t, Q, v, w: friction_pass(model, jr.Coulomb(), t, Q, v, w,
                                                         jnp.zeros(model.n + 1, bool),
                                                         jnp.zeros((model.n + 1, 2)), h))(table, Q, v0, w0)
    dv, dw = np.asarray(v1 - v0), np.asarray(w1 - w0)
    m, J = np.asarray(model.mass), np.asarray(model.inertia)
    xi = np.asarray(x[i])
    e1, e2 = xi[1] / np.hypot(xi[1], xi[2]), xi[2] / np.hypot(xi[1], xi[2])
    t1, t2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, -e2, e1])
    p1, p2 = m[i] * dv[i, 0], m[i] * (dv[i] @ t2)
    assert np.hypot(p1, p2) > 0
    np.testing.assert_allclose(dv[i], (p1 * t1 + p2 * t2) / m[i], rtol=tol, atol=ATOL_V[precision])
    np.testing.assert_allclose(np.delete(dv, i, 0), 0.0, atol=1e-18)  # no other node moves
    r = 0.5 * float(rod.d)
    u = [r * np.array([0.0, e2, -e1]), r * t1]
    Qn = np.asarray(Q)
    for j in (i - 1, i):
        expected = 0.5 * (p1 * (Qn[j] @ u[0]) + p2 * (Qn[j] @ u[1])) / J
        np.testing.assert_allclose(dw[j], expected, rtol=max(1e-10, tol), atol=max(1e-12, tol) * np.abs(expected).max())
    np.testing.assert_allclose(np.delete(dw, [i - 1, i], 0), 0.0, atol=1e-15)
    # slip change = W p
    W11, W12, W22 = (_natural(table, k, model.n)[i] for k in ("W11", "W12", "W22"))
    ds = _slip(i, x, Q, v1, w1, r) - _slip(i, x, Q, v0, w0, r)
    np.testing.assert_allclose(ds, [W11 * p1 + W12 * p2, W12 * p1 + W22 * p2], rtol=max(1e-9, 50 * tol))


def test_the_converged_pass_leaves_each_contact_stuck_or_slipping_against_its_impulse():
    """Coulomb's law with maximal dissipation, for many coupled contacts (neighbours share a
    segment; the segments tilted, so W₁₂ ≠ 0): converged (tolerance 1e-13, μ_s = μ_d), every
    interior contact either holds its point still (|p| < μN h, slip after ≈ 0) or slides at the
    bound with its impulse against the slip it leaves (p = −μN h û). The slip is computed here from
    the returned velocities and spins (`_slip`, as in the test above); normal forces of 0.02–2 N and node
    speeds of 0.01–3 mm/s make both kinds."""
    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 9, ends="fork", friction_precision="float64", friction_tol=1e-13, friction_sweeps=2000)
    x, Q, _, v = _state(model, seed=3)
    rng = np.random.default_rng(4)
    N = jnp.asarray(np.exp(rng.uniform(np.log(0.02), np.log(2.0), model.n + 1)))
    table = friction_table(model, x, Q, N)
    speed = np.exp(rng.uniform(np.log(1e-5), np.log(3e-3), model.n + 1))  # [m/s], node by node
    v0 = jnp.asarray(rng.normal(0, 1, (model.n + 1, 3)) * speed[:, None])
    w0 = jnp.asarray(rng.normal(0, 1, (model.n, 3)) * 100 * speed[:-1, None])
    h = 1e-5
    v1, w1, _, force, residual, sweeps = jax.jit(
        lambda t, Q, v, w: friction_pass(model, jr.Coulomb(), t, Q, v, w, jnp.zeros(model.n + 1, bool),
                                         jnp.zeros((model.n + 1, 2)), h))(table, Q, v0, w0)
    assert float(residual) <= 1e-13 and 1 < int(sweeps) < 2000
    W12 = _natural(table, "W12", model.n)
    assert np.max(np.abs(W12[1:-1])) > 1e-3 * np.max(_natural(table, "W11", model.n))  # coupled
    r = 0.5 * float(rod.d)
    kinds = set()
    for i in range(1, model.n):
        slip = _slip(i, x, Q, v1, w1, r)
        p, bound = np.asarray(force[i]) * h, float(rod.mu_d) * float(N[i]) * h
        if np.hypot(*p) < bound * (1 - 1e-9):  # held
            kinds.add("stick")
            assert np.hypot(*slip) < 1e-9 * speed.max(), (i, slip)
        else:  # at the bound, against the slip
            kinds.add("slip")
            assert np.hypot(*p) == pytest.approx(bound, rel=1e-9)
            cos = (p @ slip) / (np.hypot(*p) * np.hypot(*slip))
            assert cos == pytest.approx(-1.0, abs=1e-9), (i, cos)
    assert kinds == {"stick", "slip"}


@pytest.mark.slow  # three 3D compilations, ~50 s
def test_a_float32_pass_moves_a_run_far_less_than_its_time_step_does():
    """The error budget of `friction_precision="float32"`: in the benchmark's case (dead load
    F⁰₆ + 5 N, sine mode-6 velocity 20 mm/s, 1000 steps at half the step limit, 30 segments) the
    float32 pass moves the final amplitude and positions by far less than halving the step does
    (measured: amplitude 1.5e-6 relative against 1.4e-3, positions 1.2e-10 m against 1.1e-7 m;
    at 500 segments, where the scheme's own error is smallest, 2e-6 against 1.5e-7:
    docs/rod3d.md, "Cost of a step")."""
    from jaxrod import theory
    from jaxrod.experiments.rod3d import run
    from jaxrod.rod3d import sine_velocity, step_limit

    rod = jr.RodChannel.reference(0.3)
    F = float(theory.reference_load(rod)) + 5.0
    out = {}
    for precision, divide in (("float64", 1), ("float32", 1), ("float64", 2)):
        model = Rod3D(rod, 30, control="load", end_load=F, friction_precision=precision)
        dt = 0.5 * float(step_limit(model, model.initial_state(F)[0]))
        q, v = model.initial_state(F, lateral_velocity=sine_velocity(model, 20e-3))
        sol = run(model, q, v, 1000 * dt, 3, dt / divide, stop_on_buckle=False, stop_when_stuck=False)
        out[precision, divide] = float(sol.amplitude[-1]), np.asarray(sol.q_final.x)
    (a64, x64), (a32, x32), (a_half, x_half) = out.values()
    assert abs(a32 - a64) < 1e-2 * abs(a_half - a64) and abs(a32 / a64 - 1) < 1e-5
    assert np.abs(x32 - x64).max() < 1e-2 * np.abs(x_half - x64).max()
    assert np.abs(x32 - x64).max() > 0  # the two precisions did run differently
