"""Post-buckling of the 3D rod: the helix measures on an exact helix, and a frictionless rod
pushed past buckling going over the top of the channel inside the helical-onset band."""

import pytest
import math

import numpy as np

import jaxrod as jr
from jaxrod.experiments.helix import helix_measures, helix_theory, load_path


def test_helix_measures_recover_an_exact_helix():
    """Nodes on an exact helix of wavenumber β on the wall, with the wall force of the helix
    equilibrium plus gravity's normal component: the measures return β, the pitch, the turns
    and the wall force without gravity."""
    rod = jr.RodChannel.reference(0.0)
    L, R, EI, w = float(rod.L), float(rod.R), float(rod.EI), float(rod.w)
    n, F, beta = 120, 6.0, 13.0
    s = np.linspace(0.0, L, n + 1)
    th = beta * s
    x = np.stack([s, R * np.sin(th), -R * np.cos(th)], -1)
    N_eq = R * beta**2 * (F - EI * beta**2)
    N = N_eq + w * np.cos(th)
    h = helix_measures(rod, x, N, np.full(n, F))
    assert h["helical"]
    np.testing.assert_allclose(h["beta"], beta, rtol=1e-12)
    np.testing.assert_allclose(h["pitch"], 2 * math.pi / beta, rtol=1e-12)
    np.testing.assert_allclose(h["turns"], beta * (s[(s >= 0.75 * L)][0] - s[(s >= 0.25 * L)][0]) / (2 * math.pi), rtol=1e-12)
    np.testing.assert_allclose(h["N_equilibrium"], N_eq, rtol=1e-12)
    # gravity removed to the accuracy of the turn average over the sampled middle half
    np.testing.assert_allclose(h["N_minus_gravity"], N_eq, rtol=1e-12)
    assert h["over_top"]
    # a sinusoid (no winding) is not a helix
    xs = np.stack([s, R * np.sin(0.5 * np.sin(6 * math.pi * s / L)), -R * np.cos(0.5 * np.sin(6 * math.pi * s / L))], -1)
    hs = helix_measures(rod, xs, np.full(n + 1, w), np.full(n, F))
    assert not hs["helical"] and hs["pitch"] == np.inf and not hs["over_top"]


@pytest.mark.slow  # 23-30 s of 3D compilation; the default suite keeps a quicker check
def test_frictionless_rod_goes_over_the_top_inside_the_helical_band():
    """Pushed at 4 mm/s (20 segments, damping 50 1/s), the frictionless rod first reaches the top
    of the channel at an end load between Chen's 2√2·√(EIw/R) and Mitchell's 4√2·√(EIw/R)
    (PHYSICS.md §6), above the sinusoidal onset F⁰₆; the energy balance closes over the path."""
    rod = jr.RodChannel.reference(0.0)
    p = load_path(rod, 20, [(4e-3, 0.75)], sps=40.0, progress=False)
    h = helix_measures(rod, p["x"], p["normal_force"], p["axial_force"])
    th = helix_theory(rod)
    over = np.flatnonzero(h["over_top"])
    assert over.size, "the rod never went over the top"
    F_over = p["reaction"][over[0]]
    assert th["onset_chen"] < F_over < th["onset_mitchell"], F_over
    assert np.all(~h["over_top"][p["reaction"] < th["sinusoidal_onset"]])
    balance = p["energy"] - p["energy"][0] + p["dissipated"] - p["work_in"]
    assert np.max(np.abs(balance)) < 1e-2 * p["work_in"][-1]
