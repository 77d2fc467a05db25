"""The staircase that brackets F_far,max and the lock-up length at a bounded entry force
(`jaxrod.lockup.staircase`), on a short straight rod whose answer is known in closed form: below
the sinusoidal onset the steady entry force is f_far + X(1 − 1/2n) + drag + bias [F₀] (the soft
string of a straight rod whose held entry node's half segment has no friction, the damping's drag
c·m·v, and the implicit scheme's βh²(EA/l̂)μ_d g, all three tested in tests/test_lockup_push.py),
so at the bound f_c the largest far load is f_c minus the rest, and the lock-up length (no far
load) is where the rest reaches f_c."""


import jax
import pytest

from jaxrod.lockup.push import push_rod, units
from jaxrod.lockup.staircase import BRACKETED, staircase

jax.config.update("jax_enable_x64", True)


# 76 s on a clean clone (2 workers): 14 stages of two lanes at rel = 3 %; the default suite brackets a
# straight rod's answer in 4 stages (tests/test_lockup_drivers_fast.py::test_a_staircase_brackets_both_lanes_...)
@pytest.mark.slow
def test_a_straight_rods_staircase_brackets_the_soft_string_answer():
    rod = push_rod(1.0, 0.02, 1.0)  # L = ℓ; lane μ sets μL/ℓ
    F0, ell = units(rod)
    n, speed, c, f_c = 10, 0.01, 20.0, 1.5
    drag = c * float(rod.rho) * float(rod.L) * speed / F0
    res = staircase(rod, [0.5, 0.6], [0.3, 0.0], speed, f_c=f_c, vary_mu=[False, True], rel=0.03, n=n,
                    first_push=0.02, stage_push=0.01, max_stages=14, saves_per_stage=21, damping=c)
    far, lock = res["lanes"]
    h, l0 = res["dt"], float(rod.L) / n
    per_X = (1 - 0.5 / n) + 0.25 * h * h * float(rod.g) * float(rod.EA) / l0 / F0 * ell / float(rod.L)  # per unit X
    # far-load lane at X = 0.5 (μ = 0.5)
    expect = f_c - 0.5 * per_X - drag
    assert far["status"] == BRACKETED, far["stages"]
    assert far["lo"] <= expect * 1.002 and far["hi"] >= expect * 0.998, (far["lo"], far["hi"], expect)
    assert far["hi"] - far["lo"] <= 0.03 * far["hi"]
    assert all(s["status"] == "sliding" for s in far["stages"])
    # μ lane, no far load: X_lock(1.5) solves X per_X + drag = 1.5
    X_lock = (f_c - drag) / per_X
    assert lock["status"] == BRACKETED, lock["stages"]
    assert lock["lo"] <= X_lock * 1.002 and lock["hi"] >= X_lock * 0.998, (lock["lo"], lock["hi"], X_lock)
    # the parameter only rises, and every lower bound is a steady stage at or below the bound
    for lane in (far, lock):
        p = [s["parameter"] for s in lane["stages"]]
        assert p == sorted(p)
        assert all(s["f_in"] <= f_c for s in lane["stages"][:-1])


@pytest.mark.parametrize("kw, name", [(dict(speed=0.0), "speed"), (dict(f_c=-1.0), "f_c"), (dict(rel=0.0), "rel")])
def test_bad_input_is_refused_by_name(kw, name):
    rod = push_rod(1.0, 0.02, 1.0)
    args = dict(speed=0.01, f_c=1.5, rel=0.03)
    args.update(kw)
    with pytest.raises(ValueError, match=name):
        staircase(rod, [0.5], [0.3], args.pop("speed"), n=6, **args)
