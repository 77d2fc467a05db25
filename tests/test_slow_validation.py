"""Long validations (`make test-slow`): the field model's default resolution against a fine one."""

import jax
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.boundary.roots import bisection
from jaxrod.scene import Scene


def critical_v0(dF, n, dt):
    rod = jr.RodChannel.reference(mu=0.3)

    def buckles(v0):
        sc = Scene(rod, dF, jr.SineVelocity(v0, 6.0), "field", n, 6, dt)
        return sc.run(t1=2.0, n_save=201, save_state=False).buckled

    r = jax.jit(lambda: bisection(buckles, 1e-3, 0.2, rtol=0.0, max_iter=24))()
    return float(np.sqrt(r.lo * r.hi))


@pytest.mark.slow
@pytest.mark.parametrize("dF", [5.0, 20.0])
def test_default_resolution_is_within_one_percent_of_a_fine_one(dF):
    rod = jr.RodChannel.reference(mu=0.3)
    default = Scene(rod, dF, kind="field")
    v_default = critical_v0(dF, default.size(), default.step())
    fine = Scene(rod, dF, kind="field", n=512)
    v_fine = critical_v0(dF, 512, fine.step())
    print(f"dF = {dF}: default n = {default.size()} -> {1e3 * v_default:.4f} mm/s, n = 512 -> {1e3 * v_fine:.4f} mm/s")
    assert abs(v_default / v_fine - 1) < 0.01
