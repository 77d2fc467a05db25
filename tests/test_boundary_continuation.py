"""The continuation along a boundary curve (`jaxrod.boundary.curves._along_curve`), with a
stand-in search whose root is known: the points are searched in increasing order, each started
at the prediction from the roots before it, inside a factor-4 bracket around the prediction; a
bracket that misses the root is searched again over the full bracket, and both searches'
evaluations are counted."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.boundary.roots import ROOT_RESULTS
from jaxrod.boundary.curves import _along_curve, _predict


class _Res(eqx.Module):
    root: jnp.ndarray
    result: jnp.ndarray
    evaluations: jnp.ndarray


class _Search:
    """Root x²/100 at x; no root in a bracket that misses it (5 evaluations either way)."""

    def __init__(self):
        self.calls = []

    def __call__(self, x, lo, hi, start):
        self.calls.append((float(x), lo, hi, start))
        r = float(x) ** 2 / 100
        ok = lo <= r <= hi
        return (_Res(jnp.asarray(r if ok else jnp.nan), jnp.asarray(int(ROOT_RESULTS.converged if ok else
                                                                       ROOT_RESULTS.invalid_bracket)),
                     jnp.asarray(5)), jnp.asarray(float(x)))


def test_points_are_searched_in_order_each_from_the_prediction_of_the_ones_before():
    search = _Search()
    xs = np.array([4.0, 1.0, 2.0])
    res, sens = _along_curve(search, xs, lambda x: x**2 / 100, (1e-4, 10.0), 0.02, False)
    # exact reference: every prediction is the root, each search starts 2 % above it
    assert [c[0] for c in search.calls] == [1.0, 2.0, 4.0]
    for x, lo, hi, start in search.calls:
        r = x**2 / 100
        assert lo == pytest.approx(r / 4) and hi == pytest.approx(r * 4) and start == pytest.approx(1.02 * r)
    np.testing.assert_allclose(res.root, xs**2 / 100)  # returned in the order of xs
    np.testing.assert_array_equal(res.evaluations, [5, 5, 5])
    np.testing.assert_array_equal(sens, xs)


def test_a_bracket_that_misses_the_root_is_searched_again_over_the_full_bracket():
    search = _Search()
    xs = np.array([1.0, 3.0])
    # a reference 10× too small: the first prediction's bracket [r/40, r/2.5] misses the root
    res, _ = _along_curve(search, xs, lambda x: x**2 / 1000, (1e-4, 10.0), 0.0, False)
    assert search.calls[1] == (1.0, 1e-4, 10.0, 10.0)  # the full bracket, started at its top
    assert int(res.result[0]) == int(ROOT_RESULTS.converged) and float(res.root[0]) == pytest.approx(0.01)
    assert int(res.evaluations[0]) == 10  # both searches counted
    # the second point is predicted from the first root (ratio to the reference kept): found at once
    assert len(search.calls) == 3 and int(res.evaluations[1]) == 5


def test_a_point_without_a_root_in_the_full_bracket_is_not_searched_twice_and_not_used_to_predict():
    search = _Search()
    xs = np.array([1.0, 50.0])  # the root at 50 is 25, outside (1e-4, 10)
    res, _ = _along_curve(search, xs, lambda x: x**2 / 100, (1e-4, 10.0), 0.0, False)
    # at x = 50 the factor-4 bracket is clipped to (6.25, 10): searched once more over the full one
    assert search.calls[1][1:3] == (6.25, 10.0) and search.calls[2][1:3] == (1e-4, 10.0)
    assert int(res.result[1]) == int(ROOT_RESULTS.invalid_bracket) and int(res.evaluations[1]) == 10


def test_prediction_extrapolates_the_ratio_to_the_reference_linearly_in_log_x():
    ref = lambda x: x
    assert _predict([], [], ref, 3.0) == 3.0
    assert _predict([1.0], [2.0], ref, 3.0) == pytest.approx(6.0)  # the ratio 2 kept
    # ratio 2 at x = 1 and 4 at x = 10: log ratio rises by log 2 per decade
    assert _predict([1.0, 10.0], [2.0, 40.0], ref, 100.0) == pytest.approx(100.0 * 8.0)
    assert _predict([5.0, 5.0], [10.0, 20.0], ref, 7.0) == pytest.approx(7.0 * 4.0)  # same x twice: the last ratio


def test_root_continuation_seeds_each_bracket_with_the_last_root_and_falls_back_to_the_full_one():
    """Roots of g_ε(x) = x − r(ε) for r = 1.5, 1.1, 5.0: the second lies in [1.5/1.5, 1.5·1.5] (the
    seeded bracket), the third does not and is found in the full bracket [0.1, 10]."""
    from jaxrod.boundary.roots import continuation

    r = {0.5: 1.5, 0.1: 1.1, 0.01: 5.0}
    out = continuation(lambda x, eps: x - r[eps], [0.5, 0.1, 0.01], 0.1, 10.0, rtol=1e-12)
    assert [int(o.result) for o in out] == [int(ROOT_RESULTS.converged)] * 3
    np.testing.assert_allclose([float(o.root) for o in out], [1.5, 1.1, 5.0], rtol=1e-10)
    # a seeded bracket only 1 % wide around 1.1 misses 5.0 as well: found in the full bracket
    stuck = continuation(lambda x, eps: x - r[eps], [0.1, 0.01], 0.1, 10.0, rtol=1e-12, widen=1.01)
    assert float(stuck[1].root) == pytest.approx(5.0, rel=1e-10)


def test_the_progress_bar_counts_the_points_of_the_curve(capsys):
    """With `progress`, a bar that counts the points out of their number."""
    _along_curve(_Search(), np.array([4.0, 1.0, 2.0]), lambda x: x**2 / 100, (1e-4, 10.0), 0.02, True)
    err = capsys.readouterr().err
    assert "0/3" in err and "point" in err  # (the bar redraws at most every 0.1 s)
