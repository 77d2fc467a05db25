"""The helix of a saved rod against the laws (`jaxrod.lockup.laws`), on helices built from the
laws themselves: a rod sliding toward its far end whose force rises by the soft string's
dF/ds = μN with Mitchell's N = r F²/(4EI) + w cos θ and Lubinski's turn rate √(F/(2EI)) reads
every ratio as 1; a helix turned 10 % tighter, or with twice the wall force, reads so."""

import math

import numpy as np
import pytest

from jaxrod.lockup.laws import helix_against_laws

EI, w, r, mu = 0.05, 0.8, 0.04, 0.2
F0 = math.sqrt(EI * w / r)
ell = math.sqrt(EI / (r * w))
wave = 2 * math.pi * math.sqrt(ell * r)


def _helix(n=600, L=2.5, f_far=4.0, tight=1.0, wall=1.0):
    """A helix without the weight term in its transfer law: F(s) = F_far/(1 − μ r F_far s/(4EI))."""
    s = np.linspace(0.0, L, n + 1)
    F = f_far * F0 / (1 - mu * r * f_far * F0 * s / (4 * EI))
    k = tight * np.sqrt(F / (2 * EI))
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * np.diff(s))])
    N = wall * r * F**2 / (4 * EI) + w * np.cos(theta)
    Fseg = 0.5 * (F[1:] + F[:-1])
    return np.angle(np.exp(1j * theta)), N, Fseg, L / n


def test_a_helix_built_from_the_laws_reads_one_on_every_law():
    theta, N, Fseg, l0 = _helix()
    got = helix_against_laws(theta, N, Fseg, l0, EI, w, r, mu, wave)
    assert got["inner"].sum() > 100 and got["inner_length"] > 1.0
    assert got["pitch_ratio"] == pytest.approx(1.0, abs=0.01)
    assert got["N_ratio"] == pytest.approx(1.0, abs=0.02)  # w cos θ averages out over a turn
    assert got["N_ratio_with_weight"] < got["N_ratio"] - 0.05
    assert got["soft_string_ratio"] == pytest.approx(1.0, abs=0.03)
    assert got["soft_string_ratio_whole"] == pytest.approx(1.0, abs=0.01)
    assert got["reversals"] == 0 and got["wall_ratio_winding"] == pytest.approx(1.0, abs=0.03)
    # the profile it read, at the nodes: arc length, the wall force as given, the axial force averaged to them
    np.testing.assert_allclose(got["s"], np.arange(theta.size) * l0, rtol=1e-12)
    np.testing.assert_array_equal(got["N"], N)
    np.testing.assert_allclose(got["F"][1:-1], 0.5 * (Fseg[1:] + Fseg[:-1]), rtol=1e-12)


def test_a_helix_that_changes_hand_is_counted():
    """The same helix, its hand reversed halfway along (θ' changes sign at s = L/2): one reversal."""
    theta, N, Fseg, l0 = _helix()
    th = np.unwrap(theta)
    mid = th.size // 2
    th[mid:] = 2 * th[mid] - th[mid:]
    got = helix_against_laws(np.angle(np.exp(1j * th)), N, Fseg, l0, EI, w, r, mu, wave)
    assert got["reversals"] == 1


def test_a_tighter_helix_and_a_harder_wall_are_read_as_such():
    theta, N, Fseg, l0 = _helix(tight=1.1, wall=2.0)
    got = helix_against_laws(theta, N, Fseg, l0, EI, w, r, mu, wave)
    assert got["pitch_ratio"] == pytest.approx(1 / 1.1, abs=0.01)
    assert got["N_ratio"] == pytest.approx(2.0, abs=0.04)
    assert got["soft_string_ratio"] == pytest.approx(0.5, abs=0.03)  # F rises by μN with half this N


def test_a_straight_rod_has_no_helix_to_compare():
    n = 100
    got = helix_against_laws(np.zeros(n + 1), np.full(n + 1, w), np.full(n, F0), 0.04, EI, w, r, mu, wave)
    assert not got["helical"].any() and math.isnan(got["N_ratio"]) and got["inner_length"] == 0.0
    with pytest.raises(ValueError, match="theta"):
        helix_against_laws(np.zeros(n), np.full(n + 1, w), np.full(n, F0), 0.04, EI, w, r, mu, wave)


@pytest.mark.parametrize("amplitude, winding", [(1.0, False), (2.0, True)])
def test_a_sinusoid_is_no_helix_and_winds_only_past_half_a_turn(amplitude, winding):
    """θ = a sin(2πs/wave), wrapped: spanning 2a within a window, less than a full turn, so no
    node is helical and nothing is compared; it winds (θ spans more than π in a window) for
    a = 2 rad, not for a = 1 rad."""
    n = 400
    l0 = 2.5 / n
    s = np.arange(n + 1) * l0
    theta = np.angle(np.exp(1j * amplitude * np.sin(2 * np.pi * s / wave)))
    got = helix_against_laws(theta, np.full(n + 1, w), np.full(n, F0), l0, EI, w, r, mu, wave)
    assert not got["helical"].any() and not got["inner"].any() and math.isnan(got["pitch_ratio"])
    assert (got["winding_length"] > 2.0) == winding and (got["winding_length"] == 0.0) == (not winding)
