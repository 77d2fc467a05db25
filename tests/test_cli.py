import csv
import json
import math
import os
import subprocess
import sys

import pytest

import jaxrod as jr
from jaxrod.cli import main
from jaxrod.registry import make_perturbation
from jaxrod.scene import Scene

EXPECTED_KEYS = {"F0cr_continuous", "omega0", "critical_mode", "F0_mode", "k", "f", "Adot_cr", "v_cr", "A_cr"}


def run_json(capsys, *argv):
    assert main(list(argv)) == 0
    return json.loads(capsys.readouterr().out)


def test_theory_json_reference_rod(capsys):
    out = run_json(capsys, "theory", "--mu", "0.3", "--dF", "5", "--json")
    assert EXPECTED_KEYS <= set(out)
    # Independent hand computation (PHYSICS.md formulas).
    EI = 77e9 * math.pi * 1.5e-3**4 / 64
    rho = 6450 * math.pi * 1.5e-3**2 / 4
    R, g, L = 5.125e-3, 9.81, 3.0
    om = 6 * math.pi / L
    F0 = EI * om**2 + rho * g / (R * om**2)
    k = om**2 / rho * (F0 - (F0 + 5.0))
    f = 4 * 0.3 * rho * g / (math.pi * rho * R)
    assert out["critical_mode"] == 6
    assert out["F0_mode"] == pytest.approx(F0, rel=1e-12)
    assert out["F0cr_continuous"] == pytest.approx(2 * math.sqrt(rho * g * EI / R), rel=1e-12)
    assert out["k"] == pytest.approx(k, rel=1e-10)
    assert out["f"] == pytest.approx(f, rel=1e-12)
    assert out["Adot_cr"] == pytest.approx(f / math.sqrt(-k), rel=1e-10)
    assert out["v_cr"] == pytest.approx(R * f / math.sqrt(-k), rel=1e-10)
    assert out["A_cr"] == pytest.approx(f / -k, rel=1e-10)


def test_theory_json_mode_and_rod_options(capsys):
    out = run_json(capsys, "theory", "--mode", "8", "--dF", "1", "--R", "0.01", "--json")
    assert out["mode"] == 8
    rho = 6450 * math.pi * 1.5e-3**2 / 4
    EI = 77e9 * math.pi * 1.5e-3**4 / 64
    om = 8 * math.pi / 3.0
    assert out["F0_mode"] == pytest.approx(EI * om**2 + rho * 9.81 / (0.01 * om**2), rel=1e-12)
    # below the frictionless load: no finite intercept, reported as null
    out = run_json(capsys, "theory", "--dF", "-0.5", "--json")
    assert out["k"] > 0 and out["Adot_cr"] is None and out["v_cr"] is None


@pytest.mark.parametrize(
    "argv, option",
    [
        (["theory", "--mu", "-0.1"], "--mu"),
        (["theory", "--mu", "abc"], "--mu"),
        (["theory", "--dF", "nan"], "--dF"),
        (["theory", "--R", "-1"], "--R"),
        (["theory", "--nu", "0.6"], "--nu"),
        (["theory", "--mode", "0"], "--mode"),
        (["theory", "--mode", "x"], "--mode"),
    ],
)
def test_theory_bad_values_exit_nonzero_with_one_line(capsys, argv, option):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option in err


def test_console_command_is_installed():
    exe = os.path.join(os.path.dirname(sys.executable), "jaxrod")
    cmd = [exe] if os.path.exists(exe) else [sys.executable, "-m", "jaxrod"]
    res = subprocess.run(cmd + ["theory", "--json"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["critical_mode"] == 6


@pytest.mark.slow  # 14 s; the default suite checks the same agreement through reproduce e2 (tiny)
def test_phase_figure(tmp_path):
    from jaxrod.figures import phase_portraits

    agreement = phase_portraits(str(tmp_path), n_grid=10)
    assert (tmp_path / "phase.png").stat().st_size > 10_000
    lines = (tmp_path / "phase.csv").read_text().splitlines()
    assert len(lines) == 1 + 6 * 100
    assert len(agreement) == 6
    assert min(agreement.values()) >= 0.95


SIM_KEYS = {"buckled", "t_buckle", "dominant_mode", "max_theta", "stuck", "energy_balance_error"}


@pytest.mark.parametrize("model", ["mode", "galerkin", "field"])
def test_simulate_json(capsys, model):
    base = ["simulate", "--model", model, "--dF", "5", "--mu", "0.3", "--n-save", "51", "--json"]
    if model == "field":
        base += ["--n", "48"]
    if model == "galerkin":
        base += ["--n", "16"]
    small = run_json(capsys, *base, "--amplitude", "0.01")
    assert SIM_KEYS <= set(small)
    assert small["buckled"] is False and small["stuck"] is True and small["t_buckle"] is None
    assert small["dominant_mode"] == 6 and small["energy_balance_error"] < 1e-2
    big = run_json(capsys, *base, "--amplitude", "0.06")
    assert big["buckled"] is True and big["max_theta"] >= 0.5 and big["t_buckle"] > 0


def test_simulate_random_perturbations_and_plot(capsys, tmp_path):
    png = tmp_path / "sim.png"
    out = run_json(capsys, "simulate", "--model", "field", "--n", "32", "--perturbation", "random-velocity",
                   "--amplitude", "0.015", "--seed", "3", "--dF", "10", "--n-save", "101",
                   "--json", "--plot", str(png))
    assert SIM_KEYS <= set(out) and png.stat().st_size > 10_000
    out2 = run_json(capsys, "simulate", "--model", "field", "--n", "32", "--perturbation", "random-velocity",
                    "--amplitude", "0.015", "--seed", "3", "--dF", "10", "--n-save", "101", "--json")
    assert out2["max_theta"] == out["max_theta"]  # same seed, same run
    out3 = run_json(capsys, "simulate", "--model", "galerkin", "--n", "8", "--perturbation", "random-position",
                    "--amplitude", "5", "--dF", "2", "--n-save", "51", "--json")
    assert SIM_KEYS <= set(out3)


@pytest.mark.parametrize(
    "argv, option",
    [
        (["simulate", "--mu", "-1"], "--mu"),
        (["simulate", "--model", "rod"], "--model"),
        (["simulate", "--amplitude", "-0.1"], "--amplitude"),
        (["simulate", "--t1", "0"], "--t1"),
        (["simulate", "--n", "2"], "--n"),
        (["simulate", "--perturbation", "noise"], "--perturbation"),
        (["simulate", "--dt", "abc"], "--dt"),
    ],
)
def test_simulate_bad_values(capsys, argv, option):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option in err


def test_map_main_job(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=1")  # leave env as found
    out = tmp_path / "map"
    assert main(["map", "--dF", "1:40:4", "--v0", "0.002:0.15:6", "--n", "32", "--t1", "0.5",
                 "--out", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "boundary v0 ~ dF^p" in text and "largest stable dF/F0cr seen" in text
    for f in ("map.png", "map.csv", "map.json", "sweep_mu0.3/sweep.json", "sweep_mu0/sweep.json"):
        assert (out / f).exists(), f
    s = json.loads((out / "map.json").read_text())
    fric, free = s["maps"]["0.3"], s["maps"]["0"]
    assert free["buckles_for_every_dF_gt_0"] is True and free["stable"] == 0
    assert fric["stable"] > 0 and fric["buckled"] > 0
    v_b = fric["boundary_v0"]
    assert len(v_b) >= 3 and all(b <= a for a, b in zip(v_b, v_b[1:]))  # boundary falls with dF
    assert -1.0 < fric["exponent"] < -0.3
    # the boundary searched at every load (root finding on the departure, not the grid) lies
    # inside each column's grid bracket: a boundary read one cell off falls outside it
    dF = s["dF"]
    for f, lo, hi in zip(fric["boundary_dF"], fric["boundary_v0_lo"], fric["boundary_v0_hi"]):
        v = fric["curve_v0"][dF.index(f)]
        assert v is not None and lo <= v <= hi, (f, lo, v, hi)
    # the CSV holds every member's numbers; the members either side of a boundary, rerun as
    # single scenes at the map's resolution, get the same labels
    with open(out / "map.csv") as fh:
        rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    assert len(rows) == 2 * 24
    mine = [r for r in rows if float(r["mu"]) == 0.3]
    assert sum(r["buckled"] in ("1", "True") for r in mine) == fric["buckled"]
    f, lo, hi = fric["boundary_dF"][0], fric["boundary_v0_lo"][0], fric["boundary_v0_hi"][0]
    rod = jr.RodChannel.reference(0.3)
    for v0, label in ((lo, False), (hi, True)):
        row = next(r for r in mine if float(r["dF"]) == f and float(r["v0"]) == v0)
        assert (row["buckled"] in ("1", "True")) == label
        scene = Scene(rod, f, make_perturbation("sine", v0), "field", n=s["n"], dt=s["dt"])
        assert bool(scene.run(t1=0.5, save_state=False).buckled) == label


def test_map_bad_range(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["map", "--dF", "5:1:3"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--dF" in err and "'5:1:3'" in err and "LO < HI" in err and "Traceback" not in err


def test_version(capsys):
    import jaxrod
    from jaxrod.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"jaxrod {jaxrod.__version__}"


@pytest.mark.parametrize("argv,option", [
    (["map", "--out", "/dev/null/x", "--dF", "1:2:2", "--v0", "0.01:0.1:2", "--quiet"], "--out"),
    (["figure", "phase", "--out", "/proc/jaxrod-test"], "--out"),
    (["simulate", "--plot", "/dev/null/a.png"], "--plot"),
    (["map", "--v0", "0:1:5"], "--v0"),
])
def test_unwritable_output_and_bad_values_end_in_one_line(argv, option, capsys):
    """Before any work: one line on stderr naming the option, exit code 2, no traceback."""
    from jaxrod.cli import main

    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and option in err and "Traceback" not in err
    assert "np.float64" not in err
