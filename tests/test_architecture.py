"""The shape of the package: imports that flow one way, short functions, the method shipped.

These checks read the source (``ast``), not the running package, so they see
imports under ``TYPE_CHECKING`` and inside functions too: a circle hidden there
is still a circle for a reader. Also: rooms (at most 12 top-level modules, every
subpackage documented, no circle between rooms), modules and C++ sources within 500
lines, no Python attribute read by name from C++, and every constant both engines
declare checked to agree (``tests/loop/test_engine_constants.py``).

The benchmark suite (``benchmarks/``, beside ``clik/``) keeps the same size, citation
and no-circle rules; no module of ``clik`` imports it, nor the tools it compares clik
with (pink, mink): clik imports and runs without them.
"""

from __future__ import annotations

import ast
import importlib
import re
from collections.abc import Mapping
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "clik"
BENCHMARKS = ROOT / "benchmarks"
METHOD = ROOT / "docs" / "method.md"

MAX_FUNCTION_LINES = 80
"""Longest function or method in ``clik/``, ``def`` line to last line."""

APPLICATIONS = (
    "clik.cli",
    "clik.commands",
    "clik.demo",
    "clik.sweep",
    "clik.viz",
    "clik.plot",
)
"""The floor above the core: they may import the core, never the other way round."""


def module_name(path: Path) -> str:
    """Dotted name of a module file under ``clik/`` (or ``benchmarks/``)."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}
BENCH_MODULES = {module_name(p): p for p in sorted(BENCHMARKS.rglob("*.py"))}
SOURCES = {**MODULES, **BENCH_MODULES}
"""Every Python module the size and citation rules read: clik's and the suite's."""


def all_imports(name: str, path: Path, known: Mapping[str, Path] = MODULES) -> set[str]:
    """Every module that module ``name`` imports, anywhere in its file, relative imports
    resolved (``from a import b`` counts as ``a.b`` when that is in ``known``, else ``a``)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parent, *([base] if base else [])])
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                found.add(sub if sub in known else base)
    return found


def imported(name: str, path: Path, known: Mapping[str, Path] = MODULES) -> set[str]:
    """The modules of ``known`` (default clik's) that module ``name`` imports."""
    return {m for m in all_imports(name, path, known) if m in known and m != name}


GRAPH = {name: imported(name, path) for name, path in MODULES.items()}
BENCH_GRAPH = {name: imported(name, path, BENCH_MODULES) for name, path in BENCH_MODULES.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle_among_clik_modules():
    assert cycles(GRAPH) == []


def test_no_import_circle_among_benchmark_modules():
    assert len(BENCH_GRAPH) > 10  # the suite is found (benchmarks/)
    assert cycles(BENCH_GRAPH) == []


NOT_FOR_CLIK = ("benchmarks", "pink", "mink")
"""Packages no module of ``clik`` may import: the benchmark suite (it lives beside the
package, in a checkout) and the peers it compares clik with. ``clik bench``
(:mod:`clik.commands.bench`) loads the suite by name at run time, from a checkout.
MuJoCo is not listed: it may become a dependency of MJCF loading (``clik.model``)."""


def forbidden_imports(name: str, path: Path) -> list[str]:
    """The imports of module ``name`` whose top-level package is in :data:`NOT_FOR_CLIK`."""
    return sorted(m for m in all_imports(name, path) if m.split(".")[0] in NOT_FOR_CLIK)


def test_the_forbidden_import_finder_finds_them(tmp_path):
    module = tmp_path / "m.py"
    module.write_text(
        "import pink\nfrom mink.tasks import FrameTask\nimport benchmarks.suite as s\n"
        "def f():\n    from benchmarks import suite\nimport numpy, clik\n"
    )
    assert forbidden_imports("clik.m", module) == [
        "benchmarks",
        "benchmarks.suite",
        "mink.tasks",
        "pink",
    ]


@pytest.mark.parametrize("name", sorted(MODULES))
def test_clik_imports_neither_the_benchmarks_nor_pink_nor_mink(name):
    assert forbidden_imports(name, MODULES[name]) == []


def _is_application(name: str) -> bool:
    return any(name == app or name.startswith(app + ".") for app in APPLICATIONS)


@pytest.mark.parametrize("name", sorted(n for n in GRAPH if not _is_application(n) and n != "clik"))
def test_core_modules_do_not_import_applications(name):
    assert not [m for m in GRAPH[name] if _is_application(m)]


def test_cli_is_imported_by_no_module():
    assert not [n for n, deps in GRAPH.items() if "clik.cli" in deps]


def long_functions(path: Path) -> list[tuple[str, int]]:
    """Functions of ``path`` longer than :data:`MAX_FUNCTION_LINES`, with their lengths."""
    tree = ast.parse(path.read_text(), str(path))
    return [
        (node.name, node.end_lineno - node.lineno + 1)
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno is not None
        and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES
    ]


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_functions_fit_on_a_screen(name):
    assert long_functions(SOURCES[name]) == []


CITATION = re.compile(r"(?<![\w)\]])\((\d{1,2})\)(?:\s*-\s*\((\d{1,2})\))?")
"""An equation number in parentheses, ``(13)``, or a range ``(13)-(15)``."""


def cited(text: str) -> set[int]:
    """Equation numbers cited in ``text`` (ranges expanded)."""
    numbers: set[int] = set()
    for first, last in CITATION.findall(text):
        numbers.update(range(int(first), int(last or first) + 1))
    return numbers


def test_citation_pattern():
    assert cited("law (10), eqs. (13)-(15) and rows (22)") == {10, 13, 14, 15, 22}
    assert cited("np.eye(4), f.read(1), x[0](2)") == set()


def test_every_equation_cited_in_clik_is_in_docs_method():
    in_code = set().union(*(cited(p.read_text()) for p in SOURCES.values()))
    assert in_code, "no citation found: the pattern is wrong"
    documented = cited(METHOD.read_text())
    assert sorted(in_code - documented) == []


def test_code_points_at_the_shipped_method():
    assert not [n for n, p in SOURCES.items() if "METHOD.md" in p.read_text()]
    readme = (ROOT / "README.md").read_text()
    assert "docs/method.md" in readme


# -- rooms, file sizes, a typed boundary, constants once --------------------------------

ENGINE = ROOT / "src" / "engine"

MAX_TOP_LEVEL_MODULES = 12
"""Modules directly in ``clik/`` (``__init__.py`` and subpackages aside)."""

MAX_FILE_LINES = 500
"""Longest Python module under ``clik/`` and ``benchmarks/``, and C++ source under
``src/engine/``."""

CXX_SUFFIXES = (".hpp", ".cpp", ".hxx", ".h")

CXX_SOURCES = sorted(p for p in ENGINE.rglob("*") if p.suffix in CXX_SUFFIXES)

ATTRIBUTE_BY_NAME = re.compile(r"""\battr\(\s*(["'])[^"']*\1\s*\)(?!\s*=[^=])""")
"""``obj.attr("name")`` (nanobind) in C++: a Python attribute read by its name. Setting
one (``m.attr("COAL_VERSION") = ...``, how the module exposes a constant) is not a read."""


def line_count(path: Path) -> int:
    """Lines of a text file."""
    return len(path.read_text(encoding="utf-8").splitlines())


def room(name: str) -> str:
    """The room of a module: ``clik.loop.tracking`` -> ``clik.loop`` (top-level: itself)."""
    return ".".join(name.split(".")[:2])


def test_at_most_twelve_top_level_modules():
    top = sorted(p.name for p in PACKAGE.glob("*.py") if p.name != "__init__.py")
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top


def test_every_subpackage_says_what_it_holds():
    bare = [
        str(p.relative_to(ROOT))
        for p in sorted([*PACKAGE.rglob("__init__.py"), *BENCHMARKS.rglob("__init__.py")])
        if not (p.read_text(encoding="utf-8").lstrip().startswith(('"""', 'r"""')))
    ]
    assert bare == []


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_python_module_within_500_lines(name):
    assert line_count(SOURCES[name]) <= MAX_FILE_LINES


@pytest.mark.parametrize("path", CXX_SOURCES, ids=lambda p: str(p.relative_to(ENGINE)))
def test_cpp_source_within_500_lines(path):
    assert line_count(path) <= MAX_FILE_LINES


def test_the_engine_sources_are_found():
    assert any(p.name == "bindings.cpp" for p in CXX_SOURCES)


def test_attribute_pattern():
    assert ATTRIBUTE_BY_NAME.search('double k = nb::cast<double>(obj.attr("gain"));')
    assert ATTRIBUTE_BY_NAME.search("obj.attr( 'gain' ).attr(\"x\")")
    assert ATTRIBUTE_BY_NAME.search('if (obj.attr("gain") == x) {')
    assert not ATTRIBUTE_BY_NAME.search('m.attr("COAL_VERSION") = COAL_VERSION;')
    assert not ATTRIBUTE_BY_NAME.search('nb::arg("gain")')


def test_cpp_reads_no_python_attribute_by_name():
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for path in CXX_SOURCES
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if ATTRIBUTE_BY_NAME.search(line)
    ]
    assert found == []


def test_rooms_import_one_way():
    """No circle between rooms either (``clik.loop`` -> ``clik.model`` and never back)."""
    rooms: dict[str, set[str]] = {}
    for name, deps in GRAPH.items():
        if name == "clik":
            continue  # the package's door imports every room
        rooms.setdefault(room(name), set()).update(
            room(d) for d in deps if d != "clik" and room(d) != room(name)
        )
    assert cycles(rooms) == []


CXX_CONSTANT = re.compile(
    r"\bconstexpr\s+(?:double|float|int|long|std::size_t|std::int\w+)\s+([A-Z][A-Z0-9_]+)\s*="
)
"""``constexpr double NAME = ...`` in the engine: a number (an alias of an enum is not)."""
PY_CONSTANT = re.compile(r"^([A-Z][A-Z0-9_]+)(?:\s*:\s*[^=]+)?\s*=", re.M)
"""A module-level ``NAME = ...`` in ``clik/``."""


def test_constant_pattern():
    assert CXX_CONSTANT.findall("constexpr double STEP_BUDGET = 0.02;") == ["STEP_BUDGET"]
    assert CXX_CONSTANT.findall("  constexpr int MAX_TASK_ROWS = 6;") == ["MAX_TASK_ROWS"]
    assert CXX_CONSTANT.findall("constexpr auto LWA = pinocchio::LOCAL_WORLD_ALIGNED;") == []
    assert PY_CONSTANT.findall("STEP_BUDGET = 0.02\nx = 1\nMAX: int = 3\n") == [
        "STEP_BUDGET",
        "MAX",
    ]


def test_every_constant_both_engines_declare_is_checked_to_agree():
    """A number declared in both languages is a row of the agreement test
    (tests/loop/test_engine_constants.py), which compares the engine's to Python's."""
    from tests.loop.test_engine_constants import SHARED

    cxx = {n for p in CXX_SOURCES for n in CXX_CONSTANT.findall(p.read_text(encoding="utf-8"))}
    python = {
        n for p in MODULES.values() for n in PY_CONSTANT.findall(p.read_text(encoding="utf-8"))
    }
    checked = {attribute for _, attribute in SHARED.values()}
    # a kind of task binds its own on its engine type (`_engine.<Kind>Goal.<NAME>`),
    # checked against its module's by tests/tasks/test_task_kinds.py
    engine = importlib.import_module("clik._engine")
    types = [getattr(engine, n) for n in dir(engine) if n.endswith("Goal")]
    checked |= {n for t in types for n in vars(t) if n.isupper()}
    assert sorted((cxx & python) - checked) == []
    assert cxx & python  # the scan finds the shared ones (STEP_BUDGET, ...)


# -- kinds of task: named only in their own modules ---------------------------------------


def task_kind_modules() -> dict[str, str]:
    """Each ``[[tasks]] kind`` name and the module of the class that reads it."""
    from clik.tasks.registry import TASK_KINDS

    return {name: kind.__module__ for kind in TASK_KINDS for name in kind.names}


def kind_names_compared(path: Path, names: set[str]) -> list[tuple[int, str]]:
    """``(line, name)`` of each task-kind name compared as a string literal in ``path``
    (``x == "posture"``, ``kind in ("com", ...)``, ``x != "pose"``)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if not isinstance(node, ast.Compare):
            continue
        for side in [node.left, *node.comparators]:
            items = side.elts if isinstance(side, ast.Tuple | ast.List | ast.Set) else [side]
            for item in items:
                if isinstance(item, ast.Constant) and item.value in names:
                    found.append((node.lineno, str(item.value)))
    return found


def test_the_kind_name_pattern(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text('if kind == "posture" or kind in ("com", "x"):\n    pass\nkind = "pose"\n')
    assert kind_names_compared(probe, {"posture", "com", "pose"}) == [(1, "posture"), (1, "com")]


def test_a_task_kind_is_named_only_in_its_own_module():
    """No module compares a task kind's name as a string but the kind's own: the loop, the
    laws, the controller, the scenarios, the summary and the views ask the kind."""
    owners = task_kind_modules()
    found = [
        f"{name}:{line}: {kind!r}"
        for name, path in MODULES.items()
        for line, kind in kind_names_compared(path, set(owners))
        if owners[kind] != name
    ]
    assert found == []


def test_every_task_kind_is_registered_and_whole():
    """Every BaseTask class under clik/tasks is in the registry, with no abstract part left."""
    import inspect

    from clik.tasks.kind import BaseTask
    from clik.tasks.registry import TASK_KINDS

    defined = {
        cls
        for name in MODULES
        if name.startswith("clik.tasks.")
        for cls in vars(__import__(name, fromlist=["_"])).values()
        if inspect.isclass(cls)
        and issubclass(cls, BaseTask)
        and cls is not BaseTask
        and cls.__module__ == name
    }
    assert defined == set(TASK_KINDS)
    assert [k.__name__ for k in TASK_KINDS if inspect.isabstract(k)] == []
