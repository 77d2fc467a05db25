"""The 3D rod's boundary search (`jaxrod.experiments.e3.rod3d`): the bracketing bisection
against labels with a known boundary, and the replay of recorded runs."""

import math

import pytest

from jaxrod.experiments.e3.rod3d import _bisect


def _counting(root):
    calls = []

    def label(v):
        calls.append(v)
        return v > root

    return label, calls


@pytest.mark.parametrize("root", [1.0, 1.03, 0.97, 0.5, 3.0, 1.0399])
def test_bisect_brackets_a_known_boundary_to_rtol(root):
    label, calls = _counting(root)
    lo, hi = _bisect(label, 1.0, 0.04, 0.01, 40)
    assert len(set(calls)) == len(calls)  # no amplitude run twice
    assert lo <= root < hi
    assert hi / lo - 1 <= 0.01
    assert not label(lo) and label(hi)


def test_bisect_uses_few_runs_near_the_guess():
    # inside the first bracket: its 2 ends + 4 geometric halvings of its 8.3 % (1.04/0.96) to
    # 1.005 %
    label, calls = _counting(1.01)
    _bisect(label, 1.0, 0.04, 0.01, 40)
    assert len(calls) == 6


def test_bisect_gives_up_after_max_runs():
    label, calls = _counting(math.inf)  # never buckles
    assert _bisect(label, 1.0, 0.04, 0.01, 6) is None
    assert len(calls) == 6


def test_bisect_stops_bisecting_at_max_runs_with_the_bracket_it_has():
    # bracketed by the first two runs (root inside ±4 %), then bisected: 8 runs in all leave a
    # bracket of 8.3 %/2⁶ ≈ 0.13 %, wider than the rtol of 1e-9 it never reaches
    label, calls = _counting(1.01)
    lo, hi = _bisect(label, 1.0, 0.04, 1e-9, 8)
    assert len(calls) == 8
    assert lo <= 1.01 < hi and 1e-3 < hi / lo - 1 < 2e-3


def test_bisect_gives_up_when_every_amplitude_down_to_a_millionth_buckles():
    # buckles at any v > 0 but not at 0 (a rod the load buckles from its straight state, 3D at
    # 60 N with 60 segments): the downward doubling stops at guess·1e-6 instead of reaching 0
    label, calls = _counting(0.0)
    assert _bisect(label, 1.0, 0.04, 0.01, 40) is None
    assert min(calls) == pytest.approx(1e-6) and all(v > 0 for v in calls)


def test_runs_file_of_older_columns_is_read_as_verlet_and_migrated(tmp_path):
    from jaxrod.experiments.e3.rod3d import RUN_COLUMNS, _append, _runs_of

    path = tmp_path / "runs.csv"
    old = [c for c in RUN_COLUMNS if c != "scheme"]
    path.write_text(",".join(old) + "\n" + "5.0,60,0.3,surface,pinned,0.001,0.4,1e-05,0.026,1,2.0\n")
    settings = (60, 0.3, 0.4, 1e-5, "surface", "pinned", 1e-3)
    assert _runs_of(str(path), *settings, "verlet") == {(5.0, 0.026): True}
    assert _runs_of(str(path), *settings, "leapfrog") == {}
    _append(str(path), dict(dF=5.0, n_segments=60, mu=0.3, friction_at="surface", ends="pinned", sink=1e-3, t1=0.4,
                            dt=1e-5, scheme="leapfrog", v0=0.025, buckled=0, seconds=1.0))
    assert path.read_text().splitlines()[0] == ",".join(RUN_COLUMNS)
    assert _runs_of(str(path), *settings, "verlet") == {(5.0, 0.026): True}
    assert _runs_of(str(path), *settings, "leapfrog") == {(5.0, 0.025): False}
    # a step within DT_RTOL (1e-3) of the recorded one is the same run; one step further is not
    near, far = list(settings), list(settings)
    near[3], far[3] = 1e-5 * (1 + 0.5e-3), 1e-5 * (1 + 2e-3)
    assert _runs_of(str(path), *near, "leapfrog") == {(5.0, 0.025): False}
    assert _runs_of(str(path), *far, "leapfrog") == {}


@pytest.mark.slow
def test_boundary_3d_replays_its_runs(tmp_path):
    from jaxrod.experiments.e3.rod3d import boundary_3d

    path = tmp_path / "runs.csv"
    first = boundary_3d([20.0], n=8, rtol=0.1, t1=0.1, runs_csv=str(path), progress=False)
    lines = path.read_text().splitlines()
    again = boundary_3d([20.0], n=8, rtol=0.1, t1=0.1, runs_csv=str(path), progress=False)
    assert path.read_text().splitlines() == lines  # nothing run again
    assert again["points"][0]["seconds_new_runs"] == 0.0
    assert again["points"][0]["bracket"] == first["points"][0]["bracket"]
    assert len(lines) - 1 == first["points"][0]["runs"]
    lo, hi = first["points"][0]["bracket"]
    assert hi / lo - 1 <= 0.1


@pytest.mark.slow
def test_label_is_the_scene_run_of_the_3d_rod():
    import jax
    import jax.numpy as jnp

    from jaxrod.boundary.indicators import crossing_state
    from jaxrod.experiments.e3.rod3d import label_3d
    from jaxrod.params import RodChannel
    from jaxrod.perturbations import SineVelocity
    from jaxrod.scene import Scene

    rod = RodChannel.reference(0.3)
    dt = Scene(rod, 20.0, SineVelocity(1e-3), kind="rod3d", n=8).step()
    label = label_3d(rod, 8, dt, 0.05)
    scene = jax.jit(lambda v0: crossing_state(Scene(rod, 20.0, SineVelocity(v0), kind="rod3d", n=8, dt=dt), 0.05))
    seen = set()
    for v0 in (2e-3, 60e-3):
        (q, _), b = scene(jnp.asarray(v0))
        assert bool(label(jnp.asarray(20.0), jnp.asarray(v0))) == bool(b)
        seen.add(bool(b))
    assert seen == {False, True}  # both labels occur


def test_bisect_stops_at_a_failed_run():
    """A failed run (label None: the 3D rod's state became non-finite) ends the search with no
    bracket instead of counting as stable."""
    calls = []

    def label(v):
        calls.append(v)
        return None if len(calls) == 3 else v > 1.3

    assert _bisect(label, 1.0, 0.04, 0.01, 40) is None and len(calls) == 3


def _predicted_against_wide(n, dF):
    """E3's 3D search from the field model's v₀* (±4 %) and plain label bisection of the same
    runs from [1e-4, 1] m/s: two brackets of one monotone label, so both hold the boundary."""
    import jaxrod as jr
    from jaxrod.experiments.e3.rod3d import boundary_3d

    pred = boundary_3d([dF], n=n, rtol=0.01, t1=0.4, progress=False)["points"][0]
    wide, _ = jr.boundary.critical_velocity(jr.RodChannel.reference(0.3), dF, model="rod3d", n=n, method="bisection",
                                            rtol=1e-2, t1=0.4, sensitivities=())
    lo, hi = pred["bracket"]
    assert int(wide.result) == 0 and hi / lo - 1 <= 0.01
    assert max(lo, float(wide.lo)) <= min(hi, float(wide.hi))  # the brackets overlap
    return pred["runs"], int(wide.evaluations)


@pytest.mark.slow  # the real 3D label at 60 segments (~30 s cold); tests/test_e3_boundary_records.py runs the
# search on a synthetic label, checking what the label is made with, in the default suite
def test_predicted_3d_search_brackets_the_boundary_at_60_segments():
    """E3's 3D search from the field model's v₀* (60 segments, 20 N, horizon 0.2 s) meets the
    target of ≤ 10 runs to a bracket of 1 %, and plain runs of the scene (`Scene.run`, not the
    search's label) hold its ends: stable at the bracket's low end, buckled at its high end."""
    import jaxrod as jr
    from jaxrod.experiments.e3.rod3d import boundary_3d
    from jaxrod.perturbations import SineVelocity

    pred = boundary_3d([20.0], n=60, rtol=0.01, t1=0.2, progress=False)["points"][0]
    lo, hi = pred["bracket"]
    assert pred["runs"] <= 10 and hi / lo - 1 <= 0.01
    rod = jr.RodChannel.reference(0.3)
    dt = jr.Scene(rod, 20.0, SineVelocity(1e-3), kind="rod3d", n=60).step()  # the search's step
    ends = [bool(jr.Scene(rod, 20.0, SineVelocity(v0), kind="rod3d", n=60, dt=dt).run(t1=0.2, n_save=2).buckled)
            for v0 in (lo, hi)]
    assert ends == [False, True]


@pytest.mark.slow  # 60 segments: 6 + 12 runs (~1.5 min)
def test_predicted_3d_search_agrees_with_wide_bisection_at_60_segments():
    runs, wide = _predicted_against_wide(60, 20.0)
    assert runs <= 10 and runs < wide


@pytest.mark.slow  # 500 segments: about 20 runs (~15 min on one core)
def test_predicted_3d_search_agrees_with_wide_bisection_at_500_segments():
    runs, wide = _predicted_against_wide(500, 20.0)
    assert runs <= 10 and runs < wide
