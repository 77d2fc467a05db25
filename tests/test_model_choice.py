import csv
import json
import os

import pytest

from jaxrod.cli import _resolve_auto_model, build_parser, main
from jaxrod.model_choice import choose_model

TABLE = os.path.join(os.path.dirname(__file__), "..", "benchmarks", "results", "model_choice.csv")

# Every scene of benchmarks/model_choice.py: (scene name in its CSV, perturbation, the largest load
# the computation meets [N], mu) and the rule's answer for it (checked against the measured table
# below, not restated).
SCENES = [
    ("sine mode 6, dF = 1 N, mu = 0.3", "sine", 1.0, 0.3, ("mode", None)),
    ("sine mode 6, dF = 5 N, mu = 0.3", "sine", 5.0, 0.3, ("field", 128)),
    ("sine mode 6, dF = 20 N, mu = 0.3", "sine", 20.0, 0.3, ("field", 128)),
    ("E3 map, mu = 0.3, 8x8 grid", "sine", 64.0, 0.3, ("field", 384)),
    ("random velocity ±15 mm/s, mu = 0.05", "random-velocity", 200.0, 0.05, ("field", 768)),
    ("random velocity ±15 mm/s, mu = 1", "random-velocity", 200.0, 1.0, ("field", 768)),
    ("random position ±2 N/m, mu = 0.05", "random-position", 200.0, 0.05, ("field", 384)),
    ("random position ±2 N/m, mu = 1", "random-position", 200.0, 1.0, ("field", 384)),
]


def test_rule_picks_only_models_measured_within_two_percent():
    """Against the benchmark's own table: for every scene, the model the rule picks was
    measured within 2 % of the finest field model (and with the same dominant mode)."""
    if not os.path.exists(TABLE):
        pytest.skip("benchmarks/results/model_choice.csv not present")
    with open(TABLE) as fh:
        rows = list(csv.DictReader(fh))
    for name, perturbation, dF, mu, _ in SCENES:
        model, n = choose_model(perturbation, dF, mu)
        match = [r for r in rows if r["scene"] == name and r["model"] == model
                 and r["n"] == ("" if n is None else str(n))]
        assert len(match) == 1, (name, model, n)
        assert match[0]["within"] == "True", (name, model, n, match[0]["error"])


def test_rule_boundaries_and_other_perturbations():
    assert choose_model("sine", 0.2, 0.05) == ("mode", None)
    assert choose_model("sine", 1.5, 0.3)[0] == "field"
    assert choose_model("sine", 60.0, 1.0) == ("field", 384)
    assert choose_model("random-shape", 5.0, 0.3) == choose_model("random-velocity", 5.0, 0.3)


@pytest.mark.parametrize(
    "args, word",
    [(("noise", 1.0, 0.3), "perturbation"), (("sine", float("nan"), 0.3), "dF"),
     (("sine", 1.0, -0.1), "mu"), (("sine", 1.0, float("inf")), "mu")],
)
def test_rule_rejects_bad_input(args, word):
    with pytest.raises(ValueError, match=word):
        choose_model(*args)


def test_simulate_auto_runs_and_reports_the_chosen_model(capsys):
    base = ["simulate", "--model", "auto", "--amplitude", "0.01", "--t1", "0.05", "--n-save", "11", "--json"]
    assert main(base + ["--dF", "1"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert out["model"] == "mode" and out["n"] is None
    assert "--model auto chose the mode model" in cap.err
    assert main(base + ["--dF", "5"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert out["model"] == "field" and out["n"] == 128 and out["result"] is not None
    assert "--model auto chose the field model with n = 128" in cap.err
    assert main(base + ["--dF", "5", "--n", "32"]) == 0  # an explicit --n is kept
    assert json.loads(capsys.readouterr().out)["n"] == 32


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["map", "--dF", "0.5:64:4"], ("field", 384)),
        (["map", "--dF", "0.2:1:3", "--mu", "0.3"], ("mode", None)),
        (["boundary", "--dF", "1:20:3"], ("field", 128)),
        (["critical-load", "--perturbation", "random-position"], ("field", 384)),
        (["critical-load", "--max-dF", "0.5"], ("mode", None)),
    ],
)
def test_auto_for_the_other_commands(capsys, argv, expected):
    args = build_parser().parse_args(argv + ["--model", "auto"])
    _resolve_auto_model(args)
    assert (args.model, args.n) == expected
    assert "--model auto chose" in capsys.readouterr().err
