"""README.md, docs/status.md and benchmarks/README.md are references that stay true: their links resolve, their
length stays within its limit, and the numbers they copy from a results file or a script are
checked against that source.

A table (or any text) copied from a file is framed in the README:

    <!-- include: benchmarks/results/first_answer/first_answer.md | headings +2 -->
    ...the file's content...
    <!-- end include -->

and the framed text must equal the file's content, stripped, after the options that follow the
path, each after a `|`:

- `preamble`: only the file's text before its first level-2 heading (`## `);
- `headings +N`: every Markdown heading of the file N levels deeper (`#` -> `###` for +2), so a
  file's title fits under the README's sections.

The output of a script is framed likewise:

    <!-- generated: studies/paper/table.py --compact -->
    ...what `python studies/paper/table.py --compact` prints...
    <!-- end generated -->

After a results file is rewritten or a script's output changes, `python tests/test_readme.py
--update` rewrites every frame of both READMEs from its source (and prints what it changed).
"""

from __future__ import annotations

import pathlib
import re
import subprocess
import sys
import unicodedata

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
LIMITS = {"README.md": 150, "docs/status.md": 240, "benchmarks/README.md": 400}  # README: the front door; the
# measurements behind it in docs/status.md
FILES = sorted(LIMITS)

FRAME = re.compile(r"<!-- (include|generated): (.+?) -->\n(.*?)<!-- end \1 -->", re.S)
FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.S | re.M)
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})[ \t]+(.+?)[ \t#]*$", re.M)


# ---------------------------------------------------------------- frames


def _shift_headings(text: str, levels: int) -> str:
    """Every ATX heading outside code fences `levels` deeper."""
    out, fenced = [], False
    for line in text.split("\n"):
        if line.startswith(("```", "~~~")):
            fenced = not fenced
        elif not fenced and re.match(r"#{1,6} ", line):
            line = "#" * levels + line
        out.append(line)
    return "\n".join(out)


def _source_text(kind: str, spec: str) -> str:
    """What a frame must hold: the included file (after its options) or the script's output."""
    if kind == "generated":
        argv = spec.split()
        res = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True, text=True, timeout=120,
                             check=True)
        return res.stdout.strip()
    path, *options = [p.strip() for p in spec.split("|")]
    text = (ROOT / path).read_text(encoding="utf-8")
    for option in options:
        if option == "preamble":
            m = re.search(r"^## ", text, re.M)
            text = text[: m.start()] if m else text
        elif m := re.fullmatch(r"headings \+(\d)", option):
            text = _shift_headings(text, int(m.group(1)))
        else:
            raise ValueError(f"unknown include option {option!r} in {spec!r}")
    return text.strip()


def _frames(name: str):
    text = (ROOT / name).read_text(encoding="utf-8")
    return [(m.group(1), m.group(2).strip(), m.group(3)) for m in FRAME.finditer(text)]


def test_frames_exist():
    """docs/status.md (the measurements behind the README) frames the speed headline, the mutation
    score and the paper's table."""
    readme = {(kind, spec.split("|")[0].split()[0]) for kind, spec, _ in _frames("docs/status.md")}
    assert ("include", "benchmarks/results/first_answer/first_answer.md") in readme
    assert ("include", "results/mutation/report.md") in readme
    assert ("generated", "studies/paper/table.py") in readme


@pytest.mark.parametrize("name", FILES)
def test_framed_text_equals_its_source(name):
    for kind, spec, body in _frames(name):
        assert body.strip() == _source_text(kind, spec), (
            f"{name}: the text framed by <!-- {kind}: {spec} --> differs from its source; "
            "run `python tests/test_readme.py --update`")


def update() -> None:
    for name in FILES:
        path = ROOT / name
        text = path.read_text(encoding="utf-8")

        def fill(m):
            new = _source_text(m.group(1), m.group(2).strip())
            return f"<!-- {m.group(1)}: {m.group(2)} -->\n{new}\n<!-- end {m.group(1)} -->"

        new = FRAME.sub(fill, text)
        if new != text:
            path.write_text(new, encoding="utf-8")
            print(f"updated {name}")


# ---------------------------------------------------------------- links and anchors


def _plain(text: str) -> str:
    """Markdown text without fenced code blocks, HTML comments and inline code spans' backticks."""
    text = FENCE.sub("", text)
    return re.sub(r"<!--.*?-->", "", text, flags=re.S)


def github_slug(heading: str) -> str:
    """GitHub's anchor of a heading: the rendered text lowercased, every character that is not a
    letter, a digit, a space, `-` or `_` dropped (letters of any script are kept), spaces -> `-`."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links -> their text
    text = re.sub(r"<[^>]+>", "", text).replace("`", "").replace("*", "")
    text = text.lower()
    kept = []
    for ch in text:
        cat = unicodedata.category(ch)
        if ch in " -_" or cat[0] in "LN" or cat == "Mn":
            kept.append(ch)
    return "".join(kept).replace(" ", "-")


def mkdocs_slug(heading: str) -> str:
    """Python-Markdown's default anchor (the documentation site): ASCII only."""
    from markdown.extensions.toc import slugify

    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = re.sub(r"<[^>]+>", "", text).replace("`", "").replace("*", "")
    return slugify(text, "-")


def anchors(path: pathlib.Path, slug=github_slug) -> set[str]:
    """The heading anchors of a Markdown file, with GitHub's -1, -2 suffixes for repeats."""
    seen: dict[str, int] = {}
    out = set()
    for m in HEADING.finditer(_plain(path.read_text(encoding="utf-8"))):
        s = slug(m.group(2))
        if s in seen:
            seen[s] += 1
            out.add(f"{s}-{seen[s]}")
        else:
            seen[s] = 0
            out.add(s)
    return out


def links(name: str) -> list[str]:
    text = re.sub(r"`[^`\n]*`", "", _plain((ROOT / name).read_text(encoding="utf-8")))
    return [m.group(1) for m in LINK.finditer(text)]


def test_github_slug():
    assert github_slug("Time to first answer (`first_answer.py`)") == "time-to-first-answer-first_answerpy"
    assert github_slug("Accuracy, as tested") == "accuracy-as-tested"
    assert github_slug("3D rod: the step's cost (`rod3d_step.py`)") == "3d-rod-the-steps-cost-rod3d_steppy"
    assert github_slug("Field model: v₀* against ΔF") == "field-model-v₀-against-δf"
    assert github_slug("Work–precision diagrams") == "workprecision-diagrams"


@pytest.mark.parametrize("name", FILES)
def test_links_and_anchors_resolve(name):
    here = (ROOT / name).parent
    bad = []
    for target in links(name):
        if re.match(r"[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
            continue
        file, _, anchor = target.partition("#")
        path = (here / file).resolve() if file else ROOT / name
        if not path.exists():
            bad.append(f"{target}: no such file")
            continue
        if anchor:
            if path.suffix != ".md":
                bad.append(f"{target}: an anchor into a file that is not Markdown")
            elif anchor not in anchors(path):
                bad.append(f"{target}: no heading with that anchor in {path.relative_to(ROOT)}")
            elif "docs" in path.relative_to(ROOT).parts and anchor not in anchors(path, mkdocs_slug):
                bad.append(f"{target}: the documentation site gives that heading another anchor")
    assert not bad, f"{name}:\n" + "\n".join(bad)


@pytest.mark.parametrize("name", FILES)
def test_length_within_limit(name):
    lines = (ROOT / name).read_text(encoding="utf-8").count("\n")
    assert lines <= LIMITS[name], f"{name} has {lines} lines, the limit is {LIMITS[name]}"


def test_every_benchmark_script_has_a_section():
    text = (ROOT / "benchmarks" / "README.md").read_text(encoding="utf-8")
    headings = [m.group(2) for m in HEADING.finditer(_plain(text))]
    missing = [p.name for p in sorted((ROOT / "benchmarks").glob("*.py")) if not p.name.startswith("_")
               and not any(f"`{p.name}`" in h for h in headings)]
    assert not missing, f"benchmarks/README.md has no section for {missing}"


def test_no_work_period_ordinals():
    """A measurement names its commit and date, never the work period that made it."""
    pages = [ROOT / n for n in FILES] + sorted((ROOT / "docs").glob("*.md"))
    found = [f"{p.relative_to(ROOT)}:{i}" for p in pages
             for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(r"\bsession\b", line, re.I)]
    assert not found, found


if __name__ == "__main__":
    if sys.argv[1:] == ["--update"]:
        update()
    else:
        sys.exit(pytest.main([__file__, "-q", "-p", "no:xdist"]))


def test_the_readme_code_runs(capsys):
    """The README's Python blocks (the example, then the API sketch, which continues it) run as
    written, and the example prints what the README says it prints."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, re.S | re.M)
    assert len(blocks) == 2
    scope: dict = {}
    exec(compile("\n".join(blocks), "README.md", "exec"), scope)  # noqa: S102
    out = capsys.readouterr().out
    assert "critical lateral speed: 28.47 mm/s" in out and "prints a critical lateral speed of 28.47 mm/s" in text
    assert int(scope["sol"].result) == 0 and float(scope["root"].root) > 0
