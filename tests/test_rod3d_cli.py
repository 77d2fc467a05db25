"""`jaxrod simulate --model rod3d`: the 3D rod from the command line."""

import json

import pytest

from jaxrod.cli import main


@pytest.mark.slow  # 23-30 s of 3D compilation; the default suite keeps a quicker check
def test_simulate_rod3d_displacement_control_reports_the_peak_reaction(capsys):
    assert main(["simulate", "--model", "rod3d", "--control", "displacement", "--speed", "2e-3",
                 "--n", "8", "--t1", "0.05", "--n-save", "51", "--amplitude", "0.01", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "rod3d" and out["control"] == "displacement" and out["n_segments"] == 8
    # linear response before buckling: reaction ≈ EA·displacement/L at the peak, to 10 %
    EA, L = 77e9 * 3.14159265 * 1.5e-3**2 / 4, 3.0
    assert out["peak_reaction"] == pytest.approx(EA * out["end_displacement_at_peak"] / L, rel=0.1)
    assert out["result"] == "successful"


def test_simulate_rod3d_rejects_other_perturbations():
    with pytest.raises(SystemExit):
        main(["simulate", "--model", "rod3d", "--perturbation", "random-velocity", "--n", "8"])
