"""Symmetric positive definite block-tridiagonal linear systems, solved in O(n).

The implicit step of the 3D rod solves (M + βh²H) Δ = b, where the Hessian H of a discrete rod
couples only neighbouring nodes and segments: ordered as blocks (x_k, φ_k) of six unknowns it is
block tridiagonal. `block_tridiagonal_solve` factors it by the block Thomas algorithm (a block
Cholesky: Sₖ = Dₖ − Uₖ₋₁ᵀ Sₖ₋₁⁻¹ Uₖ₋₁) in one forward and one backward `lax.scan` over the
blocks, each 6×6 Cholesky factor and triangular solve written out entry by entry: a small
loop body that XLA compiles as one function on the CPU (`jaxrod._xla`), much faster than
the same scan with `jnp.linalg.solve` (LAPACK) for each block (`benchmarks/rod3d_implicit_parts.py`).
A parallel (cyclic) reduction would take log₂ n levels of batched 6×6 products but compiles each
level separately; the scan is the smallest program.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

__all__ = ["block_tridiagonal_solve", "block_tridiagonal_matvec", "block_tridiagonal_factor", "block_tridiagonal_factor_solve"]


def _cholesky(S, m: int):
    """The lower Cholesky factor of the m×m matrix `S` as a list of rows of scalars (entries
    above the diagonal `None`); a pivot that is not positive gives NaN (and so a non-finite
    state, which the run reports), never a silent answer."""
    L = [[None] * m for _ in range(m)]
    for j in range(m):
        s = S[j, j] - sum(L[j][k] * L[j][k] for k in range(j))
        L[j][j] = jnp.sqrt(jnp.where(s > 0, s, jnp.nan))
        for i in range(j + 1, m):
            L[i][j] = (S[i, j] - sum(L[i][k] * L[j][k] for k in range(j))) / L[j][j]
    return L


def _cholesky_solve(L, B, m: int):
    """(L Lᵀ)⁻¹ B for the factor `L` of `_cholesky` and B of shape (m, r)."""
    y = [None] * m
    for i in range(m):
        y[i] = (B[i] - sum(L[i][k] * y[k] for k in range(i))) / L[i][i]
    x = [None] * m
    for i in reversed(range(m)):
        x[i] = (y[i] - sum(L[k][i] * x[k] for k in range(i + 1, m))) / L[i][i]
    return jnp.stack(x)


def block_tridiagonal_solve(D: Float[Array, "nb m m"], U: Float[Array, "nb1 m m"],
                            b: Float[Array, "nb m"]) -> Float[Array, "nb m"]:
    """x with A x = b for the symmetric positive definite block-tridiagonal A whose diagonal
    blocks are `D` (nb, m, m) and whose blocks above the diagonal are `U` (nb − 1, m, m)
    (block (k, k + 1) = Uₖ, block (k + 1, k) = Uₖᵀ). O(nb m³) operations in two scans; NaN where
    A is not positive definite."""
    m = D.shape[-1]
    zero = jnp.zeros((1, m, m), D.dtype)
    Uk = jnp.concatenate([U, zero])  # block (k, k + 1), none after the last
    Lk = jnp.concatenate([zero, jnp.swapaxes(U, -1, -2)])  # block (k, k − 1)

    def forward(carry, inp):
        C_prev, y_prev = carry
        Dk, Lo, Up, bk = inp
        S = Dk - Lo @ C_prev
        sol = _cholesky_solve(_cholesky(S, m), jnp.concatenate([Up, (bk - Lo @ y_prev)[:, None]], 1), m)
        C, y = sol[:, :m], sol[:, m]
        return (C, y), (C, y)

    _, (C, y) = jax.lax.scan(forward, (jnp.zeros((m, m), D.dtype), jnp.zeros(m, D.dtype)), (D, Lk, Uk, b))
    return _back_substitute(C, y)


def _back_substitute(C, y):
    """xₖ = yₖ − Cₖ xₖ₊₁ from the last block up: the block Thomas algorithm's backward scan."""

    def backward(x_next, inp):
        Ck, yk = inp
        x = yk - Ck @ x_next
        return x, x

    _, x = jax.lax.scan(backward, jnp.zeros(y.shape[-1], y.dtype), (C, y), reverse=True)
    return x


def block_tridiagonal_matvec(D: Float[Array, "nb m m"], U: Float[Array, "nb1 m m"],
                             x: Float[Array, "nb m"]) -> Float[Array, "nb m"]:
    """A x for the block-tridiagonal A of `block_tridiagonal_solve` (its tests' reference; the 3D
    rod's kick applies its stiffness on component arrays, `jaxrod.rod3d.hessian`)."""
    out = jnp.einsum("kij,kj->ki", D, x)
    out = out.at[:-1].add(jnp.einsum("kij,kj->ki", U, x[1:]))
    return out.at[1:].add(jnp.einsum("kji,kj->ki", U, x[:-1]))


def block_tridiagonal_factor(D: Float[Array, "nb m m"], U: Float[Array, "nb1 m m"]):
    """The block Thomas factorisation of `block_tridiagonal_solve`, kept for many right-hand
    sides: the inverses Sₖ⁻¹ of the pivot blocks Sₖ = Dₖ − Uₖ₋₁ᵀ Sₖ₋₁⁻¹ Uₖ₋₁ and Cₖ = Sₖ⁻¹Uₖ
    ((nb, m, m) each; NaN where A is not positive definite). `block_tridiagonal_factor_solve`
    then costs two scans of m×m products."""
    m = D.shape[-1]
    zero = jnp.zeros((1, m, m), D.dtype)
    Uk = jnp.concatenate([U, zero])
    Lk = jnp.concatenate([zero, jnp.swapaxes(U, -1, -2)])
    eye = jnp.eye(m, dtype=D.dtype)

    def forward(C_prev, inp):
        Dk, Lo, Up = inp
        S = Dk - Lo @ C_prev
        sol = _cholesky_solve(_cholesky(S, m), jnp.concatenate([Up, eye], 1), m)
        C, Sinv = sol[:, :m], sol[:, m:]
        return C, (Sinv, C)

    _, (Sinv, C) = jax.lax.scan(forward, jnp.zeros((m, m), D.dtype), (D, Lk, Uk))
    return Sinv, C


def block_tridiagonal_factor_solve(factor, U: Float[Array, "nb1 m m"], b: Float[Array, "nb m"]) -> Float[Array, "nb m"]:
    """x with A x = b from A's factorisation `factor` (`block_tridiagonal_factor`) and its blocks
    above the diagonal `U`."""
    Sinv, C = factor
    m = b.shape[-1]
    Lk = jnp.concatenate([jnp.zeros((1, m, m), b.dtype), jnp.swapaxes(U, -1, -2)])

    def forward(y_prev, inp):
        Si, Lo, bk = inp
        y = Si @ (bk - Lo @ y_prev)
        return y, y

    _, y = jax.lax.scan(forward, jnp.zeros(m, b.dtype), (Sinv, Lk, b))
    return _back_substitute(C, y)
