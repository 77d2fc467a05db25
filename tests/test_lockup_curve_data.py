"""The committed lock-up curve (`results/lockup/`, `jaxrod reproduce lockup`) against what the
README and docs/physics.md §8 say of it: every bracket called bracketed is within 3 % and rests
on a steady stage at or below the bound and one above it (or a lock); the soft-string columns are
`chain`'s values at the bound, recomputed here; and the README's lock-up figures are the files'."""

import csv
import json
import math
import pathlib

import jax
import pytest

from jaxrod.lockup import chain
from jaxrod.lockup.push import push_rod, units

ROOT = pathlib.Path(__file__).parent.parent
DATA = ROOT / "results" / "lockup"

jax.config.update("jax_enable_x64", True)


def _rows(name):
    with open(DATA / name) as fh:
        return list(csv.DictReader(fh))


def test_every_bracket_rests_on_steady_stages_on_either_side_of_the_bound():
    stages = _rows("stages.csv")
    for row in _rows("curve.csv"):
        if row["status"] != "bracketed" or row["kind"] != "run":
            continue
        lo, hi = float(row["lo"]), float(row["hi"])
        assert 0 < hi - lo <= 0.03 * hi, row
        far = row["quantity"] == "F_far_max"
        mine = [s for s in stages if s["n_segments"] == row["n_segments"] and s["push_speed"] == row["push_speed"]
                and s["varies"] == ("far_load" if far else "mu")
                and (not far or s["muL_over_ell"] == row["muL_over_ell"])]
        f_c = float(row["entry_force_bound"])
        below = [s for s in mine if math.isclose(float(s["parameter"]), lo) and s["status"] == "sliding"]
        above = [s for s in mine if math.isclose(float(s["parameter"]), hi)]
        assert below and float(below[-1]["f_in"]) <= f_c, row
        assert above and (above[-1]["status"] == "locked" or float(above[-1]["f_in"]) > f_c), row


def test_the_soft_string_columns_are_the_chain_at_the_bound():
    summary = json.loads((DATA / "curve.json").read_text())
    for row in _rows("curve.csv"):
        if row["quantity"] != "F_far_max":
            continue
        rod = push_rod(float(row["L_over_ell"]), summary["r_over_ell"], 1.0)
        F0, ell = units(rod)
        X, f_c = float(row["muL_over_ell"]), float(row["entry_force_bound"])
        mu = X * ell / float(rod.L)
        for onset in ("chen", "wu_juvkam_wold"):
            for law in ("with_weight", "without_weight"):
                got = float(chain.far_force(f_c * F0, rod.L, rod.EI, rod.rho * rod.g, rod.R, mu,
                                            helical_onset=onset, helical_law=law)) / F0
                assert float(row[f"soft_{onset}/{law}_at_fc"]) == pytest.approx(got, rel=1e-9, abs=1e-12)


def test_the_readme_quotes_the_files():
    readme = (ROOT / "README.md").read_text()
    base = [r for r in _rows("curve.csv") if r["quantity"] == "muL_lock" and r["segments_per_wave"] == "16"
            and r["push_speed"] == "0.01"]
    lo, hi = float(base[0]["lo"]), float(base[0]["hi"])
    assert f"{lo:.3f}–{hi:.3f}" in readme
    summary = json.loads((DATA / "curve.json").read_text())
    assert f"{summary['wall_s_this_call'] / 60:.1f} min" in readme
