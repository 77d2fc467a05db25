"""What each root finder of `jaxrod.boundary` reports, read against the points it evaluated: the
evaluation count, the final bracket and the value and slope it last saw, the result code of a
bad bracket, of the iteration cap and of a tolerance met, and where its bisection steps fall.
The evaluated points are recorded by an ordered `jax.debug.callback` inside the indicator, so
every check compares the finder's report with what it actually ran."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod import boundary as bd

OK, CAP, BAD, NONFINITE = (bd.ROOT_RESULTS.converged, bd.ROOT_RESULTS.max_iterations,
                           bd.ROOT_RESULTS.invalid_bracket, bd.ROOT_RESULTS.nonfinite)


def recorded(f, values=None):
    """`f` and the list of points it is evaluated at, in order (and into `values`, if given, the
    value of f at each)."""
    seen = []

    def g(x):
        jax.debug.callback(lambda v: seen.append(float(v)), x, ordered=True)
        y = f(x)
        if values is not None:
            jax.debug.callback(lambda v: values.append(float(v)), y, ordered=True)
        return y

    return g, seen


def departure(root=1.0, rate=50.0):
    """A departure indicator: buckled above `root` with u = rate·(x − root), no number below."""
    return lambda x: (x > root, jnp.where(x > root, rate * (x - root), jnp.nan))


@pytest.mark.parametrize("start", ["hi", "lo", "mid"])
def test_newton_counts_every_evaluation_and_ends_with_the_last_point_it_saw(start):
    """x³ = 2 on [1, 2]: `evaluations` is the number of runs of g (the two bracket ends, the
    midpoint for `start="mid"`, one per iteration); `value` and `derivative` are g and g′ at the
    last point run; the bracket holds the root with g(lo) ≤ 0 ≤ g(hi) (the last point's g is 0 to
    rounding here, and which end it becomes depends on how XLA fuses x³ − 2: not asserted)."""
    values = []
    g, seen = recorded(lambda x: x**3 - 2.0, values)
    r = bd.safeguarded_newton(g, 1.0, 2.0, rtol=1e-12, start=start)
    assert int(r.result) == OK and float(r.root) == pytest.approx(2 ** (1 / 3), rel=1e-12)
    assert int(r.evaluations) == len(seen) >= 3 + (start == "mid")
    last = seen[-1]
    assert float(r.value) == pytest.approx(last**3 - 2.0, abs=1e-15)
    assert float(r.derivative) == pytest.approx(3 * last**2, rel=1e-15)
    g_at = dict(zip(seen, values))
    lo, hi = float(r.lo), float(r.hi)
    assert g_at[lo] <= 0 <= g_at[hi] and lo <= float(r.root) <= hi


def test_a_coarser_newton_tolerance_stops_sooner_and_still_meets_it():
    """Newton on eˣ = 3 over [0, 5] at rtol 1e-3 stops after fewer runs than at 1e-12, its root
    within 1e-3 relative; at 1e-12 it is the exact ln 3 to 1e-12."""
    g = lambda x: jnp.exp(x) - 3.0  # noqa: E731
    coarse, fine = (bd.safeguarded_newton(g, 0.0, 5.0, rtol=t) for t in (1e-3, 1e-12))
    assert int(coarse.result) == int(fine.result) == OK
    assert int(coarse.evaluations) < int(fine.evaluations)
    assert float(coarse.root) == pytest.approx(math.log(3), rel=1e-3)
    assert float(fine.root) == pytest.approx(math.log(3), rel=1e-12)


def test_newton_reports_a_bracket_without_a_sign_change_the_cap_and_a_failed_run():
    """g > 0 at both ends: `invalid_bracket` after the two bracket runs. A cap of one iteration
    on a far root: `max_iterations`. A g that is NaN inside the bracket: `nonfinite`."""
    r = bd.safeguarded_newton(lambda x: x**2 + 1.0, 1.0, 2.0)
    assert int(r.result) == BAD and int(r.evaluations) == 2
    r = bd.safeguarded_newton(lambda x: jnp.exp(x) - 3.0, 0.0, 50.0, max_iter=1)
    assert int(r.result) == CAP and int(r.evaluations) == 3
    r = bd.safeguarded_newton(lambda x: jnp.where((x > 0.4) & (x < 0.6), jnp.nan, x - 0.5), 0.0, 1.0,
                              start="mid", geometric=False)
    assert int(r.result) == NONFINITE


def test_newton_with_an_absolute_tolerance_finds_a_root_at_zero():
    """x³ + x = 0 on [−1, 2]: with `atol` 1e-6 the search stops at |x*| ≤ 1e-6 and says
    converged; a relative tolerance alone cannot be met next to 0 (each Newton step there is as
    long as x), so a cap of 5 iterations ends it with `max_iterations`."""
    g = lambda x: x**3 + x  # noqa: E731
    r = bd.safeguarded_newton(g, -1.0, 2.0, rtol=0.0, atol=1e-6, max_iter=8)
    assert int(r.result) == OK and abs(float(r.root)) <= 1e-6
    r = bd.safeguarded_newton(g, -1.0, 2.0, rtol=1e-3, max_iter=5)
    assert int(r.result) == CAP


def test_newton_on_a_line_lands_on_its_root_and_stops_there():
    """g(x) = x on [−1, 1]: one Newton step from 1 lands exactly on the root 0, which then becomes
    the bracket's lower end (g(0) = 0 ≤ 0); a root on the bracket's end is a root, so the search
    stops there, converged in three runs (the two ends and 0), though no relative tolerance can
    be met at 0."""
    g, seen = recorded(lambda x: x)
    r = bd.safeguarded_newton(g, -1.0, 1.0, rtol=1e-10)
    assert int(r.result) == OK and float(r.root) == 0.0 and float(r.lo) == 0.0
    assert seen == [-1.0, 1.0, 0.0] and int(r.evaluations) == 3


@pytest.mark.parametrize("geometric", [True, False])
def test_bisection_halves_the_bracket_in_the_space_it_is_asked_for(geometric):
    """The label x > 10 on [1, 10⁴]: the first run inside the bracket is at √(lo·hi) = 100 for
    a geometric search, (lo + hi)/2 otherwise; every run after halves the bracket in that
    space. `evaluations` counts the two ends and every midpoint; the root is the bracket's
    middle and `value` the last label seen (1.0 above the root, 0.0 below)."""
    g, seen = recorded(lambda x: x > 10.0)
    r = bd.bisection(g, 1.0, 1e4, rtol=1e-6, geometric=geometric)
    assert int(r.result) == OK and int(r.evaluations) == len(seen)
    assert seen[:2] == [1.0, 1e4]
    assert seen[2] == pytest.approx(100.0 if geometric else 5000.5, rel=1e-14)
    lo, hi = float(r.lo), float(r.hi)
    assert lo <= 10.0 < hi and hi - lo <= 1e-6 * hi
    assert float(r.root) == pytest.approx(0.5 * (lo + hi), rel=1e-15)
    assert float(r.value) == (1.0 if seen[-1] > 10.0 else 0.0)
    assert np.isnan(float(r.derivative))


def test_bisection_reports_a_bracket_without_a_sign_change_and_the_cap():
    """A label true at both ends (or false at both): `invalid_bracket` after two runs; a cap of
    3 midpoints on a wide bracket: `max_iterations` after 5 runs, the bracket still holding the
    root."""
    for lo, hi in ((20.0, 40.0), (1.0, 5.0)):
        r = bd.bisection(lambda x: x > 10.0, lo, hi)
        assert int(r.result) == BAD and int(r.evaluations) == 2
    r = bd.bisection(lambda x: x > 10.0, 1.0, 1e4, max_iter=3)
    assert int(r.result) == CAP and int(r.evaluations) == 5 and float(r.lo) <= 10.0 < float(r.hi)


def test_bisection_takes_a_label_at_zero_as_stable_and_a_value_above_zero_as_not():
    """g(lo) = 0 is on the stable side (g(lo) ≤ 0 < g(hi)); g(hi) = 0 is not above the root."""
    assert int(bd.bisection(lambda x: x - 1.0, 1.0, 3.0, rtol=1e-6).result) == OK
    assert int(bd.bisection(lambda x: x - 3.0, 1.0, 3.0, rtol=1e-6).result) == BAD


def test_departure_search_reports_what_it_ran():
    """u = 50(x − 1) above x* = 1, from [0.5, 4]: `evaluations` is the number of runs; `hi` is
    the lowest buckled point run and `lo` the highest stable one (or the trusted lower end);
    `value` is u there and `derivative` the rate 50 (the secant of two buckled runs on a linear
    branch); the root is x* to rtol."""
    ev, seen = recorded(departure())
    r = bd.departure_secant(ev, 0.5, 4.0, 1e3, rtol=1e-8)
    assert int(r.result) == OK and float(r.root) == pytest.approx(1.0, rel=1e-8)
    assert int(r.evaluations) == len(seen)
    buckled, stable = [x for x in seen if x > 1.0], [x for x in seen if x <= 1.0]
    assert float(r.hi) == min(buckled) and float(r.lo) == max(stable + [0.5])
    assert float(r.value) == pytest.approx(50.0 * (min(buckled) - 1.0), rel=1e-12)
    assert float(r.derivative) == pytest.approx(50.0, rel=1e-6)


def test_departure_search_steps_up_from_a_stable_start_by_a_quarter_at_a_time():
    """Started at a stable x = 1 below the root 3 (bracket [0.5, 4]): before the first buckled
    run each step grows x by 25 % (a step to the bracket's geometric middle would be longer)."""
    ev, seen = recorded(departure(root=3.0))
    r = bd.departure_secant(ev, 0.5, 4.0, 1e3, start=1.0, rtol=1e-6)
    assert int(r.result) == OK and float(r.root) == pytest.approx(3.0, rel=1e-6)
    first_buckled = next(i for i, x in enumerate(seen) if x > 3.0)
    assert first_buckled >= 2
    np.testing.assert_allclose(seen[:first_buckled + 1], 1.25 ** np.arange(first_buckled + 1), rtol=1e-12)


def test_departure_search_takes_the_rate_bound_as_a_number_or_a_function():
    """A constant bound given as a function of x finds the same root in the same runs as the
    number; a bound below the true rate (20 < 50) still converges from the buckled side."""
    f = departure()
    a = bd.departure_secant(f, 0.5, 4.0, 80.0, rtol=1e-8)
    b = bd.departure_secant(f, 0.5, 4.0, lambda x: 80.0 + 0.0 * x, rtol=1e-8)
    assert int(a.evaluations) == int(b.evaluations) and float(a.root) == float(b.root)
    c = bd.departure_secant(f, 0.5, 4.0, 20.0, rtol=1e-8)
    assert int(c.result) == OK and float(c.root) == pytest.approx(1.0, rel=1e-8)


def test_departure_search_reports_a_bracket_without_the_root_and_the_cap():
    """A root below the bracket (every run buckles, down to `lo`): `invalid_bracket` and no root;
    a root above it (the upper end stable): the same; a cap of 2 runs: `max_iterations`, no
    root, the bracket of the runs made."""
    for root in (0.2, 6.0):
        r = bd.departure_secant(departure(root), 0.5, 4.0, 1e3, rtol=1e-6)
        assert int(r.result) == BAD and np.isnan(float(r.root))
    r = bd.departure_secant(departure(), 0.5, 4.0, 1.0, rtol=1e-10, max_iter=2)
    assert int(r.result) == CAP and np.isnan(float(r.root)) and int(r.evaluations) == 2
    assert 0.5 <= float(r.lo) <= 1.0 < float(r.hi) <= 4.0


def test_departure_search_started_outside_the_bracket_starts_at_its_end():
    """A start above `hi` (or below `lo`) is clipped to the bracket: its first run is at that
    end."""
    for start, end in ((9.0, 4.0), (0.1, 0.5)):
        ev, seen = recorded(departure())
        bd.departure_secant(ev, 0.5, 4.0, 1e3, start=start, rtol=1e-6)
        assert seen[0] == end


def test_every_finder_returns_float64_roots_and_int32_codes():
    """The fields' dtypes are those of `RootResult` for every finder (x64 on): float roots and
    brackets, 32-bit integer counts and codes."""
    results = [bd.safeguarded_newton(lambda x: x - 1.0, 0, 4),
               bd.bisection(lambda x: x > 1.0, 0, 4),
               bd.departure_secant(departure(), 0, 4, 1e3)]
    for r in results:
        assert r.root.dtype == r.lo.dtype == r.hi.dtype == jnp.float64
        assert r.evaluations.dtype == r.result.dtype == jnp.int32


def test_departure_search_by_default_finds_the_root_to_1e_6():
    """With its default tolerance (1e-6 relative) the search of u = 50(x − 1) from [0.5, 4]
    with the rate bound 10³ gives x* = 1 to 1e-6 (the first run's step u/λ alone lands at
    3.85)."""
    r = bd.departure_secant(departure(), 0.5, 4.0, 1e3)
    assert int(r.result) == OK and float(r.root) == pytest.approx(1.0, rel=1e-6)
