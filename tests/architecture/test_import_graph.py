"""The package's import graph has no cycle — counting every import: module level, inside functions and
under ``if TYPE_CHECKING:`` (a cycle hidden in any of those is still a cycle a reader must untangle)."""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

import fearguard

ROOT = Path(fearguard.__file__).parent


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def import_graph(root: Path = ROOT) -> tuple[nx.DiGraph, dict[str, int]]:
    """Edges module → package module it imports; also how many imports sit in functions / TYPE_CHECKING."""
    package = root.name
    modules = {_module_name(p, root): p for p in root.rglob("*.py")}
    graph = nx.DiGraph()
    graph.add_nodes_from(modules)
    counts = {"function": 0, "type_checking": 0, "module": 0}

    def target(name: str) -> str | None:  # the deepest fearguard module a dotted name refers to
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    for module, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        is_package = path.name == "__init__.py"
        kinds: dict[ast.AST, str] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                for inner in ast.walk(node):
                    kinds.setdefault(inner, "function")
            if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
                for inner in ast.walk(node):
                    kinds.setdefault(inner, "type_checking")
        for node in ast.walk(tree):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(module, is_package, node)
                names = [f"{base}.{a.name}" for a in node.names] or [base]
            for name in names:
                if name.split(".")[0] != package:
                    continue
                dest = target(name)
                if dest is not None and dest != module:
                    graph.add_edge(module, dest)
                    counts[kinds.get(node, "module")] += 1
    return graph, counts


def test_the_import_graph_of_the_whole_package_has_no_cycle() -> None:
    graph, counts = import_graph()
    assert counts["function"] + counts["type_checking"] + counts["module"] > 100  # the scan sees the package
    cycles = list(nx.simple_cycles(graph))
    assert cycles == [], "import cycles: " + "; ".join(" → ".join([*c, c[0]]) for c in sorted(cycles)[:10])


def test_the_scan_finds_cycles_hidden_in_functions_and_type_checking_blocks(tmp_path: Path) -> None:
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from pkg.sub import b\n")
    (pkg / "sub" / "b.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..c import X\n")
    (pkg / "c.py").write_text("import pkg.a\nimport os\n")
    graph, counts = import_graph(pkg)
    assert counts == {"function": 1, "type_checking": 1, "module": 1}
    cycles = list(nx.simple_cycles(graph))
    assert len(cycles) == 1 and set(cycles[0]) == {"pkg.a", "pkg.sub.b", "pkg.c"}
