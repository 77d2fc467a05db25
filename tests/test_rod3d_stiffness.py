"""The 3D rod's stiffness and its implicit kick on a short rod, quick enough for the default suite
(no run is compiled): the bending stiffness through the discrete Euler load of the rod's own
potential and of the implicit step's matrix, and the kick against a dense solve of Newmark's
system."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D, sine_velocity
from jaxrod.rod3d.hessian import _turned, hessian_blocks, implicit_kick
from jaxrod.rod3d.state import held_pattern


def _dense(D, U):
    nb, m = D.shape[0], D.shape[-1]
    A = np.zeros((nb * m, nb * m))
    for k in range(nb):
        A[m * k:m * k + m, m * k:m * k + m] = D[k]
        if k < nb - 1:
            A[m * k:m * k + m, m * k + m:m * k + 2 * m] = U[k]
            A[m * k + m:m * k + 2 * m, m * k:m * k + m] = np.asarray(U[k]).T
    return A


def _free_mask(model):
    """1 where a block unknown (x, φ; the last block's φ a placeholder) is free, as a flat bool."""
    held_n, held_s = held_pattern(model)
    free_s = np.concatenate([~held_s, np.zeros((1, 3), bool)])
    return np.concatenate([~held_n, free_s], -1).reshape(-1)


def _potential_hessian(model, q):
    """The Hessian of `model.potential` (jaxrod.rod3d.energy: what the forces are the gradient of)
    in the step's block coordinates (x_k, φ_k) at q, by AD, dense."""
    n = model.n

    def energy(z):
        z = z.reshape(n + 1, 6)
        Q = jax.vmap(_turned)(z[:-1, 3:], q.Q)
        return model.potential(q.x + z[:, :3], Q)

    return np.asarray(jax.jit(jax.hessian(energy))(jnp.zeros(6 * (n + 1))))


def _lowest_eigenvalue(H, free):
    return float(np.linalg.eigvalsh(H[np.ix_(free, free)])[0])


@pytest.mark.parametrize("source", ["potential", "implicit matrix"])
def test_the_euler_load_of_a_short_rod_is_the_discrete_elasticas(source):
    """A free rod in space (no wall, no gravity), 12 segments, fork ends, under a dead end load F:
    the lowest eigenvalue of its stiffness falls linearly with F and crosses zero at the Euler
    load of the discrete elastica, F_c = (4EI/l̂²) sin²(π/2n) (−0.6 % from π²EI/L² at 12 segments;
    shear and stretch move it by under 1e-5), with EI = E·πd⁴/64 from the rod's own numbers. From
    the potential whose gradient every scheme steps (jaxrod.rod3d.energy) and from the stiffness
    the implicit kick solves with (`hessian_blocks`): a bending stiffness off by a factor in either
    moves F_c by that factor."""
    rod = jr.RodChannel.reference(0.0)
    n = 12
    EI = float(rod.E) * np.pi * float(rod.d) ** 4 / 64
    l0 = float(rod.L) / n
    F_c = 4 * EI / l0**2 * np.sin(np.pi / (2 * n)) ** 2
    lows = []
    for F in (0.5 * F_c, 0.9 * F_c):
        model = Rod3D(rod, n, channel=False, gravity=False, ends="fork", control="load", end_load=F)
        q, _ = model.initial_state()
        if source == "potential":
            H = _potential_hessian(model, q)
        else:
            H = _dense(*(np.asarray(b) for b in hessian_blocks(model, q.x, q.Q)))
        lows.append(_lowest_eigenvalue(H, _free_mask(model)))
    assert lows[0] > lows[1] > 0
    F_zero = 0.5 * F_c + (0.9 - 0.5) * F_c * lows[0] / (lows[0] - lows[1])
    assert F_zero == pytest.approx(F_c, rel=2e-3)


def test_a_uniform_twist_stores_and_returns_the_torsional_rigidity():
    """A straight free rod (no wall, gravity or load), 10 segments, each segment turned about the
    axis by k·φ more than the last: the twist energy is ½ (GJ/l̂) φ² over its 9 joints and the couple on
    the last segment is GJ φ/l̂ about the axis, with GJ = G·πd⁴/32, G = E/2(1 + ν), from the rod's own
    numbers (small φ: the couple's log map is exact to φ² relative); a torsional rigidity off by a
    factor in energy and couple moves both by that factor (the forces-are-the-gradient test cannot
    see it)."""
    from jaxrod.rod3d.so3 import exp_so3

    rod = jr.RodChannel.reference(0.0)
    n, phi = 10, 1e-3
    model = Rod3D(rod, n, channel=False, gravity=False, ends="free", control="force")
    q, _ = model.initial_state(0.0)
    turns = exp_so3(jnp.arange(n, dtype=float)[:, None] * phi * jnp.array([[1.0, 0.0, 0.0]]))  # about the axis x
    Q = jnp.einsum("kij,kjl->kil", q.Q, turns)
    GJ = float(rod.E) / (2 * (1 + float(rod.nu))) * np.pi * float(rod.d) ** 4 / 32
    l0 = float(rod.L) / n
    terms = model.elastic_terms(q.x, Q)
    assert float(terms["twist"]) == pytest.approx(0.5 * GJ / l0 * phi**2 * (n - 1), rel=1e-6)
    assert float(terms["bend"]) < 1e-12 * float(terms["twist"])
    _, tau = model.generalized_forces(q.x, Q)
    assert float(jnp.linalg.norm(tau[-1])) == pytest.approx(GJ * phi / l0, rel=1e-6)


@pytest.mark.parametrize("hk_fraction, beta, gamma", [(1.0, 0.25, 0.0), (0.5, 0.25, 0.1), (1.0, 0.1, 0.3)])
def test_the_implicit_kick_solves_newmarks_system(hk_fraction, beta, gamma):
    """`implicit_kick` against a dense solve of (M + βh²H + γh²H_d) Δ = hk (f, τ − ω × Jω) −
    γ h hk H_d v on the free unknowns (held ones keep their prescribed values): a 6-segment rod on
    the wall with μ = 0.3, moving along the wall and spinning (the gyroscopic couple is in the
    right-hand side), at a step of 100 times its explicit limit, full and half kicks."""
    from jaxrod.rod3d import step_limit

    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 6, control="load", end_load=2.0)
    q, v = model.initial_state(None, lateral_velocity=sine_velocity(model, 0.02))
    w = jnp.asarray(np.random.default_rng(0).normal(size=v.w.shape)) * 5.0  # spins [rad/s]
    v = jax.tree_util.tree_map(lambda a: a, v)
    v = type(v)(v.v, jnp.where(jnp.asarray(held_pattern(model)[1]), 0.0, w), v.stuck, v.force, v.residual, v.sweeps)
    a = model.accelerations(q, v, 0.0)
    h = float(100 * step_limit(model))
    hk = hk_fraction * h
    out = implicit_kick(model, q, v, a, hk, h, beta, gamma)

    free = _free_mask(model)
    n = model.n
    mass = np.concatenate([np.repeat(np.asarray(model.mass)[:, None], 3, 1),
                           np.concatenate([np.repeat(np.asarray(model.inertia)[None], n, 0), np.ones((1, 3))])], -1)
    H = _dense(*(np.asarray(b) for b in hessian_blocks(model, q.x, q.Q)))
    Hd = _dense(*(np.asarray(b) for b in hessian_blocks(model, q.x, q.Q, damped=True)))
    J, W = np.asarray(model.inertia), np.asarray(v.w)
    gyro = np.cross(W, J * W)
    rhs = np.concatenate([np.asarray(a.f), np.concatenate([np.asarray(a.tau) - gyro, np.zeros((1, 3))])], -1)
    vel = np.concatenate([np.asarray(v.v), np.concatenate([W, np.zeros((1, 3))])], -1).reshape(-1)
    A = np.diag(mass.reshape(-1)) + beta * h * h * H + gamma * h * h * Hd
    b = hk * rhs.reshape(-1) - gamma * h * hk * Hd @ np.where(free, vel, 0.0)
    delta = np.zeros(6 * (n + 1))
    delta[free] = np.linalg.solve(A[np.ix_(free, free)], b[free])
    delta = delta.reshape(n + 1, 6)
    held_n, held_s = held_pattern(model)
    ref_v = np.where(held_n, np.asarray(model.prescribed_velocity()), np.asarray(v.v) + delta[:, :3])
    ref_w = np.where(held_s, 0.0, W + delta[:-1, 3:])
    assert np.abs(delta).max() > 0  # the kick moves the rod
    np.testing.assert_allclose(np.asarray(out.v), ref_v, rtol=0, atol=1e-9 * np.abs(ref_v).max())
    np.testing.assert_allclose(np.asarray(out.w), ref_w, rtol=0, atol=1e-9 * np.abs(ref_w).max())


@pytest.mark.parametrize("kw", [dict(channel=False, gravity=False, control="load", end_load=-50.0),
                                dict(control="load", end_load=6.0)])
def test_the_step_limits_frequency_bound_is_the_highest_eigenfrequency(kw):
    """`frequency_bound` (the explicit step limit 2/ω_max) against the exact ω_max of a 12-segment
    rod: the largest eigenvalue of M^{−½} H M^{−½}, H the Hessian of the rod's potential by AD, on the
    free unknowns — a free rod in tension and the rod on the wall under F⁰₆ + ~4.7 N: never below
    it, within 0.5 % (the power iteration at 12–500 segments: the slow tests of
    tests/test_rod3d_step_limit.py). The lateral block (shear against the segment's rotary inertia)
    sets ω_max in both: the axial chain's 4EA/(l̂m) is far below it wherever l̂ ≫ d."""
    from jaxrod.rod3d.stiffness import frequency_bound

    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 12, **kw)
    q, _ = model.initial_state(kw["end_load"])
    H = _potential_hessian(model, q)
    n = model.n
    mass = np.concatenate([np.repeat(np.asarray(model.mass)[:, None], 3, 1),
                           np.concatenate([np.repeat(np.asarray(model.inertia)[None], n, 0), np.ones((1, 3))])], -1)
    free = _free_mask(model)
    s = 1 / np.sqrt(mass.reshape(-1)[free])
    om_max = float(np.sqrt(np.linalg.eigvalsh(s[:, None] * H[np.ix_(free, free)] * s[None, :])[-1]))
    ratio = float(frequency_bound(model, q)) / om_max
    assert 1.0 <= ratio < 1.005, ratio
