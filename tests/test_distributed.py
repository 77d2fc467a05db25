"""Sweeps across processes: two local CPU processes under `jax.distributed` (coordinator on
127.0.0.1) against one process, bit for bit; a process lost mid-run and the sweep completed by a
rerun with another process count; the command line's distributed options."""

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from jaxrod.sweeps import OUTPUTS, SweepResult, SweepSpec, sweep

SPEC = SweepSpec(model="mode", perturbation="random-velocity", t1=0.3)  # the cheapest to compile
INPUTS = {"dF": [5.0, 40.0], "amplitude": [0.05, 0.5], "realization": list(range(16))}  # 64 members
CHUNK = 16  # 4 chunks
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# One job of two processes does three sweeps of the same members in three folders (one
# compilation per process): `fresh` from scratch; `resume`, a folder a one-process run left after
# its first chunk; `lost`, where process 1 dies after its first chunk (os._exit, no clean-up).
WORKER = """
import json, os, sys, time
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np
from jaxrod.distributed import initialize
from jaxrod.sweeps import SweepSpec, sweep
pid, port, base = int(sys.argv[1]), sys.argv[2], sys.argv[3]
initialize(f"127.0.0.1:{port}", 2, pid)
spec = SweepSpec(**json.loads(sys.argv[4]))
inputs = json.loads(sys.argv[5])

def log(name):
    def on_chunk(c):
        with open(os.path.join(base, f"{name}.ran{pid}"), "a") as fh:
            fh.write(f"{c}\\n")
        if name == "lost" and pid == 1:
            os._exit(3)
    return on_chunk

for name in ("fresh", "resume", "lost"):
    while name == "resume" and not os.path.exists(os.path.join(base, "resume.ready")):
        time.sleep(0.05)  # the test's one-process run is preparing it
    r = sweep(spec, inputs, seed=3, chunk_size=16, path=os.path.join(base, name), progress=False,
              on_chunk=log(name))
    np.savez(os.path.join(base, f"{name}.out{pid}.npz"), **r.outputs, **{"in_" + k: v for k, v in r.inputs.items()},
             processes=r.meta["processes"])
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def worker_env():
    # the test process's XLA options (its compiler settings: the bits compared), one CPU device each
    flags = " ".join(f for f in os.environ.get("XLA_FLAGS", "").split() if "device_count" not in f)
    env = dict(os.environ, JAX_PLATFORMS="cpu", XLA_FLAGS=f"{flags} --xla_force_host_platform_device_count=1".strip(),
               JAX_COMPILATION_CACHE_DIR=os.path.join(ROOT, ".pytest_cache", "jax"),
               JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0.5")
    env.pop("JAX_COORDINATOR_ADDRESS", None)
    return env


def ran(base, name, pid) -> list[int]:
    f = base / f"{name}.ran{pid}"
    return [int(x) for x in f.read_text().split()] if f.exists() else []


def chunk_files(path):
    return sorted(f for f in os.listdir(path) if f.startswith("chunk_"))


def identical(a: SweepResult, outputs: dict, inputs: dict | None = None):
    """Bit for bit (NaN where NaN)."""
    for k in OUTPUTS:
        assert outputs[k].dtype == a.outputs[k].dtype, k
        assert np.array_equal(outputs[k], a.outputs[k], equal_nan=outputs[k].dtype.kind == "f"), k
    for k, v in (inputs or {}).items():
        assert np.array_equal(v, a.inputs[k]), k


@pytest.fixture(scope="module")
def job(tmp_path_factory):
    """The two-process job's folders, and the sweep in this one process (no runtime), computed
    while the job runs."""
    base = tmp_path_factory.mktemp("distributed")
    port = free_port()
    t0 = time.perf_counter()
    logs, procs = [base / f"log{pid}.txt" for pid in (0, 1)], []
    for pid in (0, 1):
        with open(logs[pid], "w") as out:
            procs.append(subprocess.Popen([sys.executable, "-c", textwrap.dedent(WORKER), str(pid), str(port),
                                           str(base), json.dumps(SPEC.to_json()), json.dumps(INPUTS)],
                                          stdout=out, stderr=subprocess.STDOUT, env=worker_env()))
    try:
        class Interrupted(Exception):
            pass

        def stop(c):
            raise Interrupted  # a one-process run stopped after its first chunk

        with pytest.raises(Interrupted):
            sweep(SPEC, INPUTS, seed=3, chunk_size=CHUNK, path=str(base / "resume"), progress=False, on_chunk=stop)
        (base / "resume.ready").touch()
        reference = sweep(SPEC, INPUTS, seed=3, chunk_size=CHUNK, progress=False)
        try:
            procs[1].wait(timeout=240)
        except subprocess.TimeoutExpired:
            pass
        # process 1 is lost; process 0 fails at the end of the sweep, where it waits for the
        # others' chunks (gloo: connection reset), or is stopped, as a scheduler ends the job
        procs[0].send_signal(signal.SIGKILL)
        procs[0].wait(timeout=60)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()
    seconds = time.perf_counter() - t0
    assert procs[1].returncode == 3, "\n".join(f.read_text()[-3000:] for f in logs)
    return base, reference, seconds


def test_two_processes_merge_into_the_one_process_result_bit_for_bit(job):
    base, reference, seconds = job
    assert ran(base, "fresh", 0) == [0, 2] and ran(base, "fresh", 1) == [1, 3]  # each ran its share
    for pid in (0, 1):  # each process returns the whole sweep
        z = np.load(base / f"fresh.out{pid}.npz")
        assert int(z["processes"]) == 2
        identical(reference, {k: z[k] for k in OUTPUTS}, {k: z["in_" + k] for k in reference.inputs})
    assert json.loads((base / "fresh" / "sweep.json").read_text())["chunk_size"] == CHUNK
    loaded = SweepResult.load(str(base / "fresh"))
    identical(reference, loaded.outputs, loaded.inputs)
    assert reference.outputs["buckled"].any() and not reference.outputs["buckled"].all()
    print(f"two-process job: {seconds:.1f} s")


def test_a_one_process_run_is_completed_by_two(job):
    base, reference, _ = job
    # chunk 0 came from the interrupted run; the other three were dealt to the two processes
    assert ran(base, "resume", 0) == [1, 3] and ran(base, "resume", 1) == [2]
    for pid in (0, 1):
        z = np.load(base / f"resume.out{pid}.npz")
        identical(reference, {k: z[k] for k in OUTPUTS})


def test_a_lost_process_is_made_up_by_a_rerun_on_one_process(job):
    base, reference, _ = job
    path = base / "lost"
    assert ran(base, "lost", 1) == [1]  # process 1 died after writing its first chunk
    have = chunk_files(path)
    assert "chunk_00001.npz" in have and "chunk_00003.npz" not in have
    missing = [c for c in range(4) if f"chunk_{c:05d}.npz" not in have]
    mtimes = {f: os.path.getmtime(path / f) for f in have}
    computed = []
    res = sweep(SPEC, INPUTS, seed=3, chunk_size=CHUNK, path=str(path), progress=False, on_chunk=computed.append)
    assert computed == missing  # only the missing members ran
    assert {f: os.path.getmtime(path / f) for f in have} == mtimes
    identical(reference, res.outputs, res.inputs)


@pytest.mark.parametrize("argv, option", [
    (["--coordinator", "localhost"], "--coordinator"),
    (["--coordinator", "host:99999"], "--coordinator"),
    (["--num-processes", "0"], "--num-processes"),
    (["--process-id", "-1"], "--process-id"),
    (["--coordinator", "127.0.0.1:1234", "--num-processes", "2", "--process-id", "2"], "--process-id"),
    (["--num-processes", "2", "--process-id", "0"], "--coordinator"),
    (["--coordinator", "127.0.0.1:1234", "--process-id", "1"], "--num-processes"),
])
def test_bad_distributed_options_end_in_one_line(argv, option, tmp_path, capsys):
    from jaxrod.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["map", "--out", str(tmp_path / "map"), *argv])
    assert exit_.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and f"argument {option}:" in lines[0], lines
    assert not (tmp_path / "map").exists()  # before any work


@pytest.mark.slow
def test_distributed_outside_a_cluster_ends_in_one_line(tmp_path):
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("SLURM_", "OMPI_", "PMI_", "KUBERNETES_")) and k != "JAX_COORDINATOR_ADDRESS"}
    res = subprocess.run([sys.executable, "-m", "jaxrod", "map", "--out", str(tmp_path), "--distributed"],
                         capture_output=True, text=True, env={**env, "JAX_PLATFORMS": "cpu"}, timeout=120)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("jaxrod: error: argument --coordinator:"), res.stderr


@pytest.mark.slow
def test_map_command_on_two_processes_writes_the_one_process_map(tmp_path):
    grid = ["--model", "mode", "--mu", "0.3", "--dF", "1:40:4", "--v0", "0.005:0.5:4", "--t1", "0.5",
            "--no-curve", "--chunk-size", "4", "--quiet"]
    port, env = free_port(), worker_env()
    procs = [subprocess.Popen([sys.executable, "-m", "jaxrod", "map", *grid, "--out", str(tmp_path / "two"),
                               "--coordinator", f"127.0.0.1:{port}", "--num-processes", "2", "--process-id", str(pid)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
             for pid in (0, 1)]
    try:
        outs = [p.communicate(timeout=300) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    assert [p.returncode for p in procs] == [0, 0], outs
    # process 0 reports (gloo itself prints a line on stdout in every process)
    lines = [[x for x in out.splitlines() if not x.startswith("[Gloo]")] for out, _ in outs]
    assert "x 2 processes" in lines[0][0] and lines[1] == []
    # one process with one device, as each of the two had (another device count changes last bits)
    one = subprocess.run([sys.executable, "-m", "jaxrod", "map", *grid, "--out", str(tmp_path / "one")],
                         capture_output=True, text=True, env=env, timeout=300, check=True).stdout
    assert (tmp_path / "two" / "map.csv").read_bytes() == (tmp_path / "one" / "map.csv").read_bytes()
    assert lines[0][2:] == one.splitlines()[2:]  # the same summary (after the folder line)
    assert len([f for f in os.listdir(tmp_path / "two" / "sweep_mu0.3") if f.startswith("chunk_")]) == 4
