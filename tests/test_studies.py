"""`results/` holds data only; the scripts that made its one-off studies live in `studies/`, one
per study, each writing into the same path under `results/`."""

import pathlib
import py_compile

ROOT = pathlib.Path(__file__).parent.parent


def test_results_hold_no_code():
    assert sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "results").rglob("*.py")) == []


def test_every_study_compiles_and_writes_where_its_data_is():
    studies = sorted((ROOT / "studies").rglob("*.py"))
    assert len(studies) >= 10
    for p in studies:
        py_compile.compile(str(p), doraise=True)
        data = ROOT / "results" / p.parent.relative_to(ROOT / "studies")
        assert data.is_dir(), f"{p.relative_to(ROOT)}: no data folder {data.relative_to(ROOT)}"
        text = p.read_text()
        assert "results/" in text or 'rpartition(os.sep + "studies")' in text, p
