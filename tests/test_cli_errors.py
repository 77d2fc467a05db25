"""Every error a user can reach on the `jaxrod` command line ends in one line on stderr naming the
option and exit code 2, never a traceback, and before any work: no JAX computation compiled (but
the conversion of a number into an array, which the rod's own checks need), no file or folder
written. (tests/test_cli.py holds the first checks of theory and simulate values, map's
--out and --v0, figure's --out and simulate's --plot; these are the others.)"""

import jax.monitoring
import pytest

from jaxrod.cli import main

BACKEND_COMPILE = "/jax/core/compile/backend_compile_duration"
# RodChannel checks its fields (--E, --L, ...) as arrays: making a number an array compiles this
ALLOWED = {"jit(convert_element_type)"}

# (argv, the option the message must name); {tmp}: the test's folder, {file}: a file in it
CASES = [
    # output paths that cannot be written
    (["boundary", "--out", "/proc/jaxrod-test"], "--out"),
    (["critical-load", "--out", "/dev/null/x"], "--out"),
    (["reproduce", "e2", "--out", "/dev/null/x"], "--out"),
    (["map", "--out", "{file}"], "--out"),  # an existing file, not a folder
    (["figure", "phase", "--out", ""], "--out"),
    (["simulate", "--model", "rod3d", "--export", "/dev/null/x"], "--export"),
    (["simulate", "--model", "rod3d", "--export", "/proc/jaxrod-test"], "--export"),
    (["simulate", "--plot", "/proc/jaxrod.png"], "--plot"),
    (["simulate", "--plot", "{tmp}"], "--plot"),  # a folder
    (["simulate", "--plot", "{tmp}/sim.txt"], "--plot"),  # no image format
    # ranges
    (["lockup", "--out", "/dev/null/x"], "--out"),
    (["lockup", "--mu", "-1"], "--mu"),
    (["lockup", "--mu-L", "0"], "--mu-L"),
    (["lockup", "--r-over-ell", "0.7"], "--r-over-ell"),
    (["lockup", "--far-load", "-1"], "--far-load"),
    # a tubing in SI units: missing, out of range, or given beside the dimensionless case
    (["lockup", "--E", "2e11", "--od", "0.05", "--clearance", "0.02", "--length", "100"], "--density"),
    (["lockup", "--E", "2e11", "--od", "0.05", "--density", "7850", "--length", "100"], "--clearance"),
    (["lockup", "--E", "2e11", "--od", "0.05", "--clearance", "0.02", "--length", "100", "--density", "7850", "--id", "0.06"], "--id"),
    (["lockup", "--E", "2e11", "--od", "0.05", "--clearance", "0.02", "--length", "100", "--density", "-7850"], "--density"),
    (["lockup", "--E", "2e11", "--od", "0.05", "--clearance", "0.02", "--length", "100", "--weight", "0"], "--weight"),
    (["lockup", "--E", "2e11", "--od", "0.05", "--clearance", "0.02", "--length", "100", "--density", "7850", "--mu-L", "1"], "--mu-L"),
    (["lockup", "--far-force", "-1"], "--far-force"),
    (["critical-load", "--t1", "0"], "--t1"),
    (["lockup", "--far-force", "1", "--far-load", "1"], "--far-force"),
    (["lockup", "--speed", "0"], "--speed"),
    (["lockup", "--damping", "-2"], "--damping"),
    (["lockup", "--n", "2"], "--n"),
    (["map", "--dF", "abc"], "--dF"),
    (["map", "--dF", "1:2"], "--dF"),
    (["map", "--dF", "1:inf:3"], "--dF"),
    (["map", "--v0", "0.01:0.1:0"], "--v0"),
    (["map", "--v0", "-0.01,0.02"], "--v0"),
    (["boundary", "--dF", "0:5:3"], "--dF"),
    (["critical-load", "--mu", "0:1:3"], "--mu"),
    (["critical-load", "--max-dF", "-5"], "--max-dF"),
    (["boundary", "--rtol", "0.7"], "--rtol"),
    # names of models, perturbations, methods, experiments, commands, options
    (["map", "--model", "rod"], "--model"),
    (["boundary", "--model", "mode3d"], "--model"),
    (["critical-load", "--perturbation", "noise"], "--perturbation"),
    (["boundary", "--method", "newton"], "--method"),
    (["reproduce", "e9"], "which"),
    (["reproduce"], "which"),
    (["figure", "bogus"], "which"),
    (["bogus"], "command"),
    (["map", "--bogus"], "--bogus"),
    # numbers
    (["critical-load", "--amplitude", "0"], "--amplitude"),
    (["critical-load", "--realizations", "0"], "--realizations"),
    (["critical-load", "--n", "2"], "--n"),
    (["map", "--t1", "0"], "--t1"),
    (["boundary", "--model", "rod3d", "--t1", "-1"], "--t1"),
    (["map", "--n", "2"], "--n"),
    (["map", "--model", "rod3d", "--n", "3"], "--n"),
    (["map", "--model", "auto", "--mu", "-1"], "--mu"),
    (["boundary", "--mu", "-0.1"], "--mu"),
    (["boundary", "--n", "2"], "--n"),
    (["simulate", "--n-save", "1"], "--n-save"),
    (["simulate", "--seed", "x"], "--seed"),
    (["simulate", "--mode", "1.5"], "--mode"),
    (["simulate", "--dF", "inf"], "--dF"),
    (["theory", "--E", "0"], "--E"),
    (["theory", "--L", "-3"], "--L"),
    # options of the 3D rod only, and their values
    (["simulate", "--model", "field", "--export", "{tmp}/export"], "--export"),
    (["simulate", "--model", "field", "--control", "displacement"], "--control"),
    (["simulate", "--model", "auto", "--control", "load"], "--control"),
    (["simulate", "--model", "rod3d", "--speed", "2e-3"], "--speed"),
    (["simulate", "--model", "rod3d", "--control", "displacement", "--speed", "-1"], "--speed"),
]


@pytest.fixture
def compilations():
    """The names of the XLA compilations while the test runs."""
    seen = []

    def listener(event, duration, **kwargs):
        if event == BACKEND_COMPILE:
            seen.append(kwargs.get("fun_name"))

    jax.monitoring.register_event_duration_secs_listener(listener)
    yield seen
    jax.monitoring.unregister_event_duration_listener(listener)


def _one_line_error(capsys, argv, option):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    out, err = capsys.readouterr()
    assert exc.value.code == 2, (argv, exc.value.code, err)
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert option in err and "error" in err, err
    assert "Traceback" not in err and "np.float64" not in err, err
    assert out == "", out
    return err


@pytest.mark.parametrize("argv, option", CASES, ids=[" ".join(a) or "(none)" for a, _ in CASES])
def test_error_is_one_line_naming_the_option_before_any_work(argv, option, tmp_path, monkeypatch, capsys,
                                                            compilations):
    monkeypatch.chdir(tmp_path)  # a default output folder (out/...) would land here
    (tmp_path / "afile").write_text("")
    before = sorted(tmp_path.rglob("*"))
    argv = [a.format(tmp=tmp_path, file=tmp_path / "afile") for a in argv]
    _one_line_error(capsys, argv, option)
    assert sorted(tmp_path.rglob("*")) == before  # nothing created
    assert set(compilations) <= ALLOWED, compilations


@pytest.mark.parametrize("argv", [["simulate", "--model", "field", "--n", "8", "--dt", "1"],
                                  ["simulate", "--model", "mode", "--mode", "200"]],  # the default step
                         ids=["given", "default"])
def test_a_step_above_the_models_limit_names_dt(argv, tmp_path, monkeypatch, capsys):
    """The step limit needs the model (2/ω_max at the rod's resolution): checked after building it,
    before the run, and still reported as the option's error."""
    monkeypatch.chdir(tmp_path)
    err = _one_line_error(capsys, argv, "--dt")
    assert "stability limit" in err
