r"""The local error estimate of one step of the 3D rod's leapfrog schemes, for the step-size
controller of [`jaxrod.AdaptiveImplicitLeapfrog`][].

Newmark's scheme with parameter β (the implicit leapfrog's kick; β = 0 the explicit leapfrog)
has the local displacement error e = (β − 1/6) h² (a_{n+1} − aₙ) + O(h⁴) (Zienkiewicz & Xie's
estimate, from the Taylor series of the exact motion against the scheme's; for the
average-acceleration rule β = ¼ it is h²/12 (a_{n+1} − aₙ)). Here a = M⁻¹F(q) is the node
acceleration of the conservative and external forces at the step's two positions, so a mode of
frequency ω and amplitude A moving through the step contributes e ≈ (ωh)² |Δx| / 12 with
|Δx| ≈ ωhA its displacement in the step: the estimate grows as (ωh)³ A, and it is large exactly
where the step aliases a mode that moves (ωh ≳ 1), small where every moving mode is resolved. The
friction impulses and the implicit kick's own correction are not in `a`: a stick–slip event costs
no rejection by itself, only through the forces it changes.

The error is measured per node (the length of its error vector) against `atol + rtol·|Δx|`
(|Δx| the length of the node's displacement in the step, [m]), as the root mean square over the
nodes not wholly held (diffrax's controllers' norm): `err ≤ 1` accepts the step. Per node, not
per component: a component that barely moves (the axial one of a rod moving sideways) would
otherwise be held to `atol` alone.
"""

from __future__ import annotations

import jax.numpy as jnp

from .state import held_pattern

__all__ = ["step_error"]


def step_error(model, q0, q1, a0, a1, h, beta, rtol, atol):
    """The scaled local error (module docstring) of a step of `h` [s] from the position `q0`
    (forces `a0`) to `q1` (forces `a1`) of the scheme with Newmark's `beta`: a scalar, ≤ 1 for a
    step within the tolerances `rtol` (relative to the node's displacement in the step) and
    `atol` [m]."""
    free = jnp.asarray(~jnp.all(held_pattern(model)[0], -1), q0.x.dtype)  # (n + 1,): a node not wholly held
    dA = (a1.f - a0.f) / model.mass[:, None]
    e = jnp.abs(beta - 1.0 / 6.0) * h * h * jnp.sqrt(jnp.sum(dA * dA, -1))
    dx = q1.x - q0.x
    scale = atol + rtol * jnp.sqrt(jnp.sum(dx * dx, -1))
    ratio = free * e / scale
    return jnp.sqrt(jnp.sum(ratio * ratio) / jnp.maximum(jnp.sum(free), 1.0))
