"""Every warning clik emits is a ``clik.ClikWarning``, exported by ``clik`` and documented.

The classes are found by importing every module of the package and walking
``Warning``'s subclasses; the ``warnings.warn`` calls by reading the source (``ast``),
so a call on a path no test runs is checked too.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.constraints.joint_thresholds import ThresholdCapWarning, warn_capped

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "clik"
ERRORS_PAGE = ROOT / "docs" / "reference" / "errors.md"

RELAYS = {("clik.sweep.reach", "_rewarn")}
"""Functions that re-emit warnings caught elsewhere (a Dask worker's), keeping their class:
their ``warnings.warn`` passes a warning built from the caught category, not a clik class."""


def module_name(path: Path) -> str:
    """Dotted name of a module file under ``clik/``."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def clik_warning_classes() -> list[type[Warning]]:
    """Every ``Warning`` subclass defined in a module of ``clik`` (each module imported)."""
    # the package's own folder: an editable install's clik.__path__ may hold more entries
    for module in pkgutil.walk_packages([str(PACKAGE)], "clik."):
        importlib.import_module(module.name)

    def subclasses(cls: type) -> list[type]:
        return [c for sub in cls.__subclasses__() for c in (sub, *subclasses(sub))]

    found = {c for c in subclasses(Warning) if c.__module__.split(".")[0] == "clik"}
    return sorted(found, key=lambda c: c.__name__)


CLASSES = clik_warning_classes()


def warnings_section() -> str:
    """The "Warnings" section of the errors page."""
    text = ERRORS_PAGE.read_text(encoding="utf-8")
    return text.split("\n## Warnings\n", 1)[1].split("\n## ", 1)[0]


def test_the_walk_finds_the_warnings():
    assert clik.ClikWarning in CLASSES
    assert {"StartWarning", "ReachWarning", "XacroWarning"} <= {c.__name__ for c in CLASSES}


def test_clik_warning_is_a_user_warning():
    assert issubclass(clik.ClikWarning, UserWarning)
    assert not issubclass(clik.ClikWarning, clik.ClikError)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_warning_class_is_a_clik_warning(cls):
    assert issubclass(cls, clik.ClikWarning), f"{cls.__module__}.{cls.__name__}"


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_warning_class_is_exported_by_clik(cls):
    assert cls.__name__ in clik.__all__
    assert getattr(clik, cls.__name__) is cls


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_warning_class_is_on_the_errors_page(cls):
    if cls is clik.ClikWarning:
        assert "`clik.ClikWarning`" in warnings_section()
        return
    rows = [r for r in warnings_section().splitlines() if r.startswith(f"| `{cls.__name__}` |")]
    assert len(rows) == 1, f"{cls.__name__} is not in {ERRORS_PAGE.name}'s Warnings table"


def test_the_errors_page_names_no_other_warning():
    rows = [r for r in warnings_section().splitlines() if r.startswith("| `")]
    named = {r.split("`")[1] for r in rows}
    assert named == {c.__name__ for c in CLASSES} - {"ClikWarning"}


def warn_calls(tree: ast.Module) -> list[tuple[str, ast.Call]]:
    """``(enclosing function, call)`` of every ``warnings.warn`` / ``warn_explicit`` call."""
    direct = {
        alias.asname or alias.name
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.module == "warnings"
        for alias in node.names
        if alias.name in ("warn", "warn_explicit")
    }
    found: list[tuple[str, ast.Call]] = []

    def visit(node: ast.AST, function: str) -> None:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            function = node.name
        if isinstance(node, ast.Call):
            f = node.func
            by_module = (
                isinstance(f, ast.Attribute)
                and f.attr in ("warn", "warn_explicit")
                and isinstance(f.value, ast.Name)
                and f.value.id == "warnings"
            )
            if by_module or (isinstance(f, ast.Name) and f.id in direct):
                found.append((function, node))
        for child in ast.iter_child_nodes(node):
            visit(child, function)

    visit(tree, "")
    return found


def category_of(call: ast.Call, module: object) -> object:
    """The warning class a ``warnings.warn`` call passes, resolved in its module.

    ``warn(message, Category)``, ``warn(message, category=Category)`` or
    ``warn(Category(...))``; anything else (a bare message: ``UserWarning``) is None.
    """
    category = next((k.value for k in call.keywords if k.arg == "category"), None)
    if category is None and len(call.args) >= 2:
        category = call.args[1]
    if category is None and call.args and isinstance(call.args[0], ast.Call):
        category = call.args[0].func
    if isinstance(category, ast.Name):
        return getattr(module, category.id, None)
    return None


CALLS = [
    (module_name(path), function, call)
    for path in sorted(PACKAGE.rglob("*.py"))
    for function, call in warn_calls(ast.parse(path.read_text(encoding="utf-8"), str(path)))
]


def test_the_scan_finds_the_warn_calls():
    assert len(CALLS) >= 15
    assert {(m, f) for m, f, _ in CALLS} >= RELAYS  # no stale relay


@pytest.mark.parametrize(
    ("module", "function", "call"),
    [c for c in CALLS if (c[0], c[1]) not in RELAYS],
    ids=lambda v: v if isinstance(v, str) else str(getattr(v, "lineno", "")),
)
def test_every_warn_call_passes_a_clik_warning_class(module, function, call):
    category = category_of(call, importlib.import_module(module))
    where = f"{module}.{function}, line {call.lineno}"
    assert isinstance(category, type), f"{where}: no named warning class (a bare UserWarning?)"
    assert issubclass(category, clik.ClikWarning), f"{where}: {category.__name__}"


def test_pyprojects_filters_name_clik_warnings_that_exist():
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    filters = settings["tool"]["pytest"]["ini_options"].get("filterwarnings", [])
    for entry in filters:
        parts = entry.split(":")
        category = parts[2] if len(parts) > 2 else ""
        if not category.startswith("clik."):
            continue
        module, _, name = category.rpartition(".")
        cls = getattr(importlib.import_module(module), name, None)
        assert isinstance(cls, type) and issubclass(cls, clik.ClikWarning), entry


def test_one_filter_on_the_root_escalates_a_warning_clik_emits():
    """The errors page's recipe: ``filterwarnings("error", category=clik.ClikWarning)``."""
    asked, applied = np.array([5.0]), np.array([0.5])
    with warnings.catch_warnings():
        warnings.filterwarnings("error", category=clik.ClikWarning)
        with pytest.raises(ThresholdCapWarning, match="capped at a quarter"):
            warn_capped(["j"], ["revolute"], asked, applied, prismatic=False)
    with warnings.catch_warnings():
        warnings.filterwarnings("error", category=clik.ClikWarning)
        warnings.filterwarnings("ignore", category=ThresholdCapWarning)
        warn_capped(["j"], ["revolute"], asked, applied, prismatic=False)  # silenced
