"""The lock-up scene with the 3D rod (`jaxrod.lockup.push`): the case it builds, and the soft-string
law of a straight rod pushed by a slowly rising entry force — the force that reaches the far end
is the pushed force less the friction μwL of the sliding rod, and beyond the point where that
friction has taken all of it the rod does not move."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.lockup.push import extents, inject, push, push_rod, units

jax.config.update("jax_enable_x64", True)


def test_the_rod_realizes_the_dimensionless_case_for_any_material():
    """μL/ℓ and r/ℓ of the rod made for a case are the case's, for the reference nitinol and for
    a heavier, softer material (the same case in units of F₀ and ℓ, other SI numbers)."""
    other = jr.RodChannel.reference().__class__(L=1.0, d=3e-3, E=2e9, rho_v=1200.0, nu=0.4, R=0.01, g=9.81,
                                                 mu_s=0.3, mu_d=0.3)
    for material in (None, other):
        rod = push_rod(2.5, 0.02, 0.4, material)
        F0, ell = units(rod)
        w = float(rod.rho * rod.g)
        assert math.isclose(ell, math.sqrt(float(rod.EI) / (float(rod.R) * w)), rel_tol=1e-12)
        assert math.isclose(F0, math.sqrt(float(rod.EI) * w / float(rod.R)), rel_tol=1e-12)
        assert math.isclose(0.4 * float(rod.L) / ell, 2.5, rel_tol=1e-12)
        assert math.isclose(float(rod.R) / ell, 0.02, rel_tol=1e-12)
        assert float(rod.mu_s) == float(rod.mu_d) == 0.4
    assert not math.isclose(float(push_rod(2.5, 0.02, 0.4).R), float(push_rod(2.5, 0.02, 0.4, other).R))


@pytest.mark.parametrize("args, name", [((0.0, 0.02, 0.5), "mu_L_over_ell"), ((1.0, 0.7, 0.5), "r_over_ell"),
                                        ((1.0, 0.02, -1.0), "mu"), ((float("nan"), 0.02, 0.5), "mu_L_over_ell")])
def test_a_case_out_of_range_is_refused_by_name(args, name):
    with pytest.raises(ValueError, match=name):
        push_rod(*args)


def test_extents_tell_a_helix_from_a_sinusoid():
    """A helix on the first 4 m, straight, then a sinusoid of 0.6 rad on 6–9 m: the extents are
    4 m and 3 m, each blurred by the window: half a wavelength at each end that meets a straight
    part, and the helix's last half wavelength, which turns less than π, also reads as sinusoidal
    (measured: 4.5 m and 4.25 m)."""
    s = np.linspace(0.0, 10.0, 401)
    wave = 1.0
    helix = np.where(s < 4.0, 2 * np.pi * s / 0.8, 0.0)  # five turns, one every 0.8 m
    sine = np.where((s > 6.0) & (s < 9.0), 0.6 * np.sin(2 * np.pi * (s - 6.0) / wave), 0.0)
    theta = np.angle(np.exp(1j * (helix + sine)))  # wrapped, as the rod's θ is
    hel, sin = extents(theta[None], s, wave)
    ds = s[1] - s[0]
    assert 4.0 - ds <= hel[0] <= 4.0 + 0.5 * wave + ds
    assert 3.0 - ds <= sin[0] <= 3.0 + 1.5 * wave + ds
    # the lanes' records, (lanes, saves, nodes): each lane's extents are its own (θ unwrapped
    # along the rod, the last axis, whatever comes before it)
    lanes = np.stack([np.stack([theta, np.zeros_like(theta)]), np.stack([np.zeros_like(theta), theta])])
    hel2, sin2 = extents(lanes, s, wave)
    assert hel2.shape == (2, 2)
    np.testing.assert_array_equal(hel2, [[hel[0], 0.0], [0.0, hel[0]]])
    np.testing.assert_array_equal(sin2, [[sin[0], 0.0], [0.0, sin[0]]])



def test_extents_unwrap_theta_along_the_rod_so_a_sinusoid_on_the_top_is_not_a_helix():
    """A sinusoid of 0.6 rad about θ = π (the rod on the channel's top, where the wrapped angle
    jumps between π and −π) is sinusoidal along its whole 10 m, not helical: θ is unwrapped
    along the rod, the last axis, for one save and for the lanes' (lanes, saves, nodes)."""
    s = np.linspace(0.0, 10.0, 401)
    theta = np.angle(np.exp(1j * (np.pi + 0.6 * np.sin(2 * np.pi * s))))
    assert np.ptp(theta) > 6.0  # wrapped: it jumps
    hel, sin = extents(theta[None], s, 1.0)
    assert hel[0] == 0.0 and sin[0] == pytest.approx(10.0 + (s[1] - s[0]))
    lanes = np.stack([np.stack([theta, theta])] * 3)
    hel3, sin3 = extents(lanes, s, 1.0)
    np.testing.assert_array_equal(hel3, np.zeros((3, 2)))
    np.testing.assert_array_equal(sin3, np.full((3, 2), sin[0]))


def test_inject_lanes_runs_its_parts_and_keeps_n_save_saves_in_all(monkeypatch):
    """The vmapped injection runs `chunks` parts (20 by default) of `duration`/`chunks` each, with
    saves per part such that the record holds `n_save` saves, also when a part gets only its two
    ends (n_save − 1 = chunks); the parts after the first come from the hold rule (`adjust`).
    (`_phases` replaced by a recorder: what is checked is what inject_lanes asks of it.)"""
    rod = push_rod(1.0, 0.02, 0.5)
    for chunks, n_save in ((None, 101), (20, 21), (4, 5), (3, 50)):
        kw = {} if chunks is None else {"chunks": chunks}
        seen, rec = _recorded_inject_lanes(monkeypatch, rod, n_save=n_save, **kw)
        parts = 20 if chunks is None else chunks
        assert len(seen["parts"]) == parts and all(d == pytest.approx(2.0 / parts) for _, d in seen["parts"])
        assert 1 + parts * (seen["per"] - 1) >= n_save and seen["per"] >= 2
        if (n_save - 1) % parts == 0:
            assert len(rec["t"]) == n_save
        assert seen["lanes"] and seen["adjust"] is not None and seen["scheme"] == "implicit"
        assert np.asarray(seen["q"].x).shape[0] == 3 and np.all(rec["phase"] == 0)
        assert rec["F_far"].shape == (3, len(rec["t"]))


def _recorded_inject_lanes(monkeypatch, rod, n_save=21, **kw):
    """What `inject_lanes` hands its phase runner (replaced by a recorder), and its record: three
    lanes of 12 segments pushed at 10 mm/s for 2 s."""
    from jaxrod.lockup import push as P

    seen = {}

    def phases(rod, parts, q, v, dt, n_save, progress, lanes=False, adjust=None, scheme="leapfrog"):
        seen.update(parts=parts, per=n_save, lanes=lanes, adjust=adjust, scheme=scheme, q=q)
        m, saves = np.asarray(q.x).shape[0], 1 + len(parts) * (n_save - 1)
        return dict(t=np.linspace(0.0, 1.0, saves), phase=np.ones(saves, int), reaction=np.zeros((m, saves, 2)),
                    F0=1.0)

    monkeypatch.setattr(P, "_phases", phases)
    rec = P.inject_lanes(rod, [0.5, 0.3, 0.2], [0.0, 1.0, 2.0], 0.01, 2.0, n=12, n_save=n_save, **kw)
    return seen, rec


def test_the_imperfect_start_is_drawn_from_the_key_and_scaled_to_the_imperfection(monkeypatch):
    """Every lane starts from one smooth random lateral offset: the one of `key` (default: key 0),
    its largest value `imperfection` × r along the wall (θ = offset/r), made of the rod's sine
    modes 1–8 (at 12 segments the nodes resolve modes 1–11)."""
    rod = push_rod(1.0, 0.02, 0.5)
    theta = {}
    for name, kw in (("default", {}), ("0", dict(key=jax.random.key(0))), ("1", dict(key=jax.random.key(1))),
                     ("big", dict(imperfection=3e-3))):
        seen, _ = _recorded_inject_lanes(monkeypatch, rod, **kw)
        x = np.asarray(seen["q"].x)
        theta[name] = np.arctan2(x[:, :, 1], -x[:, :, 2])
        np.testing.assert_array_equal(theta[name][1:], np.broadcast_to(theta[name][0], theta[name][1:].shape))
    np.testing.assert_array_equal(theta["default"], theta["0"])
    assert np.max(np.abs(theta["1"] - theta["0"])) > 1e-4
    for name, amp in (("0", 1e-3), ("1", 1e-3), ("big", 3e-3)):
        assert np.max(np.abs(theta[name])) == pytest.approx(amp, rel=1e-9)
        modes = np.abs(np.asarray(jr.modal.modal_amplitudes(jnp.asarray(theta[name][0, 1:-1]))))
        assert np.all(modes[:8] > 1e-3 * amp) and np.all(modes[8:] < 1e-12 * amp), modes / amp


def test_a_lane_is_held_once_its_entry_force_passes_the_cap_not_when_it_reaches_it(monkeypatch):
    """The hold rule between parts: a lane whose largest entry reaction exceeds `cap` F₀ has its
    entry stopped (speed 0) and `held_from` set to that time, once; a lane exactly at the cap and
    one below it push on."""
    rod = push_rod(1.0, 0.02, 0.5)
    F0, _ = units(rod)
    seen, rec = _recorded_inject_lanes(monkeypatch, rod, cap=2.0)
    models = seen["parts"][0][0]
    reaction = np.zeros((3, 13, 2))
    reaction[0, 5, 1], reaction[1, 7, 1], reaction[2, 3, 1] = 2.0 * F0, 2.0 * F0 * (1 + 1e-9), 1.0 * F0
    held = seen["adjust"](models, {"reaction": reaction}, 0.4)
    np.testing.assert_array_equal(np.asarray(held.speed), [0.01, 0.0, 0.01])
    np.testing.assert_array_equal(rec["held_from"], [np.inf, 0.4, np.inf])
    seen["adjust"](held, {"reaction": reaction}, 0.8)  # held from its first time over, not the next
    np.testing.assert_array_equal(rec["held_from"], [np.inf, 0.4, np.inf])


def test_a_short_rod_passes_the_pushed_force_less_the_friction_of_the_rod():
    """μL/ℓ = 0.1 (L = 0.41 m, far shorter than a buckle: it stays straight up to 3F₀): under an
    entry force rising at 15 F₀/s every interior node slides toward the far end, so the load
    cell reads F_in − μ_d w L (n − ½)/n (the held far node's half segment carries no friction,
    the entry node's half does). Measured: 0.971 of μwL at n = 20 against (n − ½)/n = 0.975."""
    rod = push_rod(0.1, 0.02, 0.5)
    F0, _ = units(rod)
    r = push(rod, 3.0 * F0, 15.0 * F0, unload=False, n_save=21)
    assert r["result"] == 0 and r["n"] == 20
    muwL = 0.5 * float(rod.rho * rod.g) * float(rod.L)
    lost = (r["F_in"] - r["F_far"])[-5:] / muwL
    np.testing.assert_allclose(lost, (r["n"] - 0.5) / r["n"], atol=0.01)
    assert np.all(r["helical"] == 0) and np.all(r["sinusoidal"] == 0)


def test_past_the_force_front_a_straight_rod_does_not_move():
    """μL/ℓ = 2 (L = 8.2 m) pushed up to 1.5 F₀, below the sinusoidal onset: friction takes the
    whole force within μs/ℓ = 1.5, so the far quarter of the rod carries none of it. Static
    friction holds it exactly (a held degree of freedom has zero velocity in the projected
    scheme): its nodes stay within the initial settling of the straight state (1e-9 m, far
    below the entry's push) and the load cell reads what it read at the start."""
    rod = push_rod(2.0, 0.02, 0.5)
    F0, ell = units(rod)
    r = push(rod, 1.5 * F0, 15.0 * F0, unload=False, n_save=21, n=48)  # 48 segments, not the default 73
    assert r["result"] == 0 and r["n"] == 48 and r["u"].shape == (21, 49)
    far = slice(0, r["n"] // 4)  # node 0 is the far end
    assert r["push"][-1] > 1e-6
    assert np.max(np.abs(r["u"][:, far])) < 1e-9
    assert np.max(np.abs(r["F_far"] - r["F_far"][0])) < 1e-3 * F0


def test_the_command_writes_the_run_and_its_soft_string_comparison(tmp_path, capsys):
    """`jaxrod lockup` (`inject`) on a straight case: the entry pushed 5 mm at 5 mm/s, the far end
    sliding against F_far = 0.5 F₀, μL/ℓ = 0.5. Once the start's axial wave has been damped
    (mass-proportional damping 20/s; undamped it rings at ±0.65 F₀ about its mean, measured) the
    entry carries the soft-string straight section's F_far + μ_d w L (1 − 1/(2n)) (the held entry
    node's half segment has no friction) plus the damping's drag c·m·v (1.507 F₀ measured at
    μL/ℓ = 1), the far end moves with the entry, and the soft string gives 1 F₀ for every variant
    (no section buckles). Pulled back as far (`--unload`), the friction turns: the entry carries
    F_far − μ_d w L (1 − 1/(2n)) − c·m·v, and the far end comes back to where it started. CSV, JSON
    and figure are written. With the explicit scheme: the implicit one's bias on this case is
    the next test's."""
    from jaxrod.cli import main

    out = tmp_path / "lk"
    assert main(["lockup", "--mu-L", "0.5", "--far-load", "0.5", "--push", "0.005", "--out", str(out), "--json",
                 "--quiet", "--unload", "--scheme", "leapfrog"]) == 0
    summary = __import__("json").loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert sorted(p.name for p in out.iterdir()) == ["lockup.csv", "lockup.json", "lockup.png"]
    lo, hi = summary["entry_force_over_F0_last_fifth"]
    expected = 0.5 + 0.5 * (1 - 1 / (2 * summary["n_segments"])) + summary["drag_over_F0"]
    assert abs(lo - expected) < 2e-3 and abs(hi - expected) < 2e-3
    assert all(math.isclose(v, 1.0, rel_tol=1e-9) for v in summary["soft_string_entry_force_over_F0"].values())
    told = summary["verdict"]  # jaxrod.lockup.verdict: a steady slide, the rod straight (no turn to speak of)
    assert told["status"] == "sliding" and told["segments_per_turn"] > 1e3 and told["helix_angle"] < 0.1
    rows = (out / "lockup.csv").read_text().splitlines()
    assert rows[0].split(",")[:4] == ["t", "push", "far_displacement", "F_in"] and len(rows) == 1 + 201 + 200
    push, far = (float(x) for x in rows[201].split(",")[1:3])
    assert math.isclose(far, push, rel_tol=1e-2)  # the far end moves with the entry (less the compression)
    assert summary["helical_over_ell_end"] == 0 and summary["sinusoidal_over_ell_end"] == 0
    back = summary["unloading"]
    expected = 0.5 - 0.5 * (1 - 1 / (2 * summary["n_segments"])) - summary["drag_over_F0"]
    assert all(abs(f - expected) < 2e-3 for f in back["entry_force_over_F0_last_fifth"]), back
    assert abs(back["far_end_moved_m"]) < 1e-4 and abs(back["push_end_m"]) < 1e-9


def test_lock_up_is_told_by_the_far_end_and_the_entry_force():
    """`locked`: a far end that keeps up with the entry over the last fifth of the push slides; one
    that advances less than half as far has locked; so has a run whose entry force passed ℓ/r F₀
    (the helix angle no longer small), even if it became non-finite after that. A run that became
    non-finite first says nothing (None), whatever its far end did."""
    from jaxrod.lockup.push import locked

    push = np.linspace(0.0, 0.3, 101)
    base = dict(phase=np.zeros(101, int), push=push, f_in=np.full(101, 4.0), ell=2.0, r=0.04)
    sliding = dict(base, u=np.stack([push - 0.03, push], -1))
    stalled = dict(base, u=np.stack([np.minimum(push, 0.25) - 0.03, push], -1))  # stops at 0.25 of 0.3 m
    assert not locked(sliding) and locked(stalled)
    assert locked(dict(sliding, f_in=np.where(push > 0.1, 60.0, 4.0)))  # past ℓ/r = 50 F₀
    assert not locked(dict(sliding, f_in=np.where(push > 0.1, 60.0, 4.0)), cap=100.0)
    assert not locked(dict(sliding, f_in=np.where(push > 0.1, 50.0, 4.0)))  # reaching ℓ/r is not passing it
    assert locked(dict(sliding, f_in=np.where(push > 0.2, np.nan, np.where(push > 0.1, 60.0, 4.0)))) is True
    assert locked(dict(sliding, f_in=np.where(push > 0.1, np.nan, 4.0))) is None
    assert locked(dict(stalled, f_in=np.where(push > 0.1, np.nan, 4.0))) is None


@pytest.mark.parametrize("scheme", ["implicit", "leapfrog"])
def test_inject_runs_its_phases_with_the_scheme_it_is_given(monkeypatch, scheme):
    """`inject(scheme=...)` steps the rod with that integrator (the phase runner, which defaults
    to the explicit leapfrog, stands in here: it records its scheme and stops the call)."""
    import jaxrod.lockup.push as push_module

    seen = []

    class Stop(Exception):
        pass

    def phases(*args, scheme="leapfrog", **kw):
        seen.append(scheme)
        raise Stop

    monkeypatch.setattr(push_module, "_phases", phases)
    with pytest.raises(Stop):
        inject(push_rod(0.5, 0.02, 0.5), 0.0, 1e-3, 0.01, n=8, scheme=scheme)
    assert seen == [scheme]


@pytest.mark.slow  # 40 s: two vmapped and one single compilation
def test_lanes_are_single_injections_and_a_locked_lane_is_held():
    """`inject_lanes`: lane k of one vmapped run is `inject` with its own μ and far load (to 1e-6
    F₀ in one part; to 1e-5 F₀ and 1e-9 m in four: the run in parts puts its saves on a slightly
    different step grid); a lane whose entry force passed `cap` at the end of a part has its entry
    held still from then on (its push stops, to rounding), while the other lanes go on at the set
    speed."""
    from jaxrod.lockup.push import inject_lanes, lane

    rod = push_rod(1.0, 0.02, 0.5)
    F0, _ = units(rod)
    speed, T = 0.005, 0.4
    rec = inject_lanes(rod, [0.5, 0.25], [3.0 * F0, 0.5 * F0], speed, T, n=12, n_save=9, chunks=4, cap=2.5,
                       damping=20.0)
    single = inject(push_rod(0.5, 0.02, 0.25), 0.5 * F0, speed, T, n=12, n_save=9, damping=20.0)
    free = lane(rec, 1)
    assert np.all(rec["result"] == 0) and np.isinf(free["held_from"])
    np.testing.assert_allclose(free["f_in"], single["f_in"], atol=1e-5)
    whole = lane(inject_lanes(rod, [0.5, 0.25], [3.0 * F0, 0.5 * F0], speed, T, n=12, n_save=9, chunks=1, cap=2.5,
                              damping=20.0), 1)
    np.testing.assert_allclose(whole["f_in"], single["f_in"], atol=1e-6)
    np.testing.assert_allclose(free["u"], single["u"], atol=1e-9)
    np.testing.assert_allclose(np.diff(free["push"]), speed * np.diff(free["t"]), rtol=1e-6)
    held = lane(rec, 0)
    t_hold = held["held_from"]
    assert 0 < t_hold < T and np.max(held["f_in"][held["t"] <= t_hold + 1e-12]) > 2.5
    after = held["t"] >= t_hold - 1e-12
    assert np.ptp(held["push"][after]) < 1e-12


@pytest.mark.slow  # 40 s
def test_past_lock_up_the_far_end_holds_still():
    """μL/ℓ = 1 against 5 F₀ (above F_far,max: 3.66–4.00 F₀ for the soft string, [4.0, 4.57] for
    the 3D rod at 74 segments), the entry held once its force has passed 20 F₀ (`inject_lanes`'s
    cap): the rod wound into a helix along its whole length, the far end under its load, and
    the entry force locked in come to rest and stay there — static friction holds them exactly
    (a stuck contact has zero velocity in the projected scheme): within a save (0.5 s) of the
    hold the far end settles (0.33 mm measured, under 1 mm), then it does not move by 1 µm (the
    push, 5 mm/s, moved the entry 2.5 mm per save) and the entry force stays above 20 F₀.
    (Before the hold the far end does not stay still: at 45–48 F₀ it advanced 15 mm in a burst
    while the entry advanced 20 mm, docs/physics.md §8.)"""
    from jaxrod.lockup.push import inject_lanes, lane

    rod = push_rod(1.0, 0.02, 0.5)
    F0, _ = units(rod)
    rec = inject_lanes(rod, [0.5], [5.0 * F0], 0.005, 24.0, n_save=49, chunks=8, cap=20.0, damping=20.0)
    r = lane(rec, 0)
    assert r["result"] == 0 and 0 < r["held_from"] <= 21.0
    after = r["t"] >= r["held_from"]
    assert np.ptp(r["push"][after]) < 1e-9 and r["push"][after][0] > 0.05
    far = r["u"][after, 0]
    assert abs(far[1] - far[0]) < 1e-3 and np.ptp(far[1:]) < 1e-6
    assert np.min(r["f_in"][after]) > 20.0


@pytest.mark.slow  # a long implicit push (~20 s cold)
def test_the_implicit_scheme_biases_a_steady_slide_by_beta_h2_mu_g_EA_over_l():
    """The straight slide of the test above (μL/ℓ = 0.5, far load 0.5 F₀, 20 segments) with the
    implicit leapfrog: each step the friction pass takes μ_d g h off every node's velocity through
    its own mass, and the kick, (M + βh²H) Δv = h F, must give it back; on a uniform Δv the
    stiffness cancels except next to the held entry, where it leaves βh² (EA/l̂) μ_d g, which the
    entry carries on top of the soft-string force (`jaxrod.lockup.push.inject`). Measured against
    that closed form at 2e-5 s: within 2 % (0.0029 F₀; 0.0178 F₀ at the default 5e-5 s)."""
    rod = push_rod(0.5, 0.02, 0.5)
    F0, _ = units(rod)
    h = 2e-5
    r = inject(rod, 0.5 * F0, 5e-3, 1.5, n_save=101, damping=20.0, dt=h)
    assert r["scheme"] == "implicit" and r["n"] == 20 and r["dt"] == h
    tail = r["push"] >= 0.8 * r["push"].max()
    soft = 0.5 + 0.5 * (1 - 1 / (2 * r["n"])) + 20.0 * float(rod.rho) * float(rod.L) * 5e-3 / F0
    bias = float(np.mean(r["f_in"][tail])) - soft
    l0 = float(rod.L) / r["n"]
    expected = 0.25 * h * h * float(rod.mu_d) * float(rod.g) * float(rod.EA) / l0 / F0
    assert abs(bias / expected - 1) < 0.02, (bias, expected)
