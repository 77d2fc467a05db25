"""The root finders and searches of `jaxrod.boundary` on problems with known answers: safeguarded
Newton, bisection and the departure secant on hand-made indicators, the indicators against
exact or independent solutions, and the searches' settings (their own file, so that pytest-xdist
can run them beside tests/test_boundary.py)."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod import boundary as bd
from jaxrod import theory as th

ROD = jr.RodChannel.reference(mu=0.3)


def test_newton_without_a_slope_bisects_geometrically():
    """Where g has no slope (a step), every safeguarded Newton iterate is the geometric midpoint
    of the bracket: the iterates by hand, and the root to the tolerance."""
    c = 0.3
    res = bd.safeguarded_newton(lambda x: jnp.sign(x - c), 1e-3, 1.0, rtol=1e-6, max_iter=200)
    lo, hi, n = 1e-3, 1.0, 0
    while hi - lo > 1e-6 * hi:
        x = math.sqrt(lo * hi)
        lo, hi = (x, hi) if x < c else (lo, x)
        n += 1
    assert abs(float(res.root) - c) <= 2e-6 * c
    assert abs(int(res.evaluations) - n) <= 2  # arithmetic midpoints would take about 20 more


def test_rod_indicator_of_one_mode_is_the_exact_amplitude():
    """g = log(max|θ(T)|/θ_c) of a single-mode scene against the exact solution at T."""
    from jaxrod.models import SingleMode
    from jaxrod.models.single_mode import exact_solution

    scene = jr.scene.Scene(ROD, 5.0, jr.registry.make_perturbation("sine", 0.03), kind="mode")
    m = SingleMode.from_rod(ROD, 6, F=scene.F)
    q0, v0 = scene.initial_state()
    A = exact_solution(q0, v0, m.k, m.f_s, m.f_d, 0.2)[0]
    g = bd.rod_indicator(scene, 0.2)
    assert float(g) == pytest.approx(math.log(abs(float(A)) / 0.5), abs=1e-3)


def test_critical_load_without_sensitivities_runs_no_tangents(monkeypatch):
    """`sensitivities=()`: no forward-mode run for them (the search's runs alone)."""
    import jaxrod.boundary.search as search

    def no(*a, **k):
        raise AssertionError("departure_sensitivities called without sensitivities")

    monkeypatch.setattr(search, "departure_sensitivities", no)
    res, sens = bd.critical_load(ROD, 0.02, model="field", n=24, dt=jr.scene.Scene(ROD, 2.0, kind="field", n=24).step(),
                                 bracket=(0.1, 20.0), rtol=1e-2, sensitivities=())
    assert sens == {} and int(res.result) == 0


def test_bisection_stops_at_its_tolerance():
    """Bisection on a boolean label: one run per halving (in log x) until the bracket is within
    rtol, the geometric midpoints by hand."""
    c = 0.3
    res = bd.bisection(lambda x: x > c, 1e-3, 1.0, rtol=1e-4, max_iter=200)
    lo, hi, n = 1e-3, 1.0, 0
    while hi - lo > 1e-4 * hi:
        x = math.sqrt(lo * hi)
        lo, hi = (lo, x) if x > c else (x, hi)
        n += 1
    assert float(res.lo) == pytest.approx(lo, rel=1e-12) and float(res.hi) == pytest.approx(hi, rel=1e-12)
    assert abs(int(res.evaluations) - n) <= 2 and int(res.result) == 0


def test_newton_starts_where_it_is_told():
    """g = e^{8x} − e^{2.4} (root 0.3) on [0.1, 1]: Newton from `hi` creeps down the steep convex
    side (12 evaluations, measured), from the geometric midpoint 0.316 it is next to the root
    (7, the midpoint's own included)."""
    g = lambda x: jnp.exp(8.0 * x) - math.exp(2.4)
    from_hi = bd.safeguarded_newton(g, 0.1, 1.0, rtol=1e-10, start="hi")
    from_mid = bd.safeguarded_newton(g, 0.1, 1.0, rtol=1e-10, start="mid")
    assert float(from_hi.root) == pytest.approx(0.3, rel=1e-10) and float(from_mid.root) == pytest.approx(0.3, rel=1e-10)
    assert int(from_hi.evaluations) > int(from_mid.evaluations) + 2


def test_a_vmapped_curve_keeps_its_bracket():
    """`boundary_curve` without continuation searches in the `bracket` it is given: one that
    lies below every root is reported invalid at every load (single mode: Newton on the exact
    solution)."""
    r, _ = bd.boundary_curve(ROD, [2.0, 8.0], model="mode", bracket=(1e-4, 1e-3), sensitivities=())
    assert np.all(np.asarray(r.result) == bd.ROOT_RESULTS.invalid_bracket)  # v₀* is 15-45 mm/s


def test_smooth_indicator_against_an_independent_integration():
    """x'' − x + tanh(x'/ε') = 0 (units x = A/a, τ = λt, ε' = ε/(λa)) from x = 0, x' = Ȧ₀/(aλ):
    the indicator is x(horizon) − 1, here against SciPy's Radau at tight tolerances."""
    from scipy.integrate import solve_ivp

    k, f, eps, Ad0, T = -4.0, 6.0, 0.05, 3.5, 4.0  # a λ = 3: ε' = ε/(aλ), not ε·aλ
    lam, a = math.sqrt(4.0), f / 4.0
    e = eps / (a * lam)
    sol = solve_ivp(lambda t, y: [y[1], y[0] - math.tanh(y[1] / e)], (0, T), [0.0, Ad0 / (a * lam)],
                    method="Radau", rtol=1e-11, atol=1e-13)
    g = bd.smooth_single_mode_indicator(jnp.asarray(Ad0), jnp.asarray(k), jnp.asarray(f), eps, horizon=T)
    assert float(g) == pytest.approx(sol.y[0, -1] - 1.0, rel=1e-6, abs=1e-8)


def test_critical_load_of_another_mode_is_its_p7():
    """The single mode's ΔF* for mode 7 (above the critical mode's F⁰₆): P7 of mode 7."""
    v0 = 15e-3
    dF = float(th.critical_load_velocity(ROD, 7, v0 / ROD.R) - th.reference_load(ROD))
    res, _ = bd.critical_load(ROD, v0, model="mode", mode=7, bracket=(dF / 3, 3 * dF), sensitivities=())
    assert float(res.root) == pytest.approx(dF, rel=1e-6)


def test_a_traced_load_without_n_and_dt_is_refused_by_name():
    with pytest.raises(ValueError, match=r"^pass n and dt explicitly when the rod or the load is traced \(e\.g\. "
                                         r"under vmap\): they are static settings\."):
        jax.vmap(lambda dF: bd.critical_velocity(ROD, dF, model="field", sensitivities=())[0].root)(jnp.array([2.0, 4.0]))


@pytest.mark.parametrize("shape, most", [("sqrt", 24), ("log", 16)])
def test_departure_secant_recovers_from_overshoots(shape, most):
    """A concave departure rate (u = √(x − 1) or log(1 + 50(x − 1)) above x* = 1): the secant
    overshoots into the stable side and steps back up a fraction of the way, half of it after
    two stable runs in a row. The root to rtol, in at most `most` runs (measured 23 and 15;
    stepping back 1.5 of the way instead of 0.5 takes 29 and 20)."""
    f = jnp.sqrt if shape == "sqrt" else (lambda d: jnp.log1p(50 * d))
    ev = lambda x: (x > 1.0, jnp.where(x > 1.0, f(jnp.maximum(x - 1.0, 0.0)), jnp.nan))
    r = bd.departure_secant(ev, 0.5, 4.0, 1e3, rtol=1e-6, max_iter=60)
    assert int(r.result) == 0 and float(r.root) == pytest.approx(1.0, rel=2e-6)
    assert int(r.evaluations) <= most


def test_a_confirmed_departure_root_lies_in_a_label_bracket():
    """A rate that vanishes faster than linearly at x* = 1 (u = (x − 1)², as the 3D rod's near
    its root): from a buckled run at 1.03 the step u/λ (λ the rate bound) falls below rtol and
    the plain search ends there, 3 % above the root (2 runs). With `confirm` a stable run just
    below the lowest buckled point must hold it: the root then lies in a label bracket of
    relative width rtol around x* (5 runs, measured)."""
    ev = lambda x: (x > 1.0, jnp.where(x > 1.0, jnp.maximum(x - 1.0, 0.0) ** 2, jnp.nan))
    kw = dict(start=1.03, rtol=1e-2, max_iter=40)
    plain = bd.departure_secant(ev, 0.5, 4.0, 1e3, **kw)
    assert int(plain.result) == 0 and float(plain.root) > 1.01  # converged, but off by more than rtol
    held = bd.departure_secant(ev, 0.5, 4.0, 1e3, confirm=True, **kw)
    lo, hi, root = float(held.lo), float(held.hi), float(held.root)
    assert int(held.result) == 0 and lo <= 1.0 < hi and hi - lo <= 1e-2 * hi and lo <= root <= hi
    # the same with an absolute tolerance instead (as the load search on log ΔF asks): width ≤ atol
    held = bd.departure_secant(ev, 0.5, 4.0, 1e3, confirm=True, start=1.03, rtol=0.0, atol=1e-2, max_iter=40)
    lo, hi, root = float(held.lo), float(held.hi), float(held.root)
    assert int(held.result) == 0 and lo <= 1.0 < hi and hi - lo <= 1e-2 and lo <= root <= hi


def test_a_failed_run_ends_a_search_instead_of_counting_as_stable():
    """A run that fails (NaN label: its state became non-finite) says nothing about stability:
    bisection and the departure search stop there with `nonfinite` and no root, keeping the
    bracket of the runs that worked. Here x > 2.5 fails and the root is 0.3: counted as stable,
    the failed end would have made the bracket invalid (or, below the root, moved lo past it)."""
    c, bad = 0.3, 2.5

    def label(x):
        return jnp.where(x > bad, jnp.nan, jnp.where(x > c, 1.0, 0.0))

    res = bd.bisection(label, 1e-3, 4.0, rtol=1e-4)
    assert int(res.result) == bd.ROOT_RESULTS.nonfinite and int(res.evaluations) == 2
    # a failure inside the bracket: at the first (geometric) midpoint, √0.002, the search stops
    res = bd.bisection(lambda x: jnp.where(jnp.abs(x - math.sqrt(2e-3)) < 1e-6, jnp.nan, label(x)), 1e-3, 2.0, rtol=1e-4)
    assert int(res.result) == bd.ROOT_RESULTS.nonfinite and float(res.lo) == pytest.approx(1e-3)
    assert float(res.hi) == pytest.approx(2.0) and int(res.evaluations) == 3
    # the departure search, started at a failing point and from one that works
    ev = lambda x: (label(x), jnp.where(x > c, 50.0 * (x - c), jnp.nan))  # noqa: E731
    r = bd.departure_secant(ev, 0.01, 4.0, 1e3, start=3.0, rtol=1e-6)
    assert int(r.result) == bd.ROOT_RESULTS.nonfinite and np.isnan(float(r.root)) and int(r.evaluations) == 1
    assert float(r.lo) == pytest.approx(0.01) and float(r.hi) == pytest.approx(4.0)
    ok = bd.departure_secant(ev, 0.01, 4.0, 1e3, start=2.0, rtol=1e-6)
    assert int(ok.result) == 0 and float(ok.root) == pytest.approx(c, rel=1e-5)



def test_critical_load_brackets_to_rtol_in_the_load():
    """The load search runs on log ΔF, where a relative `rtol` in ΔF is an absolute log1p(rtol):
    the field model's label bisection at a load of tens of N ends with a bracket of relative
    width ≤ rtol (not rtol·|log ΔF|, 3.4·rtol at 30 N), and a label with its root at 1 N
    (log ΔF* = 0, where a tolerance relative to log ΔF never closes) converges like any other."""
    rod = jr.RodChannel.reference(mu=1.0)
    res, _ = bd.critical_load(rod, 15e-3, model="field", n=16, method="bisection", bracket=(5.0, 200.0),
                              rtol=1e-2, t1=0.3, sensitivities=())
    assert int(res.result) == 0 and float(res.lo) > 5.0 and float(res.hi) / float(res.lo) - 1 <= 1e-2
    for target in (1.0, 30.0):
        lab = lambda y, t=target: y > math.log(t)  # a label with its root at `target` [N], on log ΔF
        r = bd.bisection(lab, math.log(target / 1.5), math.log(target * 1.5), 0.0, 60, geometric=False,
                         atol=math.log1p(1e-2))
        lo, hi = math.exp(float(r.lo)), math.exp(float(r.hi))
        assert int(r.result) == 0 and lo <= target <= hi and hi / lo - 1 <= 1e-2


def test_safeguarded_newton_by_default_finds_the_root_to_1e_10():
    """With its default tolerance (1e-10 relative) the search of x³ = 0.1 on [0.1, 1] gives the
    cube root to 1e-10 relative (a Newton step from 1 alone lands at 0.7)."""
    res = bd.safeguarded_newton(lambda x: x**3 - 0.1, 0.1, 1.0)
    assert int(res.result) == 0
    assert float(res.root) == pytest.approx(0.1 ** (1 / 3), rel=1e-10)


def test_the_three_root_finders_results_can_be_chosen_between_inside_jit():
    """Newton, bisection and the departure search return `RootResult`s of one structure and
    dtypes, so a jitted search can pick its method per case with `lax.switch`; each finds the
    root x* = 1 of its own view of one boundary and reports converged (0)."""
    label = lambda x: jnp.where(x > 1.0, 1.0, 0.0)  # noqa: E731
    ev = lambda x: (x > 1.0, jnp.where(x > 1.0, 50.0 * (x - 1.0), jnp.nan))  # noqa: E731
    smooth = lambda x: x**3 - 1.0  # noqa: E731
    branches = [lambda: bd.safeguarded_newton(smooth, 0.5, 4.0, rtol=1e-10),
                lambda: bd.bisection(label, 0.5, 4.0, rtol=1e-6),
                lambda: bd.departure_secant(ev, 0.5, 4.0, 1e3, rtol=1e-6)]
    pick = jax.jit(lambda i: jax.lax.switch(i, branches))
    for i in range(3):
        r = pick(i)
        assert int(r.result) == bd.ROOT_RESULTS.converged and float(r.root) == pytest.approx(1.0, rel=1e-5)


def test_the_point_searches_take_the_horizon_of_the_curves_by_default(monkeypatch):
    """`critical_velocity` and `critical_load` run each label to the same default horizon `t1` as
    `boundary_curve` and `critical_load_curve`, whose points they are: the model's `search_horizon`
    for the critical velocity (`None` until `_critical` resolves it), 2 s for the critical load."""
    import inspect

    from jaxrod.boundary import search

    seen = []
    monkeypatch.setattr(search, "_critical", lambda *a, **kw: seen.append(kw["t1"]))
    bd.critical_velocity(ROD, 5.0)
    bd.critical_load(ROD, 0.02)
    default = lambda f: inspect.signature(f).parameters["t1"].default  # noqa: E731
    assert seen == [default(bd.boundary_curve), default(bd.critical_load_curve)] == [None, 2.0]


@pytest.mark.parametrize("finder", ["newton", "bisection"])
def test_a_bracket_of_whole_numbers_is_searched_as_floats(finder):
    """A bracket given as ints (Newton [0, 4], bisection [1, 4]): the search runs in the default float
    dtype and finds x³ = 2."""
    g = lambda x: x**3 - 2.0  # noqa: E731
    if finder == "newton":
        r = bd.safeguarded_newton(g, 0, 4, rtol=1e-12)
    else:
        r = bd.bisection(lambda x: jnp.where(g(x) > 0, 1.0, 0.0), 1, 4, rtol=1e-12)
    assert r.root.dtype == r.lo.dtype == jnp.result_type(float)
    assert int(r.result) == bd.ROOT_RESULTS.converged and float(r.root) == pytest.approx(2 ** (1 / 3), rel=1e-9)


def _counted(label):
    """`label` and a list that records every point it is called at (concrete calls only)."""
    seen = []

    def g(x):
        seen.append(float(x))
        return label(x)

    return g, seen


@pytest.mark.parametrize("root, guess", [(1.0, 1.01), (1.0, 3.0), (1.0, 0.2), (5e-3, 1.0)])
def test_expanding_bisection_brackets_the_root_from_any_guess(root, guess):
    """From a prediction on either side of the root, near or a decade off: the final bracket holds
    the root and is within rtol; the evaluations are the labels taken, each one a move or a halving
    that the algorithm prescribes (by hand: the ends, then squaring steps, then geometric halves)."""
    g, seen = _counted(lambda x: x > root)
    with jax.disable_jit():
        res = bd.expanding_bisection(g, guess, width=0.04, rtol=1e-2, max_iter=60, floor=1e-6, ceiling=1e3)
    assert int(res.result) == bd.ROOT_RESULTS.converged
    assert float(res.lo) <= root < float(res.hi) and float(res.hi) - float(res.lo) <= 1e-2 * float(res.hi)
    assert int(res.evaluations) == len(seen)
    # the same algorithm by hand
    lo, hi = guess * 0.96, guess * 1.04
    b_lo, b_hi, step, ref = lo > root, hi > root, 1.08, [lo, hi]
    while b_lo == b_hi:
        if b_lo:
            hi, lo = lo, max(lo / step, 1e-6)
            b_lo = lo > root
            ref.append(lo)
        else:
            lo, hi = hi, min(hi * step, 1e3)
            b_hi = hi > root
            ref.append(hi)
        step *= step
    while hi - lo > 1e-2 * hi:
        mid = math.sqrt(lo * hi)
        ref.append(mid)
        lo, hi = (lo, mid) if mid > root else (mid, hi)
    np.testing.assert_allclose(seen, ref, rtol=1e-12)


def test_expanding_bisection_is_one_call_of_the_label_in_the_program():
    """The label (a whole simulation for the 3D rod) is traced once, however many it takes."""
    traces = []
    f = lambda x: (traces.append(1), x > 0.3)[1]
    res = jax.jit(lambda x0: bd.expanding_bisection(f, x0, rtol=1e-3, max_iter=40))(0.5)
    assert len(traces) == 1 and int(res.evaluations) > 5
    assert float(res.lo) <= 0.3 < float(res.hi)


def test_expanding_bisection_reports_failures_in_its_result():
    """A failed run (NaN) ends the search as nonfinite; a root outside [floor, ceiling] is an
    invalid bracket (both ends alike at the limit); a cap on the labels is max_iterations."""
    nan_above = lambda x: jnp.where(x > 1.2, jnp.nan, jnp.where(x > 1.1, 1.0, 0.0))
    res = bd.expanding_bisection(nan_above, 0.5, rtol=1e-3, max_iter=60, floor=1e-3, ceiling=10.0)
    assert int(res.result) == bd.ROOT_RESULTS.nonfinite
    res = bd.expanding_bisection(lambda x: x > 50.0, 1.0, rtol=1e-3, max_iter=60, floor=1e-3, ceiling=10.0)
    assert int(res.result) == bd.ROOT_RESULTS.invalid_bracket and float(res.hi) == 10.0
    res = bd.expanding_bisection(lambda x: x > 1e-4, 1.0, rtol=1e-3, max_iter=60, floor=1e-3, ceiling=10.0)
    assert int(res.result) == bd.ROOT_RESULTS.invalid_bracket and float(res.lo) == pytest.approx(1e-3)
    res = bd.expanding_bisection(lambda x: x > 0.37, 1.0, rtol=1e-6, max_iter=6, floor=1e-3, ceiling=10.0)
    assert int(res.result) == bd.ROOT_RESULTS.max_iterations and int(res.evaluations) == 6


def test_a_curve_of_the_3d_rod_runs_to_its_search_horizon(monkeypatch):
    """`boundary_curve` without `t1` runs the 3D rod's labels to its recipe's `search_horizon` (0.4 s, the
    horizon its E3 brackets were checked at against 2 s) and a given `t1` as given."""
    from jaxrod.boundary import curves
    from jaxrod.rod3d import Rod3DRecipe

    seen = []
    monkeypatch.setattr(curves, "_seeded_bisection", lambda *a, **kw: seen.append(kw["t1"]))
    bd.boundary_curve(ROD, [5.0], model="rod3d")
    bd.boundary_curve(ROD, [5.0], model="rod3d", t1=1.5)
    assert seen == [Rod3DRecipe.search_horizon, 1.5] and Rod3DRecipe.search_horizon == 0.4
