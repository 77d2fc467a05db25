import csv
import json
import logging
import math
import os
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.sweeps import SweepResult, SweepSpec, sweep
from jaxrod.sweeps import result as result_module

SPEC = SweepSpec(model="field", n=16, perturbation="random-velocity", t1=0.3)
INPUTS = {"dF": [2.0, 20.0], "amplitude": [0.005, 0.05], "realization": [0, 1, 2]}
FLOATS = ("t_buckle", "max_theta", "final_theta", "t_stop")
EXACT = ("buckled", "dominant_mode", "stuck", "result")


def same(a: SweepResult, b: SweepResult):
    for k in EXACT:
        np.testing.assert_array_equal(a.outputs[k], b.outputs[k], err_msg=k)
    for k in FLOATS:
        np.testing.assert_allclose(a.outputs[k], b.outputs[k], rtol=1e-10, atol=0, err_msg=k)


def run_script(code: str, env_extra=None):
    env = dict(os.environ, **(env_extra or {}))
    res = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, env=env, timeout=600)
    return res


PRELUDE = """
import jax; jax.config.update("jax_enable_x64", True)
import numpy as np, sys, os
from jaxrod.sweeps import SweepSpec, sweep
SPEC = SweepSpec(model="field", n=16, perturbation="random-velocity", t1=0.3)
INPUTS = {"dF": [2.0, 20.0], "amplitude": [0.005, 0.05], "realization": [0, 1, 2]}
"""


@pytest.mark.slow  # 30 s (a 4-device subprocess compiling twice); lanes and refills: test_pool_does_not_depend_on_lanes_refills_or_scheduling
def test_results_do_not_depend_on_chunk_size_or_device_count(tmp_path):
    ref = sweep(SPEC, INPUTS, seed=3, chunk_size=5, progress=False)
    assert ref.outputs["buckled"].any() and not ref.outputs["buckled"].all()
    out = tmp_path / "four.npz"
    code = PRELUDE + f"""
assert jax.local_device_count() == 4, jax.local_device_count()
a = sweep(SPEC, INPUTS, seed=3, chunk_size=3, progress=False)   # rounded up to 4
b = sweep(SPEC, INPUTS, seed=3, chunk_size=8, progress=False)
np.savez("{out}", **{{"a_" + k: v for k, v in a.outputs.items()}}, **{{"b_" + k: v for k, v in b.outputs.items()}})
"""
    res = run_script(code, {"XLA_FLAGS": "--xla_force_host_platform_device_count=4"})
    assert res.returncode == 0, res.stderr[-3000:]
    z = np.load(out)
    for tag in ("a_", "b_"):
        other = SweepResult(ref.inputs, {k: z[tag + k] for k in ref.outputs}, ref.shape, ref.names, ref.meta)
        same(ref, other)


def test_random_keys_differ_per_member_and_follow_the_seed():
    a = sweep(SPEC, {"dF": 20.0, "amplitude": 0.05, "realization": np.arange(6)}, seed=1, progress=False)
    b = sweep(SPEC, {"dF": 20.0, "amplitude": 0.05, "realization": np.arange(6)}, seed=2, progress=False)
    assert len(np.unique(a.outputs["max_theta"])) == 6
    assert not np.array_equal(a.outputs["max_theta"], b.outputs["max_theta"])


def test_resume_after_interruption(tmp_path):
    path = tmp_path / "run"
    code = PRELUDE + f"""
def stop(c):
    if c == 0:
        os._exit(3)   # killed right after its first chunk was written
sweep(SPEC, INPUTS, seed=3, chunk_size=4, path="{path}", progress=False, on_chunk=stop)
"""
    res = run_script(code)
    assert res.returncode == 3, res.stderr[-3000:]
    assert sorted(os.listdir(path)) == ["chunk_00000.npz", "sweep.json"]
    mtime = os.path.getmtime(path / "chunk_00000.npz")
    # a chunk half written when the process died: the temporary file it was written to (the
    # chunk's name appears only once it is complete) — ignored on resume
    (path / ".tmp_half.npz").write_bytes(b"PK\x03\x04 half a chunk")
    computed = []
    resumed = sweep(SPEC, INPUTS, seed=3, chunk_size=4, path=str(path), progress=False,
                    on_chunk=computed.append)
    assert computed == [1, 2]  # chunk 0 not recomputed
    assert os.path.getmtime(path / "chunk_00000.npz") == mtime
    full = sweep(SPEC, INPUTS, seed=3, chunk_size=4, progress=False)
    same(full, resumed)
    loaded = SweepResult.load(str(path))
    same(full, loaded)
    assert loaded.shape == (2, 2, 3) and loaded.names == ("dF", "amplitude", "realization")
    np.testing.assert_array_equal(loaded.inputs["dF"], full.inputs["dF"])
    assert sorted(p for p in os.listdir(path) if p.startswith("chunk_")) == [f"chunk_0000{c}.npz" for c in range(3)]


def test_member_ranges_concatenate_to_the_whole_sweep_and_the_csv_holds_its_numbers(tmp_path):
    """`sweep(members=…)` runs a sub-range of the global members (what a host of a distributed
    run does); `SweepResult.concatenate` of disjoint ranges, in any order, is the whole sweep;
    `to_csv` writes every member's inputs and outputs as numbers that read back equal."""
    full = sweep(SPEC, INPUTS, seed=3, chunk_size=4, progress=False)
    parts = [sweep(SPEC, INPUTS, seed=3, chunk_size=4, members=r, progress=False)
             for r in (range(8, 12), range(0, 5), range(5, 8))]
    assert [len(p) for p in parts] == [4, 5, 3]
    np.testing.assert_array_equal(parts[0].inputs["index"], [8, 9, 10, 11])
    same(full, SweepResult.concatenate(parts))
    full.to_csv(str(tmp_path / "s.csv"))
    with open(tmp_path / "s.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(full)
    for i, row in enumerate(rows):
        for k, v in {**full.inputs, **full.outputs}.items():
            want = v[i]
            got = row[k]
            if isinstance(want, (bool, np.bool_)):
                assert got in (str(bool(want)), str(int(want))), (k, got, want)
            else:
                assert float(got) == pytest.approx(float(want), rel=1e-12, abs=0.0) or (
                    np.isinf(float(want)) and float(got) == float(want)), (k, got, want)


def test_mismatched_resume_is_refused_and_metadata_round_trips(tmp_path):
    path = str(tmp_path / "run")
    res = sweep(SPEC, INPUTS, seed=3, path=path, progress=False)
    meta = json.load(open(os.path.join(path, "sweep.json")))
    assert meta["spec"] == SPEC.to_json() and meta["seed"] == 3
    assert meta["jax"] == jax.__version__ and meta["dtype"] == "float64"
    assert meta["jaxrod"] == jr.__version__ and meta["n"] == 16 and meta["dt"] > 0
    with pytest.raises(ValueError, match="different sweep"):
        sweep(SPEC, INPUTS, seed=4, path=path, progress=False)
    with pytest.raises(ValueError, match="different sweep"):
        sweep(SweepSpec(model="field", n=16, perturbation="random-velocity", t1=0.4), INPUTS, seed=3, path=path, progress=False)
    with pytest.raises(ValueError, match="different sweep"):
        sweep(SPEC, {**INPUTS, "dF": [2.0, 21.0]}, seed=3, path=path, progress=False)
    same(res, SweepResult.load(path))
    csv = tmp_path / "r.csv"
    res.to_csv(str(csv))
    lines = csv.read_text().splitlines()
    assert len(lines) == 1 + 12 and lines[0].startswith("dF,amplitude,realization,index,buckled")


def test_bad_member_is_flagged_and_the_rest_complete():
    spec = SweepSpec(model="field", n=16, perturbation="sine", t1=0.3)
    mus = [0.3, float("nan"), -0.1, 0.3, 0.3]  # the last member: a negative amplitude
    res = sweep(spec, {"mu": mus, "dF": [5.0, 5.0, 5.0, 20.0, 5.0], "amplitude": [0.05] * 4 + [-0.05]},
                combine="zip", progress=False)
    codes = res.outputs["result"].tolist()
    assert codes == [0, jr.RESULTS.invalid_input, jr.RESULTS.invalid_input, 0, jr.RESULTS.invalid_input]
    good = sweep(spec, {"mu": [0.3, 0.3], "dF": [5.0, 20.0], "amplitude": 0.05}, combine="zip", progress=False)
    for k in EXACT:
        np.testing.assert_array_equal(res.outputs[k][[0, 3]], good.outputs[k])
    assert "3 an input value is outside its valid range" in res.summary()


def test_configuration_errors_are_caught_before_any_work(tmp_path):
    path = tmp_path / "never"
    with pytest.raises(ValueError, match="unknown sweep parameter"):
        sweep(SPEC, {"dF": [1.0], "speed": [1.0]}, path=str(path), progress=False)
    with pytest.raises(ValueError, match="1-D"):
        sweep(SPEC, {"dF": [[1.0, 2.0]]}, path=str(path), progress=False)
    with pytest.raises(ValueError, match="equal lengths"):
        sweep(SPEC, {"dF": [1.0, 2.0], "amplitude": [1.0, 2.0, 3.0]}, combine="zip", path=str(path), progress=False)
    with pytest.raises(ValueError, match="combine"):
        sweep(SPEC, {"dF": [1.0]}, combine="outer", progress=False)
    with pytest.raises(ValueError, match="SweepSpec.model"):
        SweepSpec(model="rod")
    assert not path.exists()


def test_sweep_compiles_once(caplog):
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level(logging.WARNING, logger="jax"):
            sweep(SPEC, {"dF": [1.0, 3.0, 9.0], "amplitude": 0.01, "realization": [0, 1, 2]}, chunk_size=2,
                  progress=False)  # 9 members: 5 chunks, the last padded
    finally:
        jax.config.update("jax_log_compiles", False)
    compiles = [r.getMessage() for r in caplog.records if r.getMessage().startswith("Compiling jit(run_chunk)")]
    assert len(compiles) == 1, compiles


def test_ensemble_probability_with_confidence_interval():
    res = sweep(SPEC, {"dF": [2.0, 40.0], "amplitude": 0.03, "realization": np.arange(8)}, progress=False)
    prob = res.probability("realization")
    assert prob["p"].shape == (2, 1)
    # the counts are the members' labels, the band is Wilson's of those counts
    k = res.grid("buckled").sum(axis=2)
    np.testing.assert_array_equal(prob["buckled"], k)
    np.testing.assert_array_equal(prob["n"], [[8], [8]])
    np.testing.assert_array_equal(prob["p"], k / 8)
    lo, hi = jr.wilson_interval(k, 8)
    np.testing.assert_array_equal(prob["lo"], lo)
    np.testing.assert_array_equal(prob["hi"], hi)
    print("buckled of 8 at dF = 2, 40 N:", k.ravel().tolist())
    # ±30 mm/s random velocities: none buckles at 2 N, most at 40 N (measured 0 and 7 of 8)
    assert prob["p"][0, 0] == 0.0 and prob["p"][1, 0] >= 0.75
    # Wilson's score interval by hand (z = 1.96): 0 of 10 gives (0, z²/(n + z²)) = (0, 0.277537);
    # 3 of 10 the textbook (0.107789, 0.603226)
    lo, hi = jr.wilson_interval(np.array([0, 3]), np.array([10, 10]))
    np.testing.assert_allclose(lo, [0.0, 0.1077893], atol=1e-7)
    np.testing.assert_allclose(hi, [3.8416 / 13.8416, 0.6032268], atol=1e-7)
    # a 90 % band (z = 1.645) is narrower: 3 of 10 gives (0.126867, 0.558322)
    lo, hi = jr.wilson_interval(3, 10, z=1.645)
    np.testing.assert_allclose([lo, hi], [0.126867, 0.558322], atol=1e-6)


@pytest.mark.slow  # 35 s of compilation; the pool's member-equals-single-run check runs by default for the reduced models
def test_rod3d_sweep_matches_single_runs_and_flags_bad_members():
    """The 3D rod in a sweep (continuous batching, the one engine): each valid member is the run
    `jaxrod.simulate` gives for the same dead load, perturbation and step (same steps, same
    stop; amplitudes within the float32 friction pass's budget); an invalid member gets its code
    and disturbs nobody."""
    from jaxrod.rod3d import Rod3D

    spec = SweepSpec(model="rod3d", n=12, perturbation="sine", t1=0.04, dF=5.0)
    amps = [2e-3, 0.2, 0.05]
    res = sweep(spec, {"amplitude": amps, "mu": [0.3, -1.0, 0.3]}, combine="zip", progress=False)
    assert res.outputs["result"].tolist() == [0, jr.RESULTS.invalid_input, 0]
    assert res.meta["n"] == 12
    rod = jr.RodChannel.reference(0.3)
    F = float(jr.theory.frictionless_load(rod, 6)) + 5.0
    model = Rod3D(rod, 12, control="load", end_load=F)
    s = jnp.arange(13) / 12
    for i in (0, 2):
        q0, v0 = model.initial_state(F, lateral_velocity=amps[i] * jnp.sin(6 * jnp.pi * s))
        opts = jr.RunOptions(save_state=False)
        integ = jr.integrators.default_for(model, res.meta["dt"])  # the 3D rod's scheme, as the sweep
        sol = jr.simulate(model, integ, q0, v0, 0.04, n_save=201, options=opts, throw=False)
        assert bool(sol.buckled) == bool(res.outputs["buckled"][i])
        # the sweep's compilation rounds the float32 friction pass differently from the single
        # run's (3.9e-10 measured; within 1e-12 before the pass was float32): within its budget,
        # 1e-5 of the amplitude (docs/rod3d.md, "Cost of a step")
        np.testing.assert_allclose(res.outputs["max_theta"][i], float(jnp.max(sol.amplitude)), rtol=1e-5)
        assert res.outputs["t_buckle"][i] == float(sol.t_buckle)
        assert res.outputs["steps"][i] == int(sol.n_steps)
    assert not res.outputs["buckled"][0] and res.outputs["buckled"][2]
    assert res.outputs["dominant_mode"][2] == 6
    with pytest.raises(ValueError, match="SweepSpec.dt"):
        sweep(SweepSpec(model="rod3d", n=12, dt=1.0), {"dF": [1.0]}, progress=False)


def test_pool_member_equals_its_single_run():
    """Continuous batching: each member of a pooled sweep is the `simulate` run of its scene —
    the same steps and the same stop, whatever lane it ran in. Amplitudes agree to 1e-13: the
    random field's synthesis from the scene's noise grid is a sum whose order XLA may change
    under vmap; labels, stop times and step counts are compared exactly."""
    from jaxrod.registry import make_perturbation
    from jaxrod.scene import Scene

    spec = SweepSpec(model="field", n=24, perturbation="random-velocity", t1=0.3)
    res = sweep(spec, {"dF": [2.0, 20.0], "amplitude": [0.005, 0.05], "realization": [0, 1]},
                seed=5, lanes=3, refill_every=7, progress=False)
    assert res.meta["scheduling"] == "pool"
    assert res.outputs["buckled"].any() and not res.outputs["buckled"].all()
    rod = jr.RodChannel.reference(0.3)
    for i in range(len(res)):
        key = jax.random.fold_in(jax.random.key(5), i)
        pert = make_perturbation("random-velocity", res.inputs["amplitude"][i], 6, key)
        scene = Scene(rod, res.inputs["dF"][i], pert, "field", n=24, dt=res.meta["dt"])
        sol = scene.run(t1=0.3, save_state=False)
        o = {k: v[i] for k, v in res.outputs.items()}
        assert o["buckled"] == bool(sol.buckled) and o["stuck"] == bool(sol.stuck[-1])
        assert o["t_buckle"] == float(sol.t_buckle) and o["t_stop"] == float(sol.t_stop)
        assert o["max_theta"] == pytest.approx(float(jnp.max(sol.amplitude)), rel=1e-13)
        assert o["final_theta"] == pytest.approx(float(sol.amplitude[-1]), rel=1e-13)
        assert o["steps"] == int(sol.n_steps)
        assert o["dominant_mode"] == int(jr.modal.dominant_mode(sol.q_final))


# the Galerkin and single-mode cases (15 s and 12 s) are slow: the field case checks the same
# property of the one pool by default
@pytest.mark.parametrize("model,n", [("field", 16), pytest.param("galerkin", 8, marks=pytest.mark.slow),
                                     pytest.param("mode", None, marks=pytest.mark.slow)])
def test_pool_does_not_depend_on_lanes_refills_or_scheduling(model, n):
    spec = SweepSpec(model=model, n=n, perturbation="random-velocity", t1=0.3)
    inputs = {"dF": [1.0, 20.0, 40.0], "amplitude": [0.002, 0.05], "realization": [0, 1]}
    ref = sweep(spec, inputs, seed=2, scheduling="chunk", progress=False)
    for lanes, every, chunk in ((2, 1, None), (4, 16, 5), (64, 3, None)):
        res = sweep(spec, inputs, seed=2, lanes=lanes, refill_every=every, chunk_size=chunk, progress=False)
        for k in ref.outputs:
            np.testing.assert_array_equal(res.outputs[k], ref.outputs[k], err_msg=f"{k}, B={lanes}")
        assert 0 < res.meta["member_steps"] <= res.meta["lane_steps"]
    # one lane runs each run alone (no idle copy beside it: the 3D rod's default); XLA rounds a
    # batch of one in the last bit otherwise, so its numbers agree to rounding, its labels,
    # results and step counts exactly, and a second chunking gives it bit for bit
    one = sweep(spec, inputs, seed=2, lanes=1, refill_every=1, progress=False)
    again = sweep(spec, inputs, seed=2, lanes=1, refill_every=5, chunk_size=5, progress=False)
    assert one.meta["member_steps"] == one.meta["lane_steps"]  # no idle lane
    for k in ref.outputs:
        if np.issubdtype(ref.outputs[k].dtype, np.floating):
            np.testing.assert_allclose(one.outputs[k], ref.outputs[k], rtol=1e-13, atol=0, err_msg=k)
        else:
            np.testing.assert_array_equal(one.outputs[k], ref.outputs[k], err_msg=k)
        np.testing.assert_array_equal(again.outputs[k], one.outputs[k], err_msg=k)


def test_run_pool_runs_every_valid_run_to_its_end():
    """The pool on counters of known lengths: every valid run stops at its own length, runs
    marked invalid are returned untouched, and the lane steps follow the rounds."""
    from jaxrod.batching import run_pool

    lengths = jnp.array([5, 1, 40, 3, 3, 17, 2, 9, 30, 1, 8], jnp.int32)
    valid = jnp.arange(11) != 4
    runs = {"count": jnp.zeros(11, jnp.int32), "length": lengths}
    advance = lambda r: {**r, "count": r["count"] + (r["count"] < r["length"]).astype(jnp.int32)}
    finished = lambda r: r["count"] >= r["length"]
    out, stats = jax.jit(lambda r, v: run_pool(advance, finished, r, v, lanes=3, refill_every=4))(runs, valid)
    np.testing.assert_array_equal(out["count"], jnp.where(valid, lengths, 0))
    assert int(stats.lane_steps) == int(stats.rounds) * 3 * 4
    # 10 runs of 119 steps in total on 3 lanes: at least 119 / 3 steps, rounded up to rounds of 4
    assert int(stats.rounds) * 4 >= 119 / 3 and int(stats.lane_steps) >= int(jnp.sum(jnp.where(valid, lengths, 0)))


def test_pool_arguments_are_checked():
    with pytest.raises(ValueError, match="scheduling"):
        sweep(SPEC, INPUTS, scheduling="fifo", progress=False)
    with pytest.raises(ValueError, match="lanes = 0"):
        sweep(SPEC, INPUTS, lanes=0, progress=False)


def test_to_xarray_labels_the_grid():
    """A grid sweep as an xarray Dataset: the swept names are its dimensions, in grid order, with
    their values as coordinates; each output is a variable of the grid's shape, equal to
    `grid(name)`; a zipped sweep has one `member` dimension."""
    res = sweep(SPEC, INPUTS, seed=3, chunk_size=5, progress=False)
    ds = res.to_xarray()
    assert tuple(ds.sizes) == ("dF", "amplitude", "realization") and tuple(ds.sizes.values()) == res.shape == (2, 2, 3)
    np.testing.assert_array_equal(ds["amplitude"].values, [0.005, 0.05])
    for k in ("buckled", "max_theta", "result", "index"):
        np.testing.assert_array_equal(ds[k].values, res.grid(k))
    # one member picked by label
    i = int(ds["index"].sel(dF=20.0, amplitude=0.05, realization=1))
    assert bool(ds["buckled"].sel(dF=20.0, amplitude=0.05, realization=1)) == bool(res.outputs["buckled"][i])
    z = sweep(SPEC, {"dF": [2.0, 20.0], "amplitude": [0.005, 0.05]}, combine="zip", seed=3, progress=False).to_xarray()
    assert tuple(z.sizes) == ("member",) and z.sizes["member"] == 2


# ---- SweepResult's numbers on results built by hand (no sweep run: every expected value is
# ---- written out below or follows from the members' own labels)

Z95, Z90 = 1.96, 1.645


def _wilson_by_hand(k, n, z):
    """Wilson's score interval as the two roots of (n + z²) p² − (2k + z²) p + k²/n = 0 (the
    score test |k/n − p| = z √(p(1 − p)/n), squared): another derivation than the code's."""
    a, b, c = n + z * z, 2 * k + z * z, k * k / n
    d = math.sqrt(b * b - 4 * a * c)
    return (b - d) / (2 * a), (b + d) / (2 * a)


def _hand_grid():
    """A 2 × 2 × 3 grid (dF, amplitude, realization), members in C order. Per (dF, amplitude)
    cell, results / buckled labels:
      (2, 0.005):  ok ok ok     / - - -  → 0 of 3 buckled
      (2, 0.05):   ok ok ok     / B - B  → 2 of 3
      (20, 0.005): nan inv ok   / B - B  → 1 of 1 (the failed members left out, one labelled B)
      (20, 0.05):  nan nan inv  / B B -  → none counted."""
    dF = np.repeat([2.0, 20.0], 6)
    amp = np.tile(np.repeat([0.005, 0.05], 3), 2)
    real = np.tile([0, 1, 2], 4)
    result = np.array([0, 0, 0, 0, 0, 0, 1, 4, 0, 1, 1, 4])
    buckled = np.array([0, 0, 0, 1, 0, 1, 1, 0, 1, 1, 1, 0], bool)
    outputs = {k: np.arange(12, dtype=float) / 10 for k in ("t_buckle", "max_theta", "final_theta", "t_stop")}
    outputs.update(buckled=buckled, result=result, dominant_mode=np.arange(12) % 4 + 1,
                   stuck=~buckled, steps=np.arange(12) * 100)
    meta = {"spec": {"model": "field", "n": 16}, "names": ["dF", "amplitude", "realization"],
            "shape": [2, 2, 3], "full_shape": [2, 2, 3], "seed": 3, "dt": 1e-5, "combine": "grid",
            "devices": ["cpu:0"], "_inputs": {"dF": dF.tolist()}}
    return SweepResult({"dF": dF, "amplitude": amp, "realization": real, "index": np.arange(12)},
                       outputs, (2, 2, 3), ("dF", "amplitude", "realization"), meta)


def test_summary_counts_labels_and_failures_by_hand():
    res = _hand_grid()
    # 7 successful members, 3 of them buckled; failures: 3 non-finite, 2 invalid inputs (the
    # buckled labels of three of them are not counted)
    assert res.summary() == (
        "12 members: 3 buckled, 4 stable; 7 successful, 3 the state became non-finite (NaN or inf), "
        "2 an input value is outside its valid range")


def test_probability_against_hand_counts_and_hand_wilson_bands():
    res = _hand_grid()
    prob = res.probability()  # over "realization" by default
    assert set(prob) == {"dF", "amplitude", "p", "lo", "hi", "n", "buckled"}
    np.testing.assert_array_equal(prob["dF"], [[2.0, 2.0], [20.0, 20.0]])
    np.testing.assert_array_equal(prob["amplitude"], [[0.005, 0.05], [0.005, 0.05]])
    np.testing.assert_array_equal(prob["n"], [[3, 3], [1, 0]])
    np.testing.assert_array_equal(prob["buckled"], [[0, 2], [1, 0]])
    assert prob["p"].dtype == float
    np.testing.assert_array_equal(prob["p"], [[0.0, 2 / 3], [1.0, np.nan]])
    for z, kw in ((Z95, {}), (Z90, {"z": Z90})):
        prob = res.probability("realization", **kw)
        for (i, j), k, n in (((0, 0), 0, 3), ((0, 1), 2, 3), ((1, 0), 1, 1)):
            np.testing.assert_allclose([prob["lo"][i, j], prob["hi"][i, j]], _wilson_by_hand(k, n, z),
                                       rtol=1e-12, atol=1e-15, err_msg=f"z = {z}, {k} of {n}")
        assert np.isnan(prob["lo"][1, 1]) and np.isnan(prob["hi"][1, 1])  # nothing counted
    # over another axis: the amplitudes of each (dF, realization)
    prob = res.probability("amplitude")
    np.testing.assert_array_equal(prob["realization"], [[0, 1, 2], [0, 1, 2]])
    np.testing.assert_array_equal(prob["n"], [[2, 2, 2], [0, 0, 1]])
    np.testing.assert_array_equal(prob["buckled"], [[1, 0, 1], [0, 0, 1]])


def test_probability_of_a_one_member_ensemble_and_axes_that_are_not_one():
    # a single realization per cell (an ensemble of one): p is that member's label
    sub = _hand_grid()
    keep = sub.inputs["realization"] == 2
    one = SweepResult({k: v[keep] for k, v in sub.inputs.items()}, {k: v[keep] for k, v in sub.outputs.items()},
                      (2, 2, 1), sub.names, sub.meta)
    prob = one.probability("realization")
    np.testing.assert_array_equal(prob["dF"], [[2.0, 2.0], [20.0, 20.0]])
    np.testing.assert_array_equal(prob["amplitude"], [[0.005, 0.05], [0.005, 0.05]])
    np.testing.assert_array_equal(prob["p"], [[0.0, 1.0], [1.0, np.nan]])
    np.testing.assert_allclose(prob["hi"][0, 0], Z95**2 / (1 + Z95**2), rtol=1e-12)
    np.testing.assert_allclose(prob["lo"][0, 1], 1 / (1 + Z95**2), rtol=1e-12)
    with pytest.raises(ValueError, match=r"^over = 'seed' is not a grid axis of this sweep \(axes: "):
        sub.probability("seed")
    zipped = SweepResult(sub.inputs, sub.outputs, (12,), sub.names, sub.meta)  # members, not a grid
    with pytest.raises(ValueError, match="not a grid axis"):
        zipped.probability("realization")


def test_wilson_interval_at_the_edges_by_hand():
    # 0 of n: (0, z²/(n + z²)); n of n: (n/(n + z²), 1); n = 1 included
    for z in (Z95, Z90, 2.576):
        for n in (1, 2, 7):
            lo, hi = jr.wilson_interval(np.array([0, n]), np.array([n, n]), z=z)
            np.testing.assert_allclose(lo, [0.0, n / (n + z * z)], rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(hi, [z * z / (n + z * z), 1.0], rtol=1e-12, atol=1e-15)
    lo, hi = jr.wilson_interval(0, 0)
    assert np.isnan(lo) and np.isnan(hi)  # no member counted: no interval
    # counts given in single precision (a JAX array without x64) still give double-precision bounds
    lo, hi = jr.wilson_interval(np.float32(2), np.float32(3))
    np.testing.assert_allclose([lo, hi], _wilson_by_hand(2, 3, Z95), rtol=1e-12)


def test_to_xarray_coordinates_values_and_attrs_of_a_hand_grid(monkeypatch):
    res = _hand_grid()
    ds = res.to_xarray()
    assert tuple(ds.sizes.items()) == (("dF", 2), ("amplitude", 2), ("realization", 3))
    np.testing.assert_array_equal(ds["dF"].values, [2.0, 20.0])
    np.testing.assert_array_equal(ds["amplitude"].values, [0.005, 0.05])
    np.testing.assert_array_equal(ds["realization"].values, [0, 1, 2])
    assert set(ds.data_vars) == set(res.outputs) | {"index"}
    for i in range(len(res)):  # each member found by its own labels
        at = {k: res.inputs[k][i] for k in res.names}
        assert int(ds["index"].sel(at)) == i
        for k, v in res.outputs.items():
            assert ds[k].sel(at).item() == v[i], (k, i)
    # metadata: plain values as they are, nested ones as JSON text, private ones ("_…") left out
    assert ds.attrs["seed"] == 3 and ds.attrs["dt"] == 1e-5 and ds.attrs["combine"] == "grid"
    assert json.loads(ds.attrs["spec"]) == {"model": "field", "n": 16}
    assert json.loads(ds.attrs["devices"]) == ["cpu:0"]
    assert not any(k.startswith("_") for k in ds.attrs)
    assert set(ds.attrs) == {"spec", "names", "shape", "full_shape", "seed", "dt", "combine", "devices"}
    # a NumPy value in the metadata is written as text
    odd = SweepResult(res.inputs, res.outputs, res.shape, res.names, {"shape": [np.int64(2), np.float32(0.5)]})
    assert json.loads(odd.to_xarray().attrs["shape"]) == ["2", "0.5"]
    # a grid with an axis of one value
    sub = SweepResult({k: v[:3] for k, v in res.inputs.items()}, {k: v[:3] for k, v in res.outputs.items()},
                      (1, 1, 3), res.names, {})
    ds1 = sub.to_xarray()
    np.testing.assert_array_equal(ds1["dF"].values, [2.0])
    np.testing.assert_array_equal(ds1["amplitude"].values, [0.005])
    np.testing.assert_array_equal(ds1["buckled"].values, [[[False, False, False]]])
    # a zipped result: one member dimension, the inputs as its coordinates
    zipped = SweepResult(res.inputs, res.outputs, (12,), res.names, {"combine": "zip"})
    dz = zipped.to_xarray()
    assert tuple(dz.sizes.items()) == (("member", 12),) and dz.attrs == {"combine": "zip"}
    assert set(dz.coords) == {"dF", "amplitude", "realization", "index"}
    np.testing.assert_array_equal(dz["dF"].values, res.inputs["dF"])
    np.testing.assert_array_equal(dz["realization"].values, np.tile([0, 1, 2], 4))
    for k, v in res.outputs.items():
        np.testing.assert_array_equal(dz[k].values, v, err_msg=k)
    # without xarray: the error says what to install
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(ImportError, match=r"^SweepResult\.to_xarray needs xarray: pip install 'jaxrod\[xarray\]'$"):
        res.to_xarray()


def test_concatenate_member_ranges_of_a_hand_grid():
    whole = _hand_grid()

    def part(lo, hi):
        meta = {**whole.meta, "shape": [hi - lo], "members": [lo, hi]}
        return SweepResult({k: v[lo:hi] for k, v in whole.inputs.items()},
                           {k: v[lo:hi] for k, v in whole.outputs.items()}, (hi - lo,), whole.names, meta)

    for parts in ([part(8, 12), part(0, 5), part(5, 8)], [part(0, 12)]):  # several hosts, or one
        joined = SweepResult.concatenate(parts)
        assert joined.shape == (2, 2, 3) and joined.names == ("dF", "amplitude", "realization")
        assert joined.meta["seed"] == 3 and joined.meta["spec"] == {"model": "field", "n": 16}
        assert joined.meta["shape"] == [2, 2, 3] and joined.meta["members"] == [0, 12]  # its own, not part 0's
        assert set(joined.inputs) == set(whole.inputs) and set(joined.outputs) == set(whole.outputs)
        np.testing.assert_array_equal(joined.inputs["index"], np.arange(12))
        np.testing.assert_array_equal(joined.inputs["dF"], np.repeat([2.0, 20.0], 6))
        np.testing.assert_array_equal(joined.inputs["realization"], np.tile([0, 1, 2], 4))
        for k, v in whole.outputs.items():
            np.testing.assert_array_equal(joined.outputs[k], v, err_msg=k)
        np.testing.assert_array_equal(joined.probability()["buckled"], [[0, 2], [1, 0]])
    # results without a full grid shape in their metadata join as a list of members
    a, b = (SweepResult({"x": np.array(v, float), "index": np.array(i)}, {"result": np.zeros(len(i), int)},
                        (len(i),), ("x",), {}) for v, i in (([3.0], [1]), ([1.0, 2.0], [0, 2])))
    joined = SweepResult.concatenate([a, b])
    assert joined.shape == (3,) and joined.names == ("x",)
    np.testing.assert_array_equal(joined.inputs["x"], [1.0, 3.0, 2.0])


def test_load_reads_a_folder_in_its_documented_layout(tmp_path, monkeypatch):
    """`sweep.json` plus one `chunk_XXXXX.npz` per finished chunk (store.py): 5 members in
    chunks of 2, the middle chunk not finished — its members read as not run (result −1)."""
    with pytest.raises(FileNotFoundError, match="^no sweep metadata at "):
        SweepResult.load(str(tmp_path / "nothing"))
    meta = {"names": ["x"], "shape": [5], "chunk_size": 2, "seed": 7,
            "_inputs": {"x": [0.1, 0.2, 0.3, 0.4, 0.5], "index": [0, 1, 2, 3, 4]}}
    (tmp_path / "sweep.json").write_text(json.dumps(meta))
    np.savez(tmp_path / "chunk_00000.npz", result=np.array([0, 0]), buckled=np.array([True, False]))
    np.savez(tmp_path / "chunk_00002.npz", result=np.array([4]), buckled=np.array([False]))
    looked = []
    chunk_file = result_module._chunk_file
    monkeypatch.setattr(result_module, "_chunk_file", lambda p, c: looked.append(c) or chunk_file(p, c))
    res = SweepResult.load(str(tmp_path))
    assert looked == [0, 1, 2]  # the chunks of 5 members, no more
    assert res.shape == (5,) and res.names == ("x",) and res.meta["seed"] == 7 and res.meta["chunk_size"] == 2
    np.testing.assert_array_equal(res.inputs["x"], [0.1, 0.2, 0.3, 0.4, 0.5])
    np.testing.assert_array_equal(res.outputs["result"], [0, 0, -1, -1, 4])
    np.testing.assert_array_equal(res.outputs["buckled"], [True, False, False, False, False])
    assert np.all(np.isinf(res.outputs["t_buckle"]))


def test_a_sweep_of_whole_numbers_is_the_sweep_of_the_same_floats():
    """Inputs given as Python or NumPy integers (ΔF = 1, 2 N) are physical numbers: the result
    records them as floats and every member is the run of the float input."""
    spec = SweepSpec(model="mode", t1=0.01, dt=1e-4)
    ints = sweep(spec, {"dF": [1, 2], "amplitude": 0.01}, progress=False)
    floats = sweep(spec, {"dF": [1.0, 2.0], "amplitude": 0.01}, progress=False)
    assert ints.inputs["dF"].dtype == floats.inputs["dF"].dtype == np.float64
    np.testing.assert_array_equal(ints.inputs["dF"], [1.0, 2.0])
    for k in floats.outputs:
        np.testing.assert_array_equal(ints.outputs[k], floats.outputs[k])


def test_a_sweeps_progress_bar_names_the_sweep_and_counts_members(capfd):
    """Asked for progress, a sweep shows one bar on stderr: "sweep", its members done out of all
    (counted chunk by chunk: here a chunk of 2 and one of 1), and the members per second of this
    call."""
    sweep(SweepSpec(model="mode", t1=0.01, dt=1e-4), {"dF": [1.0, 2.0, 3.0]}, chunk_size=2, progress=True)
    err = capfd.readouterr().err
    last = err.replace("\r", "\n").strip().splitlines()[-1]
    assert last.startswith("sweep: 100%") and "3/3" in last and last.endswith(" members/s]")


def test_a_resumed_sweeps_bar_says_resumed_until_it_has_run_a_chunk(tmp_path, capfd, monkeypatch):
    """A sweep stopped after its first chunk and run again: while it counts the chunk found on
    disk its bar shows "0.0 members/s (resumed)" (none run yet by this call); once it has run
    the last chunk, this call's rate alone. The bar counts members, not iterations."""
    monkeypatch.setenv("COLUMNS", "200")  # a bar as wide as a terminal's (not cut at 80 columns)
    spec, inputs, path = SweepSpec(model="mode", t1=0.01, dt=1e-4), {"dF": [1.0, 2.0, 3.0]}, str(tmp_path / "s")

    class Stop(Exception):
        pass

    def stop(c):
        raise Stop

    with pytest.raises(Stop):
        sweep(spec, inputs, chunk_size=2, path=path, progress=False, on_chunk=stop)
    capfd.readouterr()
    sweep(spec, inputs, chunk_size=2, path=path, progress=True)
    lines = [ln.strip() for ln in capfd.readouterr().err.replace("\r", "\n").splitlines() if ln.strip()]
    assert any(ln.endswith(", 0.0 members/s (resumed)]") for ln in lines), lines
    assert "3/3" in lines[-1] and lines[-1].endswith(" members/s]") and "resumed" not in lines[-1]
    assert lines[0].endswith("0/3 [00:00<?, ?member/s]")  # the bar counts members


def test_a_finished_sweep_is_recognised_whatever_order_its_rod_overrides_were_written_in(tmp_path):
    """The rod overrides are a mapping: `{"L": 3, "R": 0.006}` and `{"R": 0.006, "L": 3}` are one
    sweep, so a sweep written with one is found finished by the other (no member runs again)."""
    path = str(tmp_path / "run")
    kw = dict(seed=0, chunk_size=2, path=path, progress=False)
    spec = lambda rod: SweepSpec(model="mode", t1=0.01, dt=1e-4, rod=rod)  # noqa: E731
    sweep(spec({"L": 3.0, "R": 0.006}), {"dF": [1.0, 2.0]}, **kw)
    computed = []
    again = sweep(spec({"R": 0.006, "L": 3.0}), {"dF": [1.0, 2.0]}, on_chunk=computed.append, **kw)
    assert computed == [] and again.shape == (2,)


def test_a_sweep_over_loads_takes_its_step_from_the_largest_load():
    """A sweep's members share one step: that of the largest swept ΔF (the stiffest member: a
    Galerkin rod's step at 40 N is a third of its step at 1 N), whatever the spec's own ΔF; the
    member at 40 N runs stably at it."""
    spec = SweepSpec(model="galerkin", t1=0.01)
    res = sweep(spec, {"dF": [1.0, 40.0], "amplitude": 0.01}, progress=False)
    rod = jr.RodChannel.reference(spec.mu)
    steps = {dF: jr.Scene(rod, dF, kind="galerkin", n=res.meta["n"]).step() for dF in (1.0, spec.dF, 40.0)}
    assert steps[40.0] < 0.5 * min(steps[1.0], steps[spec.dF])
    assert res.meta["dt"] == pytest.approx(steps[40.0], rel=1e-12)
    np.testing.assert_array_equal(res.outputs["result"], [0, 0])


def test_zipped_inputs_of_length_one_make_one_member():
    """`combine="zip"` with every input a scalar or of length 1 is one member, the same as the
    grid of those inputs (and a length-1 input zips with a longer one by broadcasting)."""
    spec = SweepSpec(model="mode", t1=0.01, dt=1e-4)
    zipped = sweep(spec, {"dF": 2.0, "amplitude": [0.01]}, combine="zip", progress=False)
    grid = sweep(spec, {"dF": 2.0, "amplitude": [0.01]}, progress=False)
    assert len(zipped) == len(grid) == 1
    for k in grid.outputs:
        np.testing.assert_array_equal(zipped.outputs[k], grid.outputs[k])
    wide = sweep(spec, {"dF": [2.0], "amplitude": [0.01, 0.02]}, combine="zip", progress=False)
    np.testing.assert_array_equal(wide.inputs["dF"], [2.0, 2.0])


def test_a_pools_given_chunk_size_pads_smaller_sweeps_to_one_program_and_resolved_names_their_resolution(caplog):
    """Under the pool a given `chunk_size` is kept above the member count (the padding never
    runs): sweeps of 3 and 2 members at chunk size 4 compile one program and give the numbers of
    the same members swept without padding; `resolved` fills in the n and dt a sweep over the
    inputs runs at (the Galerkin model's at the largest load), and a sweep of part of the inputs
    under it runs there too."""
    from jaxrod.sweeps import resolved

    spec = SweepSpec(model="galerkin", t1=0.01)
    grid = {"dF": [1.0, 40.0], "amplitude": 0.01}
    whole = sweep(spec, grid, progress=False)
    fixed = resolved(spec, grid)
    assert (fixed.n, fixed.dt) == (whole.meta["n"], whole.meta["dt"]) and spec.dt is None
    part = sweep(fixed, {"dF": [1.0], "amplitude": 0.01}, progress=False)
    assert (part.meta["n"], part.meta["dt"]) == (whole.meta["n"], whole.meta["dt"])
    np.testing.assert_allclose(part.outputs["max_theta"], whole.outputs["max_theta"][:1], rtol=1e-12)  # another width: rounding
    mode = SweepSpec(model="mode", t1=0.01, dt=1e-4)
    plain = sweep(mode, {"dF": [1.0, 2.0, 3.0], "amplitude": 0.01}, progress=False)
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level(logging.WARNING, logger="jax"):
            three = sweep(mode, {"dF": [1.0, 2.0, 3.0], "amplitude": 0.01}, chunk_size=4, progress=False)
            two = sweep(mode, {"dF": [1.0, 2.0], "amplitude": 0.01}, chunk_size=4, progress=False)
    finally:
        jax.config.update("jax_log_compiles", False)
    compiles = [r.getMessage() for r in caplog.records if r.getMessage().startswith("Compiling jit(run_chunk)")]
    assert len(compiles) == 1, compiles
    assert three.meta["chunk_size"] == 4 and two.meta["chunk_size"] == 4 and plain.meta["chunk_size"] == 3
    # the padding stays within the memory budget (here one member): never below the members
    tight = sweep(mode, {"dF": [1.0, 2.0], "amplitude": 0.01}, chunk_size=4, memory_mb=1e-9, progress=False)
    assert tight.meta["chunk_size"] == 2
    for k in plain.outputs:  # the same labels and steps; numbers to rounding (XLA compiles another width differently)
        same = np.testing.assert_allclose if plain.outputs[k].dtype.kind == "f" else np.testing.assert_array_equal
        kw = dict(rtol=1e-12) if plain.outputs[k].dtype.kind == "f" else {}
        same(three.outputs[k], plain.outputs[k], **kw)
        same(two.outputs[k], plain.outputs[k][:2], **kw)
