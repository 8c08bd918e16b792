"""The documentation site builds strictly: ``mkdocs build --strict`` into a temporary folder.

Strict mode fails on a broken link between pages, a page missing from the navigation,
a ``::: clik.NAME`` API entry that does not resolve, a docstring that documents a
parameter the signature does not have, or a CLI reference that cannot be generated.

Needs the ``docs`` extra (``pip install -e ".[docs]"``; ``make test`` installs it).
Without it the test is skipped, except on CI (``CI=true``, as ``.ci/run`` sets it), where
it fails: a CI run must not pass with the site unchecked.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
API_NAMES = (
    "clik.Robot",
    "clik.Task",
    "clik.Goal",
    "clik.track",
    "clik.solve",
    "clik.TrackingResult",
    "clik.Controller",
    "clik.trajectory.Line",
    "clik.constraints.ConstraintSet",
    "clik.errors.ClikError",
    "clik.errors.InputError",
)
"""Anchors the API page must have (a sample of the public API)."""
TOOLS = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")


def on_ci() -> bool:
    """Whether this is a CI run: ``CI`` set to ``true`` (or ``1``, ``yes``)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def missing() -> str | None:
    """The first documentation tool that is not installed, or None."""
    for module in TOOLS:
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if not found:
            return f"no {module}: pip install -e '.[docs]' (make test installs it)"
    return None


def require_tools() -> None:
    """Skip when the site cannot be built here; on CI fail instead."""
    problem = missing()
    if problem is None:
        return
    if on_ci():
        pytest.fail(f"CI={os.environ['CI']}: the site must build, but {problem}", pytrace=False)
    pytest.skip(problem)


@pytest.mark.slow
def test_the_site_builds_strictly(tmp_path: Path) -> None:
    require_tools()
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    assert (site / "index.html").exists()
    cli = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    for command in ("clik solve", "clik sweep", "clik reach", "--export-every"):
        assert command in cli, f"the CLI reference lacks {command!r}"
    api = (site / "reference" / "api" / "index.html").read_text(encoding="utf-8")
    for name in API_NAMES:
        assert f'id="{name}"' in api, f"the API reference lacks {name}"


def test_a_missing_tool_skips_here_and_fails_on_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(f"{__name__}.TOOLS", ("no_such_docs_tool",))
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception, match="no_such_docs_tool"):
        require_tools()
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="the site must build"):
        require_tools()
