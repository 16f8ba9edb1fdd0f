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


def _type_only(tree: ast.AST) -> set[int]:
    """ids of the import nodes under ``if TYPE_CHECKING:`` (annotations only: no runtime dependency)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            out |= {id(sub) for stmt in node.body for sub in ast.walk(stmt)}
    return out


def _imports(tree: ast.AST, mods: dict, runtime_only: bool = False) -> set[str]:
    found = set()
    skip = _type_only(tree) if runtime_only else set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name in mods}
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("sumo_avoid"):
            assert node.level == 0, "relative import"
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                found.add(sub if sub in mods else node.module)
    return found


def import_graph(runtime_only: bool = False) -> dict[str, set[str]]:
    mods = _modules()
    return {m: _imports(ast.parse(f.read_text()), mods, runtime_only) - {m} for m, f in mods.items()}


# The order of the packages, lowest first: a module may import its own package and packages of lower
# levels, never a higher one nor another package of its own level. Imports under ``if TYPE_CHECKING:``
# are annotations only and not counted (core's contracts name the road's types that way).
ORDER = (
    ("core",),  # contracts, config, generic geometry: no road, no SUMO
    ("road",),  # the net as data (read with sumolib), route records, Frenet frame, right of way, rules of the road
    ("sumo",),  # libsumo: the simulation, its devices and inputs
    ("sensing",),
    ("safety", "actuation", "planning"),
    ("control",),
    ("rollout",),  # the loop, ego book-keeping, the recording
    ("metrics",),  # from the recording and the road only
    ("plots",),
    ("scenario",),
    ("runs",),  # one run: runner, outputs, child processes
    ("watch",),  # a finished run read back: viewer page, video, sumo-gui replay
    ("studies", "gym"),  # gym: environments stepping a run (optional extra [gym])
    ("cli",),
)
LEVEL = {pkg: i for i, pkgs in enumerate(ORDER) for pkg in pkgs}


def package_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def order_violations(graph: dict[str, set[str]]) -> list[str]:
    bad = []
    for m, deps in sorted(graph.items()):
        pm = package_of(m)
        for d in sorted(deps):
            pd = package_of(d)
            if pm is None or pd is None or pm == pd:
                continue
            if pm not in LEVEL or pd not in LEVEL:
                bad.append(f"{m} -> {d}: package not in ORDER")
            elif LEVEL[pd] >= LEVEL[pm]:
                bad.append(f"{m} -> {d}")
    return bad


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


def test_order_violations_sees_an_import_upwards_and_across():
    graph = {"sumo_avoid.core.a": {"sumo_avoid.road.b"}, "sumo_avoid.safety.c": {"sumo_avoid.planning.d"},
             "sumo_avoid.metrics.e": {"sumo_avoid.road.f", "sumo_avoid.metrics.g"}}
    assert order_violations(graph) == ["sumo_avoid.core.a -> sumo_avoid.road.b",
                                       "sumo_avoid.safety.c -> sumo_avoid.planning.d"]


def test_every_package_is_in_the_order():
    packages = {d.name for d in PKG.iterdir() if (d / "__init__.py").exists()} | {"cli"}
    assert packages == set(LEVEL)


def test_packages_import_only_lower_packages():
    assert order_violations(import_graph(runtime_only=True)) == []


def test_no_module_basename_in_two_packages():
    seen: dict[str, list[str]] = {}
    for f in PKG.rglob("*.py"):
        if f.name != "__init__.py":
            seen.setdefault(f.name, []).append(str(f.relative_to(PKG)))
    assert {n: p for n, p in seen.items() if len(p) > 1} == {}


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
