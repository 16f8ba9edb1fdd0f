"""The shape of the package (issue: one rollout loop of plug-ins): an acyclic import graph, imports
at module level (inside functions only for optional dependencies), files of at most 400 lines, and
a loop that stays about 40 lines. Pure: reads the source, imports nothing of the package."""
from __future__ import annotations

import ast
import inspect
import pathlib

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1] / "sumo_avoid"
OPTIONAL = {"dask", "pyarrow", "ctypes", "resource"}  # extras and platform-specific standard modules


def _modules() -> dict[str, pathlib.Path]:
    out = {}
    for f in PKG.rglob("*.py"):
        parts = ["sumo_avoid", *f.relative_to(PKG).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


def _imports(tree: ast.AST, mods: dict) -> set[str]:
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name in mods}
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("sumo_avoid"):
            assert node.level == 0, "relative import"
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                found.add(sub if sub in mods else node.module)
    return found


def import_graph() -> dict[str, set[str]]:
    mods = _modules()
    return {m: _imports(ast.parse(f.read_text()), mods) - {m} for m, f in mods.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str):
        state[m] = 1
        stack.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state:
                found = visit(n)
                if found:
                    return found
        state[m] = 2
        stack.pop()
        return None

    for m in sorted(graph):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def test_find_cycle_sees_a_cycle_and_a_dag():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_the_package_import_graph_is_acyclic():
    assert find_cycle(import_graph()) is None


def test_imports_inside_functions_only_for_optional_dependencies():
    bad = []
    for m, f in _modules().items():
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for sub in ast.walk(node):
                    if isinstance(sub, (ast.Import, ast.ImportFrom)):
                        name = sub.module if isinstance(sub, ast.ImportFrom) else sub.names[0].name
                        if name.split(".")[0] not in OPTIONAL:
                            bad.append(f"{m}:{sub.lineno} {name}")
    assert bad == []


@pytest.mark.parametrize("path", sorted(PKG.rglob("*.py")), ids=lambda p: str(p.relative_to(PKG)))
def test_no_file_over_400_lines(path):
    assert len(path.read_text().splitlines()) <= 400


def test_the_loop_is_short_and_knows_no_feature():
    from sumo_avoid.rollout.loop import rollout

    src = inspect.getsource(rollout)
    assert len(src.splitlines()) <= 45
    for word in ("radar", "flocking", "danger", "arena", "relaxation", "getattr", "hasattr", "isinstance"):
        assert word not in src


def test_tests_mirror_the_package():
    """tests/<sub>/ exists only for a subpackage sumo_avoid/<sub>/; every subpackage that holds code
    has its folder of tests (top-level modules such as cli.py are tested in tests/ itself; tests/errors/
    is the bad-input corpus over every command, docs/errors.md)."""
    tests = PKG.parent / "tests"
    subpackages = {d.name for d in PKG.iterdir() if (d / "__init__.py").exists()}
    folders = {d.name for d in tests.iterdir() if d.is_dir() and any(d.glob("test_*.py"))} - {"errors"}
    assert folders <= subpackages, f"test folders without a subpackage: {sorted(folders - subpackages)}"
    assert subpackages - folders <= {"scenario"}, f"subpackages without tests: {sorted(subpackages - folders)}"
