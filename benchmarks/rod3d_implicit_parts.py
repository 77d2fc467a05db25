"""The parts of the 3D rod's implicit kick, and the alternatives measured for each (issue
[implicit3d]: the design chosen by measurement):

- the block-tridiagonal solve (`jaxrod._banded.block_tridiagonal_solve`: block Thomas in a scan,
  each 6×6 Cholesky written out entry by entry) against the same scan with `jnp.linalg.solve`
  for each block (LAPACK per block);
- the stiffness (`jaxrod.rod3d.hessian.hessian_blocks`: closed form on component arrays) against
  forward-over-reverse AD of each element's energy (`hessian_blocks_ad`);
- the whole implicit kick.

Each inside a `fori_loop` of 100 iterations whose input changes every iteration (so that XLA
cannot hoist it), per iteration, min over 3 calls after compilation, one rod, at 60, 120, 240
and 500 segments. Rows to `benchmarks/results/rod3d_implicit_parts.csv`.

    python benchmarks/rod3d_implicit_parts.py     # ~2 min
"""

from __future__ import annotations

import os
import subprocess
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod._banded import block_tridiagonal_solve  # noqa: E402
from jaxrod.rod3d import Rod3D, Rod3DPosition  # noqa: E402
from jaxrod.rod3d.hessian import hessian_blocks, hessian_blocks_ad, implicit_kick  # noqa: E402

from _common import write_csv  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "rod3d_implicit_parts.csv")


def lapack_solve(D, U, b):
    """The block Thomas scan with `jnp.linalg.solve` per block (the alternative)."""
    m = D.shape[-1]
    zero = jnp.zeros((1, m, m), D.dtype)
    Uk, Lk = jnp.concatenate([U, zero]), jnp.concatenate([zero, jnp.swapaxes(U, -1, -2)])

    def forward(carry, inp):
        C_prev, y_prev = carry
        Dk, Lo, Up, bk = inp
        sol = jnp.linalg.solve(Dk - Lo @ C_prev, jnp.concatenate([Up, (bk - Lo @ y_prev)[:, None]], 1))
        return (sol[:, :m], sol[:, m]), (sol[:, :m], sol[:, m])

    _, (C, y) = jax.lax.scan(forward, (jnp.zeros((m, m), D.dtype), jnp.zeros(m, D.dtype)), (D, Lk, Uk, b))
    _, x = jax.lax.scan(lambda xn, inp: (inp[1] - inp[0] @ xn,) * 2, jnp.zeros(m, D.dtype), (C, y), reverse=True)
    return x


def per_iteration(f, *args):
    jax.block_until_ready(f(*args))
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        best = min(best, time.perf_counter() - t0)
    return 1e6 * best / 100


def main():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    rod = jr.RodChannel.reference(0.3)
    rows = []
    for n in (60, 120, 240, 500):
        model = Rod3D(rod, n, control="load", end_load=20.0)
        q, v = model.initial_state(None, lateral_velocity=0.01 * jnp.sin(jnp.linspace(0, 6 * jnp.pi, n + 1)))
        a = model.accelerations(q, v)
        D, U = hessian_blocks(model, q.x, q.Q)
        D = D + 1e6 * jnp.eye(6)[None]
        b = jnp.ones((n + 1, 6))
        loop_solve = lambda solve: jax.jit(lambda D, U, b: jax.lax.fori_loop(0, 100, lambda i, b: solve(D, U, b), b))

        def loop_hessian(hess):
            def body(i, c):  # every entry of D and U read, so that XLA computes all of them
                Dh, Uh = hess(model, q.x + 1e-30 * c, q.Q)
                return c + 1e-20 * (Dh.sum((1, 2)) + jnp.pad(Uh.sum((1, 2)), (0, 1)))[:, None]
            return jax.jit(lambda: jax.lax.fori_loop(0, 100, body, jnp.zeros((n + 1, 3))))

        kick = jax.jit(lambda v: jax.lax.fori_loop(
            0, 100, lambda i, v: implicit_kick(model, Rod3DPosition(q.x + 1e-9 * v.v, q.Q), v, a, 1e-5, 5e-5, 0.25, 0.1), v))
        row = dict(commit=commit, n=n,
                   solve_cholesky_us=round(per_iteration(loop_solve(block_tridiagonal_solve), D, U, b), 1),
                   solve_lapack_us=round(per_iteration(loop_solve(lapack_solve), D, U, b), 1),
                   hessian_closed_form_us=round(per_iteration(loop_hessian(hessian_blocks)), 1),
                   hessian_ad_us=round(per_iteration(loop_hessian(hessian_blocks_ad)), 1),
                   implicit_kick_us=round(per_iteration(kick, v), 1))
        rows.append(row)
        print(row, flush=True)
    write_csv(OUT, rows)


if __name__ == "__main__":
    main()
