"""The house: imports in `jaxrod/` go only downward through the layers, and there is no cycle.
Every import statement counts, also those inside functions (a lazy import is still a
dependency)."""

import ast
import pathlib

PKG = pathlib.Path(__file__).parent.parent / "jaxrod"

# Bottom to top. A module may import from its own layer or below, never above.
LAYERS = [
    ["_results", "_version", "_xla", "_cache", "_numerics", "_trig", "_banded", "params", "friction", "loads", "modal", "solution", "batching", "search", "output",
     "distributed"],
    ["theory", "lockup"],
    ["models", "rod3d.so3", "rod3d.model", "rod3d"],
    ["integrators"],
    ["perturbations", "simulate", "problem", "registry"],
    ["scene", "lockup.push", "lockup.staircase"],
    ["sweeps", "boundary", "model_choice", "map_columns"],
    ["stability_map", "worst_case", "figures"],
    ["experiments", "reproduce"],
    ["cli", "__init__", "__main__"],
]


def _modules() -> dict[str, pathlib.Path]:
    out = {}
    for f in PKG.rglob("*.py"):
        parts = list(f.relative_to(PKG).with_suffix("").parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


def _layer(name: str) -> int:
    best, depth = None, -1
    for i, layer in enumerate(LAYERS):
        for prefix in layer:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > depth:
                best, depth = i, len(prefix)
    assert best is not None, f"jaxrod.{name} is in no layer of tests/test_layers.py: add it"
    return best


def _imports(name: str, path: pathlib.Path, modules) -> set[str]:
    """The jaxrod modules that `name` imports (relative and absolute, at any depth)."""
    is_pkg = path.name == "__init__.py"
    package = name.split(".") if is_pkg and name != "__init__" else name.split(".")[:-1]
    if name == "__init__":
        package = []
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
            elif node.module and node.module.split(".")[0] == "jaxrod":
                base = []
            else:
                continue
            mod = (node.module or "").split(".")
            if not node.level:
                mod = mod[1:]
            target = [p for p in base + mod if p]
            for alias in node.names:
                sub = ".".join(target + [alias.name])
                found.add(sub if sub in modules else ".".join(target) or "__init__")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "jaxrod":
                    found.add(".".join(alias.name.split(".")[1:]) or "__init__")
    found.discard(name)
    return {m for m in found if m in modules}


def _graph():
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def test_imports_go_only_downward():
    upward = [f"jaxrod.{a} (layer {_layer(a)}) imports jaxrod.{b} (layer {_layer(b)})"
              for a, deps in _graph().items() for b in deps if _layer(b) > _layer(a)]
    assert not upward, "\n".join(upward)


def test_no_import_cycle():
    graph = _graph()
    state, stack, cycles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycles.append(" -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert not cycles, "\n".join(cycles)


def test_the_checker_sees_a_real_import():
    """The parser is not vacuous: it finds the edges everyone knows are there."""
    graph = _graph()
    assert "models.base" in graph["integrators.base"]
    assert "batching" in graph["sweeps.run"]
    assert "registry" in graph["scene"] and "models.base" in graph["rod3d.model"]


def test_every_equation_the_code_cites_is_in_docs_physics():
    """The docstrings cite equations (P1…) and sections (§n) of docs/physics.md: each must exist
    there, and the document must be in the repository."""
    import re

    doc = (PKG.parent / "docs" / "physics.md").read_text()
    labels = {a or b for a, b in re.findall(r"\(P(\d+)\)|\\tag\{P(\d+)\}", doc)}  # "(P1)" or MathJax's \tag{P1}
    sections = set(re.findall(r"^## (\d+)\.", doc, flags=re.M))
    cited_p, cited_s = set(), set()
    for f in PKG.rglob("*.py"):
        text = f.read_text()
        cited_p |= set(re.findall(r"\bP(\d{1,2})\b", text))
        cited_s |= set(re.findall(r"§(\d+)", text))
    assert cited_p and cited_s
    assert cited_p <= labels, f"cited but not in docs/physics.md: P{sorted(cited_p - labels)}"
    assert cited_s <= sections, f"cited but not in docs/physics.md: §{sorted(cited_s - sections)}"
