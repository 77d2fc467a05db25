"""The implicit-function sensitivities of the field model's boundary, against finite differences
of root solves (central, two more searches each, at a tolerance far below the difference):
dv₀*/dΔF of the critical velocity and dΔF*/dR of the critical load (R, the clearance, also moves
F⁰_m* from which ΔF is measured; both searches see it the same way). dv₀*/dμ is checked in
tests/test_boundary.py."""

import jax.numpy as jnp
import pytest

import jaxrod as jr
from jaxrod import boundary as bd

ROD = jr.RodChannel.reference(0.3)
N = 32


@pytest.mark.slow  # 12 s; the same IFT machinery against finite differences in μ runs by default (test_boundary.py)
def test_critical_velocity_sensitivity_to_the_load():
    dF = 2.0
    dt = jr.scene.Scene(ROD, dF, kind="field", n=N).step()
    res, sens = bd.critical_velocity(ROD, dF, model="field", n=N, dt=dt, rtol=1e-10, sensitivities=("dF",))
    assert int(res.result) == 0
    h = 1e-3
    kw = dict(model="field", n=N, dt=dt, rtol=1e-10, sensitivities=())
    up, _ = bd.critical_velocity(ROD, dF + h, **kw)
    dn, _ = bd.critical_velocity(ROD, dF - h, **kw)
    fd = (float(up.root) - float(dn.root)) / (2 * h)
    assert fd < 0  # the boundary falls with the load
    assert float(sens["dF"]) == pytest.approx(fd, rel=2e-3)


def test_critical_load_sensitivity_to_the_clearance():
    v0 = 15e-3
    dt = jr.scene.Scene(ROD, 100.0, kind="field", n=N).step()
    kw = dict(model="field", n=N, dt=dt, rtol=1e-10)
    res, sens = bd.critical_load(ROD, v0, sensitivities=("R",), **kw)
    assert int(res.result) == 0
    R, h = float(ROD.R), 1e-3 * float(ROD.R)
    up, _ = bd.critical_load(jr.RodChannel.reference(0.3, R=R + h), v0, sensitivities=(), **kw)
    dn, _ = bd.critical_load(jr.RodChannel.reference(0.3, R=R - h), v0, sensitivities=(), **kw)
    fd = (float(up.root) - float(dn.root)) / (2 * h)
    assert jnp.isfinite(sens["R"]) and abs(fd) > 0
    assert float(sens["R"]) == pytest.approx(fd, rel=5e-3)
