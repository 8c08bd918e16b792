"""One quick bench run shared by the bench tests (it takes several seconds)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from benchmarks.suite import run_bench


@pytest.fixture(scope="session")
def quick(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """``clik bench --quick``'s output folder and the report it returned."""
    out = tmp_path_factory.mktemp("bench")
    returned = run_bench(out, quick=True)
    return out, returned
