"""Fast checks of code the default suite otherwise leaves to slow runs: the worst-case velocity
search on a tiny field model, the one-process and simulated two-process behaviour of
`jaxrod.distributed`, the helix measures and the loop area of the post-buckling experiment, and
the bookkeeping of the E1, E1-speed, E4, E5 and convergence drivers (their expensive solvers
replaced by recorders where a real run would take minutes; the cheap ones run for real)."""

import csv
import math
import threading
from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import jax
import numpy as np
import pytest
import scipy.optimize

import jaxrod as jr
from jaxrod import theory


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return rows


# --------------------------------------------------------------------------- worst case


def test_field_norm_is_the_rms_or_the_largest_magnitude_over_the_nodes():
    from jaxrod.worst_case import field_norm

    u = jax.numpy.array([3.0, -4.0, 0.0, 1.0])
    assert math.isclose(float(field_norm(u, "l2")), math.sqrt((9 + 16 + 0 + 1) / 4), rel_tol=1e-15)
    assert float(field_norm(u, "max")) == 4.0
    assert float(field_norm(-u, "max")) == 4.0
    with pytest.raises(ValueError, match="norm = 'rms' is invalid: expected 'l2' or 'max'"):
        field_norm(u, "rms")


@pytest.fixture(scope="module")
def worst():
    from jaxrod.worst_case import worst_case_velocity

    rod = jr.RodChannel.reference(0.3)
    # 8 nodes, 2 optimiser steps, 3 random directions, a 0.1 s horizon: the smallest search
    return rod, worst_case_velocity(rod, 5.0, n=8, norm="l2", steps=2, n_random=3, t1=0.1)


def test_worst_case_field_has_the_norm_it_reports_and_is_the_smallest_found(worst):
    _, r = worst
    assert r["norm"] == "l2" and r["u"].shape == (8,)
    assert r["sine_result"] == 0 and np.all(r["random_results"] == 0)
    assert r["random_norms"].shape == (3,)
    # u is the best direction scaled to its critical norm (RMS over the nodes)
    np.testing.assert_allclose(np.sqrt(np.mean(r["u"] ** 2)), r["norm_worst"], rtol=1e-12)
    # the search starts from the best of the sine and the random directions and keeps the best
    assert len(r["history"]) == 2 + 1
    assert r["history"][0] == min(r["norm_sine"], float(r["random_norms"].min()))
    assert r["norm_worst"] == min(r["history"])
    assert r["norm_worst"] < r["norm_sine"] and r["norm_worst"] < r["random_norms"].min()
    # it is a critical norm: 1 % above it the rod buckles, 1 % below it does not
    assert r["indicator"](1.01 * r["norm_worst"]) > 0 > r["indicator"](0.99 * r["norm_worst"])
    # every random direction has a larger critical norm, so none buckles at the worst one's
    assert r["random_buckle_at_worst_norm"] == 0.0


def test_worst_case_sine_norm_is_the_critical_rms_of_the_scenes_own_sine(worst):
    """`norm_sine` is the critical RMS norm of the mode-6 sine field: a sine of amplitude a at the
    8 interior nodes s_i = iL/9 has RMS a·√(9/16) (Σᵢ sin²(6πi/9) = 9/2), so the scene's own
    sine perturbation (`make_perturbation`) of amplitude norm_sine/√(9/16) is critical: 1 %
    above it the rod buckles, 1 % below it does not."""
    from jaxrod import boundary as bd
    from jaxrod.registry import make_perturbation

    rod, r = worst
    dt = jr.Scene(rod, 0.0, kind="field", n=8).step()
    a = float(r["norm_sine"]) / math.sqrt(9 / 16)

    def label(amplitude):
        return float(bd.rod_indicator(jr.Scene(rod, 5.0, make_perturbation("sine", amplitude, 6), "field", 8, 6, dt),
                                      0.1))

    assert label(1.01 * a) > 0 > label(0.99 * a)


def test_worst_case_spectrum_and_single_mode_prediction_follow_the_theory(worst):
    rod, r = worst
    assert r["spectrum"].shape == (8,)
    np.testing.assert_allclose(r["spectrum"].sum(), 1.0, rtol=1e-12)
    assert r["dominant_mode"] == int(np.argmax(r["spectrum"])) + 1
    # the prediction is the P6 intercept R f/√|k_m| of its mode, as an RMS norm (a sine of
    # amplitude a has RMS a/√2): P7 at that velocity puts the mode's critical load at F⁰ + ΔF ...
    m = r["single_mode_prediction_mode"]
    F0 = float(theory.reference_load(rod))
    adot = r["single_mode_prediction"] * math.sqrt(2.0) / float(rod.R)
    assert math.isclose(float(theory.critical_load_velocity(rod, m, adot)) - F0, 5.0, rel_tol=1e-9)
    # ... and every other mode of the 8 needs a larger load at that velocity
    others = [float(theory.critical_load_velocity(rod, k, adot)) for k in range(1, 9) if k != m]
    assert min(others) > F0 + 5.0
    # the modes are the field's 8: at this load the intercepts fall up to mode 12, so the
    # prediction is the highest mode the field holds, not mode 9
    assert m == 8 and float(theory.critical_load_velocity(rod, 9, adot)) < F0 + 5.0


# --------------------------------------------------------------------------- distributed


@pytest.mark.parametrize("kw, message", [
    (dict(coordinator_address="localhost"), "coordinator_address = 'localhost' is invalid"),
    (dict(coordinator_address=":1234"), "coordinator_address = ':1234' is invalid"),
    (dict(coordinator_address="host:0"), "coordinator_address = 'host:0' is invalid"),
    (dict(coordinator_address="host:65536"), "coordinator_address = 'host:65536' is invalid"),
    (dict(coordinator_address="host:http"), "coordinator_address = 'host:http' is invalid"),
    (dict(num_processes=0), "num_processes = 0 is invalid: expected an int >= 1"),
    (dict(num_processes=2.0), "num_processes = 2.0 is invalid"),
    (dict(process_id=-1), r"process_id = -1 is invalid: expected an int with 0 <= process_id < num_processes\.$"),
    (dict(process_id=0.0), "process_id = 0.0 is invalid"),
    (dict(num_processes=2, process_id=2), "process_id = 2 is invalid: expected an int with 0 <= process_id < "
                                          "num_processes = 2"),
])
def test_initialize_refuses_a_malformed_setting_by_name_before_calling_jax(kw, message, monkeypatch):
    from jaxrod.distributed import initialize

    calls = []
    monkeypatch.setattr(jax.distributed, "initialize", lambda *a, **k: calls.append((a, k)))
    with pytest.raises(ValueError, match=message):
        initialize(**kw)
    assert calls == []


def test_initialize_hands_valid_settings_and_the_timeout_to_jax(monkeypatch):
    from jaxrod.distributed import initialize

    calls = []
    monkeypatch.setattr(jax.distributed, "initialize", lambda *a, **k: calls.append((a, k)))
    initialize("10.0.0.1:1", 2, 1, timeout=7)  # the smallest port, the last process
    initialize("node:65535", 1, 0)  # the largest port, a run of one process
    initialize()  # everything from the cluster's environment
    assert calls == [(("10.0.0.1:1", 2, 1), dict(initialization_timeout=7)),
                     (("node:65535", 1, 0), dict(initialization_timeout=300)),
                     ((None, None, None), dict(initialization_timeout=300))]


def test_initialize_outside_a_cluster_names_the_missing_setting(monkeypatch):
    """JAX's own checks (its runtime state, with cluster detection off, as outside any cluster),
    reported by the name of the argument; any other error passes unchanged."""
    from jax._src import distributed as jax_distributed

    from jaxrod.distributed import initialize

    monkeypatch.delenv("JAX_COORDINATOR_ADDRESS", raising=False)
    monkeypatch.delenv("JAX_LOCAL_DEVICE_IDS", raising=False)

    def outside(*args, **kw):  # a fresh runtime state: nothing global is touched
        return jax_distributed.State().initialize(*args, cluster_detection_method="deactivate", **kw)

    monkeypatch.setattr(jax.distributed, "initialize", outside)
    for args, name in (((), "coordinator_address"), (("127.0.0.1:1234",), "num_processes"),
                       (("127.0.0.1:1234", 2), "process_id")):
        with pytest.raises(ValueError, match=f"^{name} is missing: no SLURM, Open MPI or Kubernetes cluster"):
            initialize(*args)
    other = ValueError("the port is taken")

    def taken(*args, **kw):
        raise other

    monkeypatch.setattr(jax.distributed, "initialize", taken)
    with pytest.raises(ValueError) as err:
        initialize("127.0.0.1:1234", 2, 0)
    assert err.value is other


def test_one_process_shares_everything_and_gathers_its_own_arrays_flat():
    from jaxrod.distributed import broadcast, gather, share

    items = list(range(7))
    assert share(items) == items and share("abc") == "abc"
    a = np.arange(6, dtype=np.float32).reshape(2, 3)
    b = np.array([True, False])
    out = gather({"b": b, "a": a})
    assert len(out) == 1 and list(out[0]) == ["b", "a"]
    assert out[0]["a"].dtype == np.float32 and out[0]["a"].shape == (6,)
    np.testing.assert_array_equal(out[0]["a"], a.reshape(-1))
    np.testing.assert_array_equal(out[0]["b"], b)
    x = np.array([1.0, np.nan, -0.0])
    y = broadcast(x)
    assert y.dtype == x.dtype and y.tobytes() == x.tobytes()


def test_share_deals_every_kth_item_to_process_k(monkeypatch):
    from jaxrod.distributed import share

    monkeypatch.setattr(jax, "process_count", lambda: 3)
    dealt = []
    for pid in range(3):
        monkeypatch.setattr(jax, "process_index", lambda pid=pid: pid)
        dealt.append(share(list(range(10))))
    assert dealt == [[0, 3, 6, 9], [1, 4, 7], [2, 5, 8]]


class TwoProcesses:
    """Two threads standing in for two processes: `process_allgather` meets at a barrier and
    returns every process's array stacked in process order, as JAX's collective does."""

    def __init__(self):
        self.barrier = threading.Barrier(2, timeout=20)
        self.slots = [None, None]
        self.local = threading.local()

    def allgather(self, x):
        self.slots[self.local.pid] = np.array(x)
        self.barrier.wait()
        out = np.stack(self.slots)
        self.barrier.wait()  # both have read before the next call overwrites
        return out

    def run(self, fn, args, monkeypatch):
        from jax.experimental import multihost_utils

        monkeypatch.setattr(jax, "process_count", lambda: 2)
        monkeypatch.setattr(multihost_utils, "process_allgather", self.allgather)

        def one(pid):
            self.local.pid = pid
            return fn(args[pid])

        with ThreadPoolExecutor(2) as pool:
            return list(pool.map(one, (0, 1)))


def same_bits(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_gather_returns_every_process_arrays_bit_for_bit_whatever_their_lengths(monkeypatch):
    from jaxrod.distributed import gather

    p0 = {"x": np.array([1.5, np.nan, -0.0, 1e-310]), "k": np.array([7], np.int32),
          "ok": np.array([True, False])}
    p1 = {"x": np.array([2.0]), "k": np.zeros(0, np.int32), "ok": np.array([True, True, False])}
    both = TwoProcesses().run(gather, (p0, p1), monkeypatch)
    for got in both:  # each process receives the same list, in process order
        assert len(got) == 2
        for want, part in zip((p0, p1), got):
            assert list(part) == ["x", "k", "ok"]
            for name in want:
                assert same_bits(part[name], want[name]), name


def test_gather_of_empty_and_one_byte_arrays_keeps_names_and_dtypes(monkeypatch):
    from jaxrod.distributed import gather

    empty = {"x": np.zeros(0), "k": np.zeros(0, np.int64)}
    both = TwoProcesses().run(gather, (empty, empty), monkeypatch)
    for got in both:
        assert len(got) == 2
        for part in got:
            assert same_bits(part["x"], np.zeros(0)) and same_bits(part["k"], np.zeros(0, np.int64))
    one = np.array([True])  # a single byte in all: the smallest message that carries data
    both = TwoProcesses().run(gather, ({"b": one}, {"b": np.zeros(0, bool)}), monkeypatch)
    for got in both:
        assert same_bits(got[0]["b"], one) and same_bits(got[1]["b"], np.zeros(0, bool))


def test_broadcast_gives_every_process_the_array_of_process_0(monkeypatch):
    from jaxrod.distributed import broadcast

    first = np.array([3, 1, 4, 1, 5], np.int16)
    both = TwoProcesses().run(broadcast, (first, np.zeros(0, np.int16)), monkeypatch)
    assert all(same_bits(b, first) for b in both)


# --------------------------------------------------------------------------- helix


def test_helix_theory_gives_the_onset_band_and_the_sinusoidal_load():
    rod = jr.RodChannel.reference(0.0)
    EI, w, R, L = float(rod.EI), float(rod.w), float(rod.R), float(rod.L)
    from jaxrod.experiments.helix import helix_theory

    th = helix_theory(rod)
    assert math.isclose(th["onset_chen"] ** 2, 8.0 * EI * w / R, rel_tol=1e-12)  # (2√2)² EIw/R
    assert math.isclose(th["onset_mitchell"], 2.0 * th["onset_chen"], rel_tol=1e-12)
    om = 6 * math.pi / L  # mode 6, the reference rod's critical mode
    assert math.isclose(th["sinusoidal_onset"], EI * om**2 + w / (R * om**2), rel_tol=1e-12)


def test_helix_measures_of_a_batch_of_states():
    """Three states on the wall of a 102-segment rod (no node at L/4 or 3L/4: the middle half is
    nodes 26..76; segments 25..76): a right-handed helix whose θ is a multiple of 2π at nodes
    34, 51, 68, its mirror image, and a rod that winds three times in one short twist (many turns,
    θ far from linear: not a helix)."""
    from jaxrod.experiments.helix import helix_measures

    rod = jr.RodChannel.reference(0.0)
    L, R, w = float(rod.L), float(rod.R), float(rod.w)
    n, beta = 102, 4 * math.pi
    s = np.linspace(0.0, L, n + 1)
    thetas = np.stack([beta * s, -beta * s, 3 * math.pi * (1.0 + np.tanh((s - 1.5) / 0.1))])
    x = np.stack([np.broadcast_to(s, thetas.shape), R * np.sin(thetas), -R * np.cos(thetas)], -1)
    N_eq = 0.7
    N = N_eq + w * np.cos(thetas)
    axial = np.broadcast_to(5.0 + 0.01 * np.arange(n), (3, n))
    h = helix_measures(rod, x, N, axial)

    np.testing.assert_allclose(h["theta"], thetas, atol=1e-12)
    np.testing.assert_allclose(h["turns"][:2], [beta * (s[76] - s[26]) / (2 * math.pi),
                                                -beta * (s[76] - s[26]) / (2 * math.pi)], rtol=1e-12)
    assert abs(h["turns"][2] - 3.0) < 1e-3
    np.testing.assert_allclose(h["beta"][:2], beta, rtol=1e-12)
    np.testing.assert_allclose(h["linearity"][:2], 1.0, atol=1e-12)
    assert 0.5 < h["linearity"][2] < 0.95
    assert h["helical"].tolist() == [True, True, False]
    np.testing.assert_allclose(h["pitch"][:2], 0.5, rtol=1e-12)
    assert h["pitch"][2] == np.inf
    np.testing.assert_allclose(h["F"], 5.0 + 0.01 * np.mean(np.arange(25, 77)), rtol=1e-12)
    np.testing.assert_allclose(h["N_mean"], N_eq + w * np.cos(thetas[:, 26:77]).mean(-1), rtol=1e-12)
    # at nodes 34, 51 and 68 the helix lies at the bottom: there gravity adds its full w
    np.testing.assert_allclose(h["N_bottom"][:2], N_eq + w, rtol=1e-12)
    assert np.isnan(h["N_bottom"][2])
    np.testing.assert_allclose(h["N_minus_gravity"], N_eq, rtol=1e-12)
    np.testing.assert_allclose(h["max_abs_theta"], [beta * s[n - 1], beta * s[n - 1], np.abs(thetas[2, 1:-1]).max()],
                               rtol=1e-12)
    assert h["over_top"].tolist() == [True, True, True]


def test_a_rod_below_a_quarter_turn_is_not_over_the_top():
    from jaxrod.experiments.helix import helix_measures

    rod = jr.RodChannel.reference(0.0)
    L, R = float(rod.L), float(rod.R)
    s = np.linspace(0.0, L, 41)
    th = 0.9 * np.sin(2 * math.pi * s / L)  # |θ| < π/2: below the axis everywhere
    x = np.stack([s, R * np.sin(th), -R * np.cos(th)], -1)
    h = helix_measures(rod, x, np.ones(41), np.ones(40))
    assert not h["over_top"] and not h["helical"] and math.isclose(h["max_abs_theta"], 0.9, rel_tol=1e-3)


def test_loop_area_is_the_enclosed_area_signed_by_the_direction():
    from jaxrod.experiments.helix import _loop_area

    # load at 2 N over 1 mm, drop to 1 N, unload: the work lost is the rectangle, 1 mJ
    d = np.array([0.0, 1e-3, 1e-3, 0.0, 0.0])
    F = np.array([2.0, 2.0, 1.0, 1.0, 2.0])
    assert math.isclose(_loop_area(d, F), 1e-3, rel_tol=1e-12)
    assert math.isclose(_loop_area(d[::-1], F[::-1]), -1e-3, rel_tol=1e-12)
    # a triangle (trapezoid rule exact on straight sides): area ½·2·3
    assert math.isclose(_loop_area(np.array([0.0, 2.0, 2.0, 0.0]), np.array([0.0, 3.0, 0.0, 0.0])), 3.0,
                        rel_tol=1e-12)


# --------------------------------------------------------------------------- settings


def test_the_reproduction_settings_are_finite_and_grow_with_the_resolution():
    from jaxrod.experiments._settings import _settings

    tiny, quick, full = _settings("tiny"), _settings(True), _settings(False)
    assert set(tiny) == set(quick) == set(full) == {"n", "mus", "realizations", "map_dF", "map_v0", "t1", "max_dF"}
    for s in (tiny, quick, full):
        assert isinstance(s["t1"], float) and 0.1 <= s["t1"] <= 2.0
        assert isinstance(s["max_dF"], float) and math.isfinite(s["max_dF"]) and s["max_dF"] >= s["map_dF"][1]
        mus = np.asarray(s["mus"])
        assert mus.dtype == np.float64 and np.all(np.diff(mus) > 0) and 0 < mus[0] and mus[-1] == 1.0
        assert isinstance(s["realizations"], int) and s["realizations"] >= 2
        for lo, hi, count in (s["map_dF"], s["map_v0"]):
            assert 0 < lo < hi and math.isfinite(hi) and isinstance(count, int) and count >= 4
    assert full["n"] is None  # the scene's default resolution
    assert isinstance(tiny["n"], int) and isinstance(quick["n"], int) and 16 <= tiny["n"] < quick["n"]
    for key in ("realizations",):
        assert tiny[key] <= quick[key] < full[key]
    for key in ("map_dF", "map_v0"):
        assert tiny[key][:2] == quick[key][:2] == full[key][:2] and tiny[key][2] <= quick[key][2] < full[key][2]
    assert len(tiny["mus"]) <= len(quick["mus"]) < len(full["mus"]) and quick["t1"] <= full["t1"]


# --------------------------------------------------------------------------- E4 helpers


def test_e4_fit_recovers_an_exact_power_law_from_its_positive_finite_points():
    from jaxrod.experiments.e4.field import _fit

    x = np.array([0.05, 0.1, 0.3, 0.6, 1.0])
    y = 7.0 * x**2
    p, se, c = _fit(x, y)
    assert math.isclose(p, 2.0, rel_tol=1e-12) and se < 1e-10 and math.isclose(c, 7.0, rel_tol=1e-12)
    y_bad = y.copy()
    y_bad[[1, 2, 3]] = [np.nan, 0.0, -1.0]  # a failed search and non-positive values are left out
    p, _, c = _fit(x, y_bad)
    assert math.isclose(p, 2.0, rel_tol=1e-12) and math.isclose(c, 7.0, rel_tol=1e-12)
    assert all(math.isnan(v) for v in _fit(x[:2], [np.nan, 3.0]))


def test_e4_frictionless_critical_load_is_the_growth_of_a_free_sine_mode():
    """At μ = 0 the sine velocity v₀ sin(6πs/L) grows as θ(t) = (v₀/R) sinh(λt)/λ with
    λ² = −k₆(F⁰ + ΔF) (P3); ΔF* is the load where θ(t1) reaches the 0.5 rad threshold. The
    field model's default 128 nodes resolve mode 6 to within about 1 % of it."""
    from jaxrod.experiments.e4.field import _frictionless_dF

    rod = jr.RodChannel.reference(0.0)
    F0 = float(theory.reference_load(rod))
    v0, t1 = 1e-3, 0.3

    def theta(dF):
        lam = math.sqrt(-float(theory.stiffness(rod, 6, F0 + dF)))
        return v0 / float(rod.R) * math.sinh(lam * t1) / lam - 0.5

    closed = scipy.optimize.brentq(theta, 1e-6, 1.0, xtol=1e-12)
    dF, result = _frictionless_dF({"n": None, "t1": t1}, v0, "sine")
    assert result == 0
    assert math.isclose(dF, closed, rel_tol=0.02), (dF, closed)


# --------------------------------------------------------------------------- convergence


def test_dominant_modes_at_repeats_each_realization_of_the_search():
    """Entry (i, r) is the run of μ = mus[i], ΔF = dFs[i, r] from the realization
    fold_in(key(seed), i·R + r), with the step of the largest load; the low-friction, high-load
    entry is the one that buckles."""
    from jaxrod.experiments.convergence import dominant_modes_at
    from jaxrod.modal import dominant_mode
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    mus, dFs, n, t1 = np.array([0.3, 0.9]), np.array([[5.0, 150.0], [5.0, 300.0]]), 8, 0.3
    modes, buckled = dominant_modes_at("random-position", 2.0, mus, dFs, n, 2, seed=5, t1=t1)
    assert modes.shape == buckled.shape == (2, 2)
    dt = Scene(jr.RodChannel.reference(), 300.0, kind="field", n=n).step()
    for i in range(2):
        for r in range(2):
            key = jax.random.fold_in(jax.random.key(5), i * 2 + r)
            sc = Scene(jr.RodChannel.reference(mu=float(mus[i])), float(dFs[i, r]),
                       make_perturbation("random-position", 2.0, 6, key), "field", n, 6, dt)
            sol = sc.run(t1=t1, n_save=201, save_state=False)
            assert int(modes[i, r]) == int(dominant_mode(sol.q_final)), (i, r)
            assert bool(buckled[i, r]) == bool(sol.buckled), (i, r)
    assert buckled.tolist() == [[False, True], [False, False]]


def test_convergence_tabulates_each_search_and_the_modes_past_it(tmp_path, monkeypatch):
    """The driver's bookkeeping, with the searches and the runs past them replaced by recorders:
    ΔF* means skip failed searches, a mode counts only where its search succeeded and the rod
    buckled, and the CSV has one row per (kind, n, μ, realization)."""
    import jaxrod.boundary
    from jaxrod.experiments import convergence as conv

    monkeypatch.setitem(conv.SIZES, "tiny", dict(mus=(0.3, 0.9), realizations=2,
                                                 n={"random-velocity": (16, 24), "random-position": (12, 20)},
                                                 t1=0.25))
    searches, runs = [], []

    def roots(kind, n):
        base = 10.0 if kind == "random-velocity" else 3.0
        return np.array([[base * n, np.nan], [base * n + 1.0, base * n + 3.0]])

    def search(mus, amp, *, perturbation, realizations, seed, n, t1, bracket, rtol):
        searches.append(dict(mus=list(mus), amp=amp, kind=perturbation, R=realizations, seed=seed, n=n, t1=t1,
                             bracket=bracket, rtol=rtol))
        return SimpleNamespace(root=roots(perturbation, n)), None

    def modes_at(kind, amp, mus, dFs, n, R, seed):
        runs.append((kind, n, seed))
        assert amp == conv.AMPLITUDES[kind]  # the runs at 1.05 ΔF* have the searches' amplitude
        np.testing.assert_allclose(dFs, roots(kind, n) * 1.05, rtol=1e-15)
        return np.array([[n // 2, 7], [6, 8]]), np.array([[True, True], [False, True]])

    monkeypatch.setattr(jaxrod.boundary, "critical_load_curve", search)
    monkeypatch.setattr(conv, "dominant_modes_at", modes_at)
    res = conv.convergence(str(tmp_path), quick="tiny", progress=False, max_dF=50.0)

    assert searches == [dict(mus=[0.3, 0.9], amp=conv.AMPLITUDES[k], kind=k, R=2, seed=5, n=n, t1=0.25,
                             bracket=(1e-3, 50.0), rtol=1e-4)
                        for k, ns in (("random-velocity", (16, 24)), ("random-position", (12, 20))) for n in ns]
    assert runs == [("random-velocity", 16, 5), ("random-velocity", 24, 5), ("random-position", 12, 5),
                    ("random-position", 20, 5)]
    assert {k: res[k] for k in ("model", "realizations", "seed", "rtol")} == dict(
        model="field", realizations=2, seed=5, rtol=1e-4)
    v3 = res["random-velocity, mu=0.3"]
    assert v3["n"] == [16, 24] and v3["dF_star_mean"] == [160.0, 240.0]
    np.testing.assert_array_equal(v3["dominant_mode"], [[8.0, np.nan], [12.0, np.nan]])
    np.testing.assert_array_equal(v3["dF_star"], [[160.0, np.nan], [240.0, np.nan]])
    assert v3["dominant_mode_mean"] == [8.0, 12.0]
    assert math.isclose(v3["last_change_rel"], 240.0 / 160.0 - 1, rel_tol=1e-12)
    p9 = res["random-position, mu=0.9"]
    assert p9["dF_star"] == [[37.0, 39.0], [61.0, 63.0]]
    assert p9["dF_star_mean"] == [38.0, 62.0]
    np.testing.assert_array_equal(p9["dominant_mode"], [[np.nan, 8.0], [np.nan, 8.0]])
    assert p9["dominant_mode_mean"] == [8.0, 8.0]  # the unbuckled realization is left out
    assert math.isclose(p9["last_change_rel"], 62.0 / 38.0 - 1, rel_tol=1e-12)
    rows = read_csv(tmp_path / "convergence.csv")
    assert list(rows[0]) == ["perturbation", "mu", "n", "realization", "dF_star", "dominant_mode"]
    assert len(rows) == 2 * 2 * 2 * 2
    assert rows[1] == dict(perturbation="random-velocity", mu="0.3", n="16", realization="1", dF_star="nan",
                           dominant_mode="nan")
    assert rows[-1] == dict(perturbation="random-position", mu="0.9", n="20", realization="1", dF_star="63.0",
                            dominant_mode="8.0")
    # one resolution per kind: no change between resolutions to report (NaN), the rest as before
    conv.SIZES["tiny"]["n"] = {"random-velocity": (16,), "random-position": (12,)}
    one = conv.convergence(str(tmp_path), quick="tiny", progress=False, max_dF=50.0)
    assert all(math.isnan(one[k]["last_change_rel"]) for k in one if ", mu=" in k)
    assert one["random-velocity, mu=0.3"]["dF_star_mean"] == [160.0]
    assert (tmp_path / "convergence.png").stat().st_size > 0


# --------------------------------------------------------------------------- E1 and E1 speed


def test_e1_speed_exponent_fits_only_the_positive_overshoots_inside_the_fit_range():
    from jaxrod.experiments.e1_speed import FIT_RANGE, _exponent

    lo, hi = FIT_RANGE
    speeds = np.array([lo / 3, lo, 3e-4, 1e-3, hi, 3 * hi])
    over = 0.8 * speeds ** (2 / 3)
    over[0], over[-1] = 50.0, 1e-9  # outside the range: off the law, and left out
    p, se = _exponent(speeds, over)
    assert math.isclose(p, 2 / 3, rel_tol=1e-12) and se < 1e-10
    over[2], over[3] = np.nan, -0.1  # a run that did not buckle, an undershoot
    p, se = _exponent(speeds, over)
    assert math.isclose(p, 2 / 3, rel_tol=1e-12) and math.isnan(se)  # two points: no error estimate
    over[1] = 0.0
    assert all(math.isnan(v) for v in _exponent(speeds, over))


def test_e1_speed_records_field_and_known_3d_runs_and_fits_the_exponent(tmp_path, monkeypatch):
    """The quick setting with the field runs and the one missing 3D run replaced by recorders:
    field overshoots on an exact speed^(2/3) law give the exponent 2/3; the 3D runs at 1 mm/s
    come from `known`, the one at 0.3 mm/s is run, and a curve that did not peak is NaN."""
    from jaxrod.experiments import e1_speed as mod

    rod = jr.RodChannel.reference(0.0)
    F0 = float(theory.reference_load(rod))
    S = mod.SIZES[True]
    field_calls, rod_calls = [], []

    def ramp(rod_, speed, v0s, n):
        field_calls.append((float(rod_.mu_d), speed, tuple(v0s), n))
        return F0 + np.array([(k + 1) * 40.0 * speed ** (2 / 3) for k in range(len(v0s))])

    def curves(mu, v0s, n, speed, t1, n_save):
        rod_calls.append((mu, tuple(v0s), n, speed, t1, n_save))
        return dict(critical_force=np.array([2.5, 2.2]), peaked=np.array([True, False]))

    monkeypatch.setattr(mod, "field_ramp_force", ramp)
    monkeypatch.setattr(mod, "e1_curves", curves)
    known = {(1e-3, 5e-3): 2.9, (1e-3, 10e-3): 2.6, (3e-4, 5e-3): 99.0}  # 0.3 mm/s: one of two known
    res = mod.e1_speed(str(tmp_path), quick=True, progress=False, n_field=16, known=known)

    assert field_calls == [(0.0, sp, S["v0s"], 16) for sp in S["field_speeds"]]
    assert rod_calls == [(0.0, S["v0s_3d"], S["n3d"], 3e-4, 0.8, 801)]
    assert res["mu"] == 0.0 and res["F0_6"] == F0 and res["n_field"] == 16 and res["n_segments_3d"] == S["n3d"]
    assert math.isclose(res["load_rate_N_per_s_at_1mm_s"], float(rod.EA) * 1e-3 / float(rod.L), rel_tol=1e-12)
    assert res["theory_exponent"] == 2 / 3 and res["field"]["fit_speeds_m_s"] == list(mod.FIT_RANGE)
    np.testing.assert_allclose(res["field"]["overshoot_exponent"], [2 / 3] * 3, rtol=1e-10)
    np.testing.assert_allclose(res["field"]["critical_force_N"][1], F0 + np.array([40.0, 80.0, 120.0]) * 1e-2,
                               rtol=1e-12)  # at 1 mm/s, (1e-3)^(2/3) = 1e-2
    assert (res["field"]["speeds_m_s"], res["field"]["v0_m_s"]) == (list(S["field_speeds"]), list(S["v0s"]))
    assert (res["rod3d"]["speeds_m_s"], res["rod3d"]["v0_m_s"]) == (list(S["rod_speeds"]), list(S["v0s_3d"]))
    assert res["threshold_field_rad"] == 0.5
    assert res["rod3d"]["critical_force_N"][0] == [2.9, 2.6]
    assert res["rod3d"]["critical_force_N"][1][0] == 2.5 and math.isnan(res["rod3d"]["critical_force_N"][1][1])
    e3d = res["rod3d"]["overshoot_exponent"]
    assert math.isclose(e3d[0], math.log((2.9 - F0) / (2.5 - F0)) / math.log(1e-3 / 3e-4), rel_tol=1e-12)
    assert math.isnan(e3d[1])
    rows = read_csv(tmp_path / "e1_speed.csv")
    assert list(rows[0]) == ["model", "n", "speed_m_s", "v0_m_s", "critical_force_N", "overshoot_N"]
    assert len(rows) == len(S["field_speeds"]) * len(S["v0s"]) + len(S["rod_speeds"]) * len(S["v0s_3d"])
    assert [r["model"] for r in rows].count("rod3d") == 4
    first3d = rows[len(S["field_speeds"]) * len(S["v0s"])]
    assert (first3d["model"], float(first3d["speed_m_s"]), float(first3d["critical_force_N"])) == ("rod3d", 1e-3, 2.9)
    assert math.isclose(float(first3d["overshoot_N"]), 2.9 - F0, rel_tol=1e-12)
    last = rows[-1]
    assert (last["model"], last["n"], float(last["speed_m_s"]), float(last["v0_m_s"])) == ("rod3d", "40", 3e-4, 10e-3)
    assert last["critical_force_N"] == last["overshoot_N"] == "nan"
    assert math.isclose(float(rows[0]["overshoot_N"]), float(rows[0]["critical_force_N"]) - F0, rel_tol=1e-12)
    assert (tmp_path / "e1_speed.png").stat().st_size > 0


def test_e1_tabulates_its_3d_curves_and_hands_its_peaked_runs_to_e1_speed(tmp_path, monkeypatch):
    from jaxrod.experiments import e1 as mod
    from jaxrod.experiments.rod3d import SIZES

    S = SIZES["tiny"]
    calls, speed_calls = [], []

    def curves(mu, v0s, n, t1, n_save):
        calls.append((mu, tuple(v0s), n, t1, n_save))
        k = len(v0s)
        d = np.tile(np.linspace(0.0, 1e-3, 11), (k, 1))
        return dict(displacement=d, reaction=3.0 * d / 1e-3 + mu, critical_force=2.0 + mu + np.arange(k),
                    d_critical=np.full(k, 4e-4), buckled=np.ones(k, bool), peaked=np.arange(k) == 0,
                    balance=np.full(k, 1e-6), dt=1e-5)

    def speed(out, quick, progress, known):
        speed_calls.append((out, quick, progress, known))
        return {"from": "e1_speed"}

    monkeypatch.setattr(mod, "e1_curves", curves)
    monkeypatch.setattr(mod, "e1_speed", speed)
    res = mod.e1(str(tmp_path), quick="tiny", progress=False)

    v0s = tuple(S["v0s"])
    assert calls == [(0.0, v0s, S["n"], S["t1"], S["n_save"]), (0.3, v0s, S["n"], S["t1"], S["n_save"])] + [
        (0.3, (15e-3,), n, S["t1"], S["n_save"]) for n in S["conv"]]
    assert res["model"] == "rod3d" and res["n_segments"] == S["n"] and res["speed_m_s"] == 1e-3
    assert res["v0_m_s"] == list(v0s)
    rod = jr.RodChannel.reference(0.0)
    om = 6 * math.pi / float(rod.L)
    assert math.isclose(res["F0_6_theory"], float(rod.EI) * om**2 + float(rod.w) / (float(rod.R) * om**2),
                        rel_tol=1e-12)
    assert res["mu=0.3"]["critical_force"] == [2.3, 3.3]
    assert res["mu=0.0"]["d_critical_mm"] == [0.4, 0.4] and res["mu=0.0"]["peaked"] == [True, False]
    assert res["mu=0.0"]["buckled"] == [True, True] and res["mu=0.0"]["energy_balance_max_J"] == [1e-6, 1e-6]
    assert res["mu=0.0"]["dt"] == 1e-5
    assert res["convergence"] == dict(mu=0.3, v0=15e-3, n_segments=list(S["conv"]),
                                      critical_force=[2.3] * len(S["conv"]))
    # E1's μ = 0 runs at 1 mm/s are reused by the speed study (same segment count), peaked ones only
    assert speed_calls == [(str(tmp_path), "tiny", False, {(1e-3, v0s[0]): 2.0})]
    assert res["speed"] == {"from": "e1_speed"}
    rows = read_csv(tmp_path / "e1_force_displacement.csv")
    assert list(rows[0]) == ["mu", "v0", "displacement", "reaction"]
    assert len(rows) == 2 * len(v0s) * 3  # every fifth of 11 saves: 0, 5, 10
    assert [float(r["displacement"]) for r in rows[:3]] == [0.0, 5e-4, 1e-3]
    assert [float(r["reaction"]) for r in rows[-3:]] == [0.3, 1.8, 3.3]
    assert (tmp_path / "e1_force_displacement.png").stat().st_size > 0


# --------------------------------------------------------------------------- E5


def test_e5_averages_the_modes_of_successful_buckled_runs_and_names_the_theory_mode(tmp_path, monkeypatch):
    """E5 in the tiny setting with its searches, the runs past them and the convergence study
    replaced by recorders: a realization counts only where its search succeeded and its run
    buckled; the theory's mode is the one whose P7 load is lowest for the equal modal velocity
    of a uniform ±15 mm/s noise on n nodes."""
    import jaxrod.boundary
    from jaxrod.experiments._settings import _settings
    from jaxrod.experiments.e5 import field as mod

    s = _settings("tiny")
    n, mus, R = s["n"], s["mus"], s["realizations"]
    assert len(mus) == 3 and R == 2
    root = np.array([[2.0, 4.0], [6.0, 8.0], [10.0, 12.0]])
    result = np.array([[0, 0], [0, 2], [0, 0]])
    searches, runs, studies = [], [], []

    def search(mus_, amp, *, perturbation, realizations, seed, n, t1, bracket, rtol):
        searches.append((list(mus_), amp, perturbation, realizations, seed, n, t1, bracket, rtol))
        return SimpleNamespace(root=root, result=result), None

    def modes_at(kind, amp, mus_, dFs, n_, R_, seed):
        runs.append((kind, amp, n_, R_, seed))
        np.testing.assert_allclose(dFs, root * 1.05, rtol=1e-15)
        return np.array([[6, 8], [7, 9], [10, 12]]), np.array([[True, True], [True, True], [True, False]])

    monkeypatch.setattr(jaxrod.boundary, "critical_load_curve", search)
    monkeypatch.setattr(mod, "dominant_modes_at", modes_at)
    monkeypatch.setattr(mod, "convergence", lambda *a: studies.append(a) or {"studied": True})
    res = mod.e5(str(tmp_path), "tiny", False)

    kinds = (("random-velocity", 15e-3), ("random-position", 2.0))
    assert searches == [(mus.tolist(), amp, k, R, 5, n, s["t1"], (1e-3, s["max_dF"]), 1e-4) for k, amp in kinds]
    assert runs == [(k, amp, n, R, 5) for k, amp in kinds]
    assert studies == [(str(tmp_path), "tiny", False)] and res["convergence"] == {"studied": True}
    assert res["model"] == "field" and res["n"] == n
    for kind, amp in kinds:
        r = res[kind]
        assert r["n"] == n and r["amplitude"] == amp and r["mu"] == mus.tolist()
        # μ[1]: the second search failed; μ[2]: the second run did not buckle
        assert r["dominant_mode_mean"] == [7.0, 7.0, 10.0] and r["dominant_mode_std"] == [1.0, 0.0, 0.0]
        assert r["dominant_mode_min"] == 6.0
        np.testing.assert_allclose(r["dF_evaluated"], [3.15, 6.3, 11.55], rtol=1e-12)
    th = res["theory_first_mode_equal_modal_velocity"]
    a = 15e-3 / math.sqrt(3.0) * math.sqrt(2.0 / (n + 1)) / float(jr.RodChannel.reference().R)
    assert math.isclose(th["modal_velocity_rad_s"], a, rel_tol=1e-12) and th["mu"] == mus.tolist()
    for mu, mode in zip(mus, th["mode"]):
        rod = jr.RodChannel.reference(float(mu))
        loads = [float(theory.critical_load_velocity(rod, m, a)) for m in range(1, n + 1)]
        assert mode == 1 + int(np.argmin(loads)) and mode >= 6
    rows = read_csv(tmp_path / "e5_modes.csv")
    assert list(rows[0]) == ["perturbation", "mu", "mode_mean", "mode_std"] and len(rows) == 6
    assert [(r["perturbation"], float(r["mode_mean"])) for r in rows[3:]] == [("random-position", 7.0)] * 2 + [
        ("random-position", 10.0)]
    assert (tmp_path / "e5_modes.png").stat().st_size > 0


def test_e5_at_the_default_resolution_takes_each_perturbations_own_node_count(tmp_path, monkeypatch):
    """Without a node count in the setting (the full run), E5 records the sine default for the
    largest load F⁰₆ + max ΔF, and searches and runs each perturbation at its scene's own size."""
    import jaxrod.boundary
    from jaxrod.experiments._settings import _settings
    from jaxrod.experiments.e5 import field as mod
    from jaxrod.models.field import default_nodes
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    s = dict(_settings("tiny"), n=None)
    monkeypatch.setattr(mod, "_settings", lambda quick: s)
    ns = []

    def search(mus_, amp, *, perturbation, realizations, seed, n, t1, bracket, rtol):
        ns.append((perturbation, n))
        return SimpleNamespace(root=np.ones((3, 2)), result=np.zeros((3, 2), int)), None

    monkeypatch.setattr(jaxrod.boundary, "critical_load_curve", search)
    monkeypatch.setattr(mod, "dominant_modes_at", lambda kind, amp, mus_, dFs, n_, R_, seed: (
        ns.append((kind, n_)) or (np.full((3, 2), 6), np.ones((3, 2), bool))))
    monkeypatch.setattr(mod, "convergence", lambda *a: {})
    res = mod.e5(str(tmp_path), "full", False)
    rod0 = jr.RodChannel.reference()
    assert res["n"] == default_nodes(rod0, float(theory.reference_load(rod0)) + s["max_dF"])
    for kind, amp in (("random-velocity", 15e-3), ("random-position", 2.0)):
        size = Scene(rod0, s["max_dF"], make_perturbation(kind, amp), "field").size()
        assert res[kind]["n"] == size and ns.count((kind, size)) == 2
    assert res["random-velocity"]["n"] != res["random-position"]["n"]  # 499 (the noise grid) and the sine default


def test_e1_speed_runs_the_field_model_at_the_resolution_of_the_committed_study(tmp_path, monkeypatch):
    """Called as E1 calls it (no `n_field`), the speed study runs the field model at the resolution
    that made the committed E1 numbers (results/paper/results.json, `e1.speed.n_field`), so
    `jaxrod reproduce e1` remakes them."""
    import json
    import pathlib

    from jaxrod.experiments import e1_speed as mod

    committed = json.loads((pathlib.Path(__file__).parents[1] / "results/paper/results.json").read_text())
    seen = set()
    monkeypatch.setattr(mod, "field_ramp_force", lambda rod, speed, v0s, n: seen.add(n) or np.full(len(v0s), 3.0))
    monkeypatch.setattr(mod, "e1_curves", lambda mu, v0s, n, speed, t1, n_save: dict(
        critical_force=np.full(len(v0s), 2.5), peaked=np.ones(len(v0s), bool)))
    res = mod.e1_speed(str(tmp_path), quick=True, progress=False, known={})
    assert seen == {committed["e1"]["speed"]["n_field"]} and res["n_field"] == committed["e1"]["speed"]["n_field"]


@pytest.mark.parametrize("m_max, nodes", [(31.9, 128), (32.5, 384)])
def test_the_field_models_default_nodes_change_past_32_unstable_modes(m_max, nodes):
    """128 nodes while at most 32 modes are unstable (m_max = (L/π)√(F/EI) ≤ 32), 384 beyond."""
    from jaxrod.models.field import default_nodes

    rod = jr.RodChannel.reference(0.3)
    F = float(rod.EI) * (m_max * math.pi / float(rod.L)) ** 2
    assert default_nodes(rod, F) == nodes
