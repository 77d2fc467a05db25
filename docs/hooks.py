"""MkDocs hooks of the documentation site (mkdocs.yml `hooks:`).

- The research notebooks (notebooks/*.ipynb) and the paper figures (results/paper/*/*.png) are
  added to the site where they live in the repository, so nothing is copied into docs/.
- The marker `<!-- results-table -->` in a page is replaced by the results table that
  studies/paper/table.py prints from results/paper/results.json (the README's table), and
  `<!-- cli-help -->` by the `--help` of every `jaxrod` command.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File

ROOT = pathlib.Path(__file__).resolve().parent.parent
TABLE_MARKER = "<!-- results-table -->"
CLI_MARKER = "<!-- cli-help -->"


@event_priority(100)  # before mkdocs-jupyter's on_files, which turns .ipynb files into pages
def on_files(files, config):
    for path in sorted(ROOT.glob("notebooks/*.ipynb")) + sorted(ROOT.glob("results/paper/*/*.png")):
        files.append(File(path.relative_to(ROOT).as_posix(), str(ROOT), config["site_dir"],
                          config["use_directory_urls"]))
    return files


def on_page_markdown(markdown, page, config, files):
    if TABLE_MARKER in markdown:
        table = subprocess.run([sys.executable, str(ROOT / "studies" / "paper" / "table.py")], check=True,
                               capture_output=True, text=True).stdout
        markdown = markdown.replace(TABLE_MARKER, table)
    if CLI_MARKER in markdown:
        markdown = markdown.replace(CLI_MARKER, _cli_help())
    return markdown


def _cli_help() -> str:
    """`jaxrod --help` and `jaxrod COMMAND --help` as Markdown sections, 100 columns wide."""
    from jaxrod.cli import build_parser

    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal's width
    try:
        parser = build_parser()
        commands = next(a for a in parser._actions if a.dest == "command").choices
        parts = [f"```text\n{parser.format_help()}```\n"]
        for name, sub in commands.items():
            parts.append(f"### jaxrod {name}\n\n```text\n{sub.format_help()}```\n")
    finally:
        if columns is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = columns
    return "\n".join(parts)
