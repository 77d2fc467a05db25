"""What tools/mutants.py and tools/mutants_heldout.py share: the commit, the Wilson interval, source
hashes and staleness, the equivalent mutants keyed by text, and the README's frame of the report.

Equivalent mutants (`tools/mutants_equivalent.json`) are a list of entries
`{"module": "jaxrod/theory.py", "line": "...", "mutant": "...", "reason": "..."}`: `line` is the
text of the mutated source line(s) (each stripped, joined by a newline) and `mutant` the text
mutmut puts in their place, both read off the mutant's diff. A mutant is equivalent when its
diff gives the same three texts, so the entry survives edits elsewhere in the module (mutmut's
ordinal names, `x_f__mutmut_15`, shift with every edit of the function); it lapses when the
line itself changes. The same text mutated the same way twice in one module shares one entry.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EQUIVALENT = os.path.join(ROOT, "tools", "mutants_equivalent.json")
README_FRAME = re.compile(r"(<!-- include: results/mutation/report\.md \| preamble \| headings \+2 -->\n)"
                          r"(.*?)(<!-- end include -->)", re.S)


def commit(short: bool = True) -> str:
    try:
        args = ["git", "rev-parse", *(["--short"] if short else []), "HEAD"]
        return subprocess.run(args, cwd=ROOT, capture_output=True, text=True).stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def dirty(paths: list[str]) -> bool:
    """Whether the working tree differs from HEAD under `paths` (the run is then of uncommitted code)."""
    out = subprocess.run(["git", "status", "--porcelain", "--", *paths], cwd=ROOT, capture_output=True, text=True)
    return bool(out.stdout.strip())


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a sampled kill rate k / n."""
    p, d = k / n, 1 + z * z / n
    c, h = (p + z * z / (2 * n)) / d, z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return c - h, c + h


def sha256(path: str, root: str = ROOT) -> str | None:
    """The sha256 of a file's bytes (relative to `root`), or None when it does not exist."""
    try:
        with open(os.path.join(root, path), "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except FileNotFoundError:
        return None


def sha256_at(rev: str, path: str) -> str | None:
    """The sha256 of a file as committed at `rev` (None when git does not have it there)."""
    out = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, capture_output=True)
    return hashlib.sha256(out.stdout).hexdigest() if out.returncode == 0 else None


# ---------------------------------------------------------------- equivalent mutants


def diff_key(diff: str) -> tuple[str, str, str] | None:
    """(module path, original line text, mutant text) of a mutant's unified diff (`mutmut show`)."""
    module, minus, plus = None, [], []
    for line in diff.splitlines():
        if line.startswith("--- "):
            module = line[4:].strip()
        elif line.startswith("+++ ") or line.startswith("@@"):
            continue
        elif line.startswith("-"):
            minus.append(line[1:].strip())
        elif line.startswith("+"):
            plus.append(line[1:].strip())
    if module is None or not (minus or plus):
        return None
    return module, "\n".join(minus), "\n".join(plus)


def load_equivalent(path: str = EQUIVALENT) -> dict[tuple[str, str, str], str]:
    with open(path, encoding="utf-8") as f:
        return {(e["module"], e["line"], e["mutant"]): e["reason"] for e in json.load(f)}


def equivalent_reason(diff: str | None, table: dict) -> str | None:
    key = diff_key(diff) if diff else None
    return table.get(key) if key else None


def lapsed_equivalent(table: dict, root: str = ROOT) -> list[tuple[str, str, str]]:
    """Entries whose original line no longer occurs in their module's working-tree source."""
    out = []
    for key in table:
        module, line = key[0], key[1]
        try:
            text = open(os.path.join(root, module), encoding="utf-8").read()
        except FileNotFoundError:
            out.append(key)
            continue
        lines = {s.strip() for s in text.splitlines()}
        if not all(part in lines for part in line.split("\n") if part):
            out.append(key)
    return out


# ---------------------------------------------------------------- staleness


def stale(report: dict, heldout: dict | None) -> dict:
    """Each mutated module's recorded sha256 (per group and the held-out run) against the working
    tree's: {"changed": [...], "modules": T, "groups": [groups with a changed module],
    "heldout": whether the held-out sample's modules changed}."""
    recorded: dict[str, set[str]] = {}
    groups = []
    for name, g in report.get("groups", {}).items():
        hashes = g.get("module_hashes", {})
        changed_here = False
        for path, h in hashes.items():
            recorded.setdefault(path, set()).add(h)
            changed_here |= sha256(path) != h
        if changed_here or not hashes:
            groups.append(name)
    held = False
    for path, h in (heldout or {}).get("module_hashes", {}).items():
        recorded.setdefault(path, set()).add(h)
        held |= sha256(path) != h
    changed = sorted(p for p, hs in recorded.items() if any(sha256(p) != h for h in hs))
    return {"changed": changed, "modules": len(recorded), "groups": groups, "heldout": held}


def stale_line(s: dict) -> str:
    return f"stale: {len(s['changed'])} of {s['modules']} mutated modules changed since their run"


# ---------------------------------------------------------------- README


def update_readme_frame(report_md: str, readme: str = os.path.join(ROOT, "README.md")) -> bool:
    """Rewrite README.md's frame of results/mutation/report.md (its preamble, headings two levels
    deeper), as `python tests/test_readme.py --update` does for every frame; True if it changed."""
    text = open(report_md, encoding="utf-8").read()
    m = re.search(r"^## ", text, re.M)
    pre = text[: m.start()] if m else text
    out, fenced = [], False
    for line in pre.split("\n"):
        if line.startswith(("```", "~~~")):
            fenced = not fenced
        elif not fenced and re.match(r"#{1,6} ", line):
            line = "##" + line
        out.append(line)
    body = "\n".join(out).strip() + "\n"
    old = open(readme, encoding="utf-8").read()
    new = README_FRAME.sub(lambda g: g.group(1) + body + g.group(3), old)
    if new != old:
        with open(readme, "w", encoding="utf-8") as f:
            f.write(new)
    return new != old
