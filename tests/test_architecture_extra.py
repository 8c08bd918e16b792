"""The shape of the package, continued: rooms, file sizes, a typed boundary.

To sit beside ``tests/test_architecture.py`` (as ``tests/test_architecture_extra.py``,
or pasted at its end: it reuses its ``ROOT``, ``MODULES``, ``GRAPH`` and ``cycles``).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.test_architecture import GRAPH, MODULES, PACKAGE, ROOT, cycles

ENGINE = ROOT / "src" / "engine"

MAX_TOP_LEVEL_MODULES = 12
"""Modules directly in ``clik/`` (``__init__.py`` and subpackages aside)."""

MAX_FILE_LINES = 500
"""Longest Python module under ``clik/`` and C++ source under ``src/engine/``."""

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
        for p in sorted(PACKAGE.rglob("__init__.py"))
        if not (p.read_text(encoding="utf-8").lstrip().startswith(('"""', 'r"""')))
    ]
    assert bare == []


@pytest.mark.parametrize("name", sorted(MODULES))
def test_python_module_within_500_lines(name):
    assert line_count(MODULES[name]) <= MAX_FILE_LINES


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
    assert sorted((cxx & python) - checked) == []
    assert cxx & python  # the scan finds the shared ones (STEP_BUDGET, ...)
