"""The notebooks as committed: valid, stripped of outputs, and each asserting its numbers.

They are *executed* by ``pytest --nbmake notebooks/`` (``make test``); these
checks are static and fast.
"""

from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="pip install 'clik[test]' (nbformat)")

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
EXPECTED = ["01_case_study", "02_panda_obstacles", "03_your_urdf", "04_laws_and_gains"]
PRESENT = sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb"))


def read(name: str):
    return nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)


def test_the_four_notebooks_are_there():
    missing = sorted(set(EXPECTED) - set(PRESENT))
    assert not missing, f"notebooks missing: {missing}"


@pytest.mark.parametrize("name", PRESENT)
def test_notebook_is_valid_and_stripped(name):
    notebook = read(name)
    nbformat.validate(notebook)
    assert notebook.metadata["kernelspec"]["name"] == "python3"
    for i, cell in enumerate(notebook.cells):
        if cell.cell_type == "code":
            assert cell.outputs == [], f"{name}: cell {i} has outputs (strip them)"
            assert cell.execution_count is None, f"{name}: cell {i} has an execution count"


@pytest.mark.parametrize("name", PRESENT)
def test_notebook_asserts_its_headline_numbers(name):
    code = [c.source for c in read(name).cells if c.cell_type == "code"]
    assert any("\nassert " in f"\n{source}" for source in code), f"{name} asserts nothing"
    markdown = [c.source for c in read(name).cells if c.cell_type == "markdown"]
    assert markdown and markdown[0].startswith("# "), f"{name} has no title"
