"""The one definition of a lock-up run's outcome (`jaxrod.lockup.verdict`): synthetic records of
a steady slide, a transient, a lock and an unresolved helix, and the committed runs read by it."""

from __future__ import annotations

import csv
import math
import os

import numpy as np
import pytest

from jaxrod.lockup import verdict as vd

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PUSH = np.linspace(0.0, 0.3, 201)


def test_a_steady_slide_a_transient_and_a_lock():
    # the far end moves with the entry (less a fixed compression) at a settled force
    steady = vd.verdict(PUSH, PUSH - 1e-3 * (PUSH > 0.01), 4.3 + 0.01 * np.sin(40 * PUSH))
    assert steady["status"] == vd.SLIDING, steady
    assert steady["transfer"][1] == pytest.approx(1.0, abs=1e-9)
    # the committed 74-segment case at far load 4 F0: the far end 0.7 of the entry, the force rising
    transient = vd.verdict(PUSH, 0.7 * PUSH, 13.1 + 18.0 * PUSH)
    assert transient["status"] == vd.TRANSIENT and transient["transfer"][1] == pytest.approx(0.7)
    # the same force, but the far end keeping pace: still transient (the force has not settled)
    assert vd.verdict(PUSH, PUSH, 13.1 + 18.0 * PUSH)["status"] == vd.TRANSIENT
    # the far end stops at 60 % of the push while the entry force climbs
    far = np.minimum(PUSH, 0.18)
    lock = vd.verdict(PUSH, far, 4.0 + 50.0 * np.maximum(PUSH - 0.18, 0.0))
    assert lock["status"] == vd.LOCKED, lock
    # stopped, but the force does not rise: not a lock
    assert vd.verdict(PUSH, far, np.full_like(PUSH, 4.0))["status"] == vd.TRANSIENT
    # a thrashing record whose force changes sign is not a lock either
    assert vd.verdict(PUSH, far, 80 * np.sin(200 * PUSH) * (PUSH > 0.2))["status"] == vd.TRANSIENT


def test_the_thresholds_decide_at_their_values():
    far_ratio = lambda rho: vd.verdict(PUSH, rho * PUSH, np.full_like(PUSH, 3.0))["status"]
    assert far_ratio(0.91) == vd.SLIDING and far_ratio(0.89) == vd.TRANSIENT
    stop = np.minimum(PUSH, 0.24) + 0.04 * np.maximum(PUSH - 0.24, 0.0)  # 4 % of the entry in the last part
    assert vd.verdict(PUSH, stop, 3.0 + PUSH)["status"] == vd.LOCKED
    assert vd.verdict(PUSH, stop, 3.0 + PUSH, criterion=vd.Criterion(lock=0.03))["status"] == vd.TRANSIENT
    drift = lambda rate: vd.verdict(PUSH, PUSH, 3.0 * (1 + rate * PUSH / 0.06))["status"]  # rate per part
    assert drift(0.015) == vd.SLIDING and drift(0.03) == vd.TRANSIENT
    # the strictest slide threshold, 1 (the far end keeps exact pace), is a valid criterion
    exact = vd.Criterion(slide=1.0)
    assert vd.verdict(PUSH, PUSH, np.full_like(PUSH, 3.0), criterion=exact)["status"] == vd.SLIDING
    assert vd.verdict(PUSH, 0.99 * PUSH, np.full_like(PUSH, 3.0), criterion=exact)["status"] == vd.TRANSIENT


def test_a_helix_turning_faster_than_the_segments_resolve_is_unresolved():
    n, l0, r = 40, 0.05, 0.04
    s = np.arange(n + 1)
    straight = np.zeros((len(PUSH), n + 1))
    helix = straight.copy()
    helix[-60:] = (2 * np.pi / 5.0) * s  # 5 segments per turn near the end of the push
    per_turn, angle = vd.turn_resolution(helix, l0, r)
    assert per_turn[-1] == pytest.approx(5.0) and math.isinf(per_turn[0])
    assert angle[-1] == pytest.approx(math.degrees(math.atan(r * 2 * np.pi / 5.0 / l0)))
    f = 4.3 + 0.0 * PUSH
    out = vd.verdict(PUSH, PUSH, f, helix, l0, r)
    assert out["status"] == vd.UNRESOLVED and out["segments_per_turn"] == pytest.approx(5.0)
    assert out["f_unresolved"] == pytest.approx(4.3)
    rising = 4.3 + PUSH  # the entry force at the first unresolved save, not at the first save
    assert vd.verdict(PUSH, PUSH, rising, helix, l0, r)["f_unresolved"] == pytest.approx(4.3 + PUSH[-60])
    assert vd.verdict(PUSH, PUSH, f, straight, l0, r)["status"] == vd.SLIDING
    # a gentle helix, 20 segments per turn at a small angle, is resolved
    gentle = straight.copy()
    gentle[-60:] = (2 * np.pi / 20.0) * s
    assert vd.verdict(PUSH, PUSH, f, gentle, l0, 0.005)["status"] == vd.SLIDING
    # the angle bound alone: 20 segments per turn but a wide clearance
    assert vd.verdict(PUSH, PUSH, f, gentle, l0, 0.2)["status"] == vd.UNRESOLVED


def test_a_failed_record_and_bad_input():
    f = np.full_like(PUSH, 3.0)
    f[150] = np.nan
    assert vd.verdict(PUSH, PUSH, f)["status"] == vd.FAILED
    with pytest.raises(ValueError, match=r"^push, far, f_in have shapes"):
        vd.verdict(PUSH[:5], PUSH[:5], PUSH[:5])
    with pytest.raises(ValueError, match=r"^Criterion.lock, slide = "):
        vd.verdict(PUSH, PUSH, f, criterion=vd.Criterion(lock=0.95))
    with pytest.raises(ValueError, match=r"^Criterion.windows = "):
        vd.verdict(PUSH, PUSH, f, criterion=vd.Criterion(windows=1))


def _committed(name):
    with open(os.path.join(ROOT, "results", "lockup", name, "lockup.csv"), newline="") as fh:
        rows = list(csv.DictReader(fh))
    push, far, f = (np.array([float(r[k]) for r in rows]) for k in ("push", "far_displacement", "f_in"))
    k = int(np.argmax(push)) + 1  # the loading phase
    return vd.verdict(push[:k], far[:k], f[:k])


def test_the_committed_runs_read_by_the_definition():
    """The lower end of the old F_far,max bracket at μL/ℓ = 1 (far load 4 F₀, 74 and 148 segments)
    is a transient, as the runs' own files show; so is the 37-segment gate case at 2.5 F₀ (its
    force still rose 2.4 % between the last two fifths), while its half-speed and longer runs
    slide steadily."""
    for name in ("muL1_far4.0_n74", "muL1_far4.0_n148", "muL1_far2.5", "muL1_far2.5_n74"):
        assert _committed(name)["status"] == vd.TRANSIENT, name
    for name in ("muL1_far2.5_half_speed", "muL1_far2.5_long", "muL0.5_far4"):
        assert _committed(name)["status"] == vd.SLIDING, name


def test_only_neighbours_on_the_wall_count_for_the_turn():
    """A pinned end at the channel's axis has an angle that says nothing of a helix: with the
    contact mask, a jump of π next to it does not make the run unresolved."""
    n, l0, r = 20, 0.1, 0.04
    theta = np.zeros((len(PUSH), n + 1))
    theta[:, -1] = np.pi  # the end node, off the wall
    contact = np.ones_like(theta, bool)
    contact[:, -1] = False
    f = np.full_like(PUSH, 3.0)
    assert vd.verdict(PUSH, PUSH, f, theta, l0, r)["status"] == vd.UNRESOLVED
    assert vd.verdict(PUSH, PUSH, f, theta, l0, r, contact=contact)["status"] == vd.SLIDING
