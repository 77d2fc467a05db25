"""The documentation site builds with `mkdocs build --strict` (what `make docs` runs: a broken
link or an unresolved cross-reference in a page or a docstring fails it), and has an API entry
for the key objects, the notebooks with their stored figures, the CLI's help and the results
table."""

import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent

# page of the site -> the anchors mkdocstrings gives the objects documented there
API = {
    "api/rod": ["jaxrod.RodChannel", "jaxrod.theory", "jaxrod.Solution"],
    "api/models": ["jaxrod.SingleMode", "jaxrod.GalerkinModel", "jaxrod.FieldModel"],
    "api/integrators": ["jaxrod.Coulomb", "jaxrod.Tanh", "jaxrod.ProjectedVerlet", "jaxrod.simulate"],
    "api/scene": ["jaxrod.Scene", "jaxrod.SineVelocity"],
    "api/sweeps": ["jaxrod.sweep", "jaxrod.SweepSpec", "jaxrod.SweepResult", "jaxrod.SweepResult.to_xarray"],
    "api/boundary": ["jaxrod.critical_velocity", "jaxrod.boundary.boundary_curve"],
    "api/rod3d": ["jaxrod.rod3d.Rod3D", "jaxrod.rod3d.step_limit"],
    "api/figures": ["jaxrod.figures.plot_simulation", "jaxrod.figures.export3d.write_vtk"],
}


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    res = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                          str(ROOT / "mkdocs.yml"), "--site-dir", str(out)],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-4000:]
    assert "WARNING" not in res.stderr, res.stderr[-4000:]
    return out


def _page(site, name):
    return (site / name / "index.html").read_text()


@pytest.mark.parametrize("page", sorted(API))
def test_api_page_documents_the_key_objects(site, page):
    html = _page(site, page)
    for anchor in API[page]:
        assert f'id="{anchor}"' in html, anchor


def test_guides_notebooks_cli_and_results_table(site):
    for page in ("getting-started", "models", "friction", "sweeps", "boundary", "rod3d", "paper", "cli",
                 "physics"):
        assert (site / page / "index.html").exists(), page
    cli = _page(site, "cli")
    assert "usage: jaxrod map" in cli and "--out OUT" in cli  # the help, written at build time
    paper = _page(site, "paper")
    assert "E3 map: boundary exponent" in paper and "<table>" in paper  # from studies/paper/table.py
    for nb in sorted(ROOT.glob("notebooks/0*.ipynb")):
        html = _page(site, f"notebooks/{nb.stem}")
        if '"image/png"' in nb.read_text():  # stored figures are shown, not re-run
            assert "data:image/png;base64" in html, nb.name
