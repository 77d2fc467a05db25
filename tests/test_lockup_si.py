"""A tubing given in SI units (`jaxrod.lockup.si`, `jaxrod lockup --E ... --far-force`): the
section's stiffness and weight are the tube's, its case is P8's, and the command given the
reference rod in SI gives the answer of the same case given dimensionless, in N and m beside it."""

import json
import math

import jax
import pytest

from jaxrod.lockup.push import push_rod, units
from jaxrod.lockup.si import G_STANDARD, case, tubing

jax.config.update("jax_enable_x64", True)


def test_a_tube_has_the_bending_stiffness_mass_and_weight_of_its_annulus():
    """Coiled tubing 2" × 0.175" wall (50.8 / 41.9 mm), steel: EI = Eπ(D⁴ − D_i⁴)/64, mass per length
    ρπ(D² − D_i²)/4, weight that times g; GJ/EI as for any isotropic section; buoyed in mud of
    1200 kg/m³ the weight is the one given and the mass stays the steel's."""
    D, Di, E, rho = 0.0508, 0.04191, 200e9, 7850.0
    rod = tubing(E, D, 0.0254, 1000.0, 0.3, inner_diameter=Di, density=rho, nu=0.3)
    area = math.pi * (D**2 - Di**2) / 4
    assert math.isclose(float(rod.EI), E * math.pi * (D**4 - Di**4) / 64, rel_tol=1e-12)
    assert math.isclose(float(rod.rho), rho * area, rel_tol=1e-12)
    assert math.isclose(float(rod.rho * rod.g), rho * area * G_STANDARD, rel_tol=1e-12)
    assert float(rod.d) == D and float(rod.R) == 0.0254 and float(rod.L) == 1000.0
    assert float(rod.mu_s) == float(rod.mu_d) == 0.3
    buoyed = (rho - 1200.0) * area * G_STANDARD
    mud = tubing(E, D, 0.0254, 1000.0, 0.3, inner_diameter=Di, density=rho, weight_per_length=buoyed)
    assert math.isclose(float(mud.rho), rho * area, rel_tol=1e-12)
    assert math.isclose(float(mud.rho * mud.g), buoyed, rel_tol=1e-12)
    only_weight = tubing(E, D, 0.0254, 1000.0, 0.3, inner_diameter=Di, weight_per_length=40.0)
    assert math.isclose(float(only_weight.rho * only_weight.g), 40.0, rel_tol=1e-12)
    assert math.isclose(float(only_weight.rho), 40.0 / G_STANDARD, rel_tol=1e-12)
    c = case(rod)
    EI, w = float(rod.EI), rho * area * G_STANDARD
    assert math.isclose(c["F0"], math.sqrt(EI * w / 0.0254), rel_tol=1e-12)
    assert math.isclose(c["ell"], math.sqrt(EI / (0.0254 * w)), rel_tol=1e-12)
    assert math.isclose(c["mu_L_over_ell"], 0.3 * 1000.0 / c["ell"], rel_tol=1e-12)
    assert math.isclose(c["r_over_ell"], 0.0254 / c["ell"], rel_tol=1e-12)


def test_the_case_of_a_rod_made_for_a_case_is_that_case():
    rod = push_rod(1.5, 0.03, 0.4)
    c = case(rod)
    assert math.isclose(c["mu_L_over_ell"], 1.5, rel_tol=1e-12) and math.isclose(c["r_over_ell"], 0.03, rel_tol=1e-12)
    assert (c["F0"], c["ell"]) == units(rod)


@pytest.mark.parametrize("kw, name", [
    (dict(E=-1.0), "E"), (dict(outer_diameter=0.0), "outer_diameter"), (dict(inner_diameter=0.06), "inner_diameter"),
    (dict(clearance=float("nan")), "clearance"), (dict(length=0.0), "length"), (dict(mu=0.0), "mu"),
    (dict(density=None), "density"), (dict(density=-5.0), "density"), (dict(weight_per_length=0.0), "weight_per_length"),
])
def test_a_bad_tubing_is_refused_naming_the_argument(kw, name):
    args = dict(E=200e9, outer_diameter=0.05, clearance=0.02, length=100.0, mu=0.3, inner_diameter=0.04,
                density=7850.0)
    args.update(kw)
    if name == "weight_per_length":
        args["density"] = None
    with pytest.raises(ValueError, match=f"^{name} = "):
        tubing(**args)


def test_the_command_given_a_tubing_in_si_gives_the_dimensionless_cases_answer_in_newtons(tmp_path, capsys):
    """The reference nitinol rod of the case μL/ℓ = 0.5, r/ℓ = 0.02, μ = 0.5 given by its modulus,
    diameter, density, clearance and length, pushed against `--far-force` = 0.5 F₀ [N]: the same
    run as the case given dimensionless (`--mu-L 0.5 --far-load 0.5`), its forces in F₀ equal to
    rounding, and the SI figures F₀ times them."""
    from jaxrod.cli import main

    rod = push_rod(0.5, 0.02, 0.5)
    F0, ell = units(rod)
    common = ["--push", "0.005", "--json", "--quiet", "--scheme", "leapfrog"]
    assert main(["lockup", "--mu-L", "0.5", "--far-load", "0.5", "--out", str(tmp_path / "a")] + common) == 0
    a = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    si = ["--E", "77e9", "--od", "1.5e-3", "--density", "6450", "--nu", "0.33", "--clearance", repr(float(rod.R)),
          "--length", repr(float(rod.L)), "--far-force", repr(0.5 * F0)]
    # RodChannel.reference's g is 9.81, the tubing's default standard gravity: give the weight to match
    w = float(rod.rho * rod.g)
    assert main(["lockup", *si, "--weight", repr(w), "--out", str(tmp_path / "b")] + common) == 0
    b = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert math.isclose(b["mu_L_over_ell"], 0.5, rel_tol=1e-9) and math.isclose(b["r_over_ell"], 0.02, rel_tol=1e-9)
    assert math.isclose(b["F0"], F0, rel_tol=1e-9) and math.isclose(b["ell"], ell, rel_tol=1e-9)
    assert b["n_segments"] == a["n_segments"]
    for x, y in zip(a["entry_force_over_F0_last_fifth"], b["entry_force_over_F0_last_fifth"]):
        assert math.isclose(x, y, rel_tol=1e-6)
    s = b["si"]
    assert math.isclose(s["far_force_N"], 0.5 * F0, rel_tol=1e-12)
    for x, y in zip(s["entry_force_N_last_fifth"], b["entry_force_over_F0_last_fifth"]):
        assert math.isclose(x, y * F0, rel_tol=1e-9)
    assert math.isclose(s["soft_string_lockup_length_m"], 4.059 * ell / 0.5, rel_tol=1e-3)
    assert all(math.isclose(v, 1.0 * F0, rel_tol=1e-9) for v in s["soft_string_entry_force_N"].values())


def test_the_command_builds_the_tubing_in_float64_in_a_fresh_process(tmp_path):
    """In a fresh process (float64 off until the command turns it on) `jaxrod lockup` given a
    tubing hands `inject` a float64 rod: no traceback (the rod once was built by the argument
    check, in float32). `inject` is replaced by a stand-in that reports the dtype and stops."""
    import subprocess
    import sys

    code = (
        "import sys, jaxrod.lockup.push as p\n"
        "def stop(rod, *a, **k):\n"
        "    print('dtype', rod.EI.dtype); sys.exit(7)\n"
        "p.inject = stop\n"
        "from jaxrod.cli import main\n"
        "main(['lockup', '--E', '200e9', '--od', '0.0508', '--id', '0.04191', '--density', '7850', '--clearance',"
        " '0.0254', '--length', '300', '--mu', '0.3', '--far-force', '20000', '--quiet', '--out', sys.argv[1]])\n")
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "lk")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 7, run.stderr[-2000:]
    assert run.stdout.strip().splitlines()[-1] == "dtype float64"


def test_the_committed_examples_are_steady_slides_and_the_docs_quote_them():
    """The two SI examples (`results/lockup/si/`): steady slides (the verdict), their SI figures
    F₀ times the dimensionless ones, between Wu & Juvkam-Wold's chain and Chen's with the weight
    term, and quoted so in docs/physics.md §8."""
    import pathlib

    root = pathlib.Path(__file__).parent.parent
    docs = (root / "docs" / "physics.md").read_text()
    for name, quote in (("coiled_tubing", "**25.97 kN**"), ("guidewire", "**0.0806–0.0812 N**")):
        d = json.loads((root / "results" / "lockup" / "si" / name / "lockup.json").read_text())
        si = d["si"]
        assert d["verdict"]["status"] == "sliding" and d["result"] == "successful"
        lo, hi = si["entry_force_N_last_fifth"]
        f_lo, f_hi = d["entry_force_over_F0_last_fifth"]
        assert math.isclose(lo, f_lo * si["F0_N"], rel_tol=1e-9) and math.isclose(hi, f_hi * si["F0_N"], rel_tol=1e-9)
        soft = si["soft_string_entry_force_N"]
        assert soft["wu_juvkam_wold / with_weight"] < lo <= hi < soft["chen / with_weight"]
        assert quote in docs
        c = case(tubing(**{"E": {"coiled_tubing": 200e9, "guidewire": 60e9}[name]},
                        **({"outer_diameter": 0.0508, "inner_diameter": 0.04191, "density": 7850.0, "clearance": 0.0254,
                            "length": 300.0, "mu": 0.3} if name == "coiled_tubing" else
                           {"outer_diameter": 3.6e-4, "density": 6450.0, "clearance": 5e-4, "length": 2.0, "mu": 0.3})))
        assert math.isclose(c["F0"], si["F0_N"], rel_tol=1e-12) and math.isclose(c["ell"], si["ell_m"], rel_tol=1e-12)
