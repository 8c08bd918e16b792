"""The README: short, without history, its quickstart run as written, its links alive.

The Quickstart section's blocks run in order, in one Python namespace, in a fresh
temporary working folder: a ```` ```python ```` block is executed (each
``print(...)  # TEXT`` line must print TEXT), a ```` ```toml ```` block whose first line
is ``# file: NAME.toml`` is written as NAME.toml, and a ```` ```console ```` block's
``$ clik ...`` lines run through :func:`clik.cli.main` and must exit 0. The runs'
``completed`` is then checked against what it promises: distances, joint ranges, speeds.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shlex
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import clik
from clik import cli

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
MAX_LINES = 150
# 7 to 40 hex digits with at least one digit and one letter a-f: a commit hash, not a
# number (1000000) or a word ("defaced").
COMMIT_HASH = re.compile(r"\b(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b", re.I)
BLOCK = re.compile(r"^```(?P<lang>\w*)\n(?P<text>.*?)^```$", re.M | re.S)
LINK = re.compile(r"\]\((?P<target>[^)\s]+)\)")
FILE_LINE = re.compile(r"^#\s*file:\s*(?P<name>[\w.-]+\.toml)\s*$")
PRINT_LINE = re.compile(r"^print\(.*\)\s+#\s(?P<expected>.+)$")
OBSTACLE_THRESHOLD = 0.03  # [m] the quickstart's obstacle threshold
DISTANCE_SLACK = 1e-3  # [m] how far inside its threshold a link may be when a row activates


def readme() -> str:
    """The README's text."""
    return README.read_text(encoding="utf-8")


def section(markdown: str, title: str) -> str:
    """The text of the ``## title`` section (up to the next ``## `` heading)."""
    match = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", markdown, re.M | re.S)
    assert match is not None, f"README has no '## {title}' section"
    return match.group(1)


def expected_prints(code: str) -> list[str]:
    """What a Python block says it prints: the comments of its one-line ``print`` calls."""
    return [m.group("expected").strip() for m in map(PRINT_LINE.match, code.splitlines()) if m]


def run_console(text: str) -> list[int]:
    """Run a console block's ``$ clik ...`` lines through the CLI; their exit codes."""
    codes = []
    for line in text.splitlines():
        if line.startswith("$ clik "):
            codes.append(cli.main(shlex.split(line[len("$ clik ") :], comments=True)))
    return codes


@contextlib.contextmanager
def working_folder(path: Path) -> Iterator[None]:
    """Run in ``path``, then come back."""
    before = Path.cwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(before)


@pytest.fixture(scope="module")
def quickstart(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The Quickstart's blocks run once: its namespace, prints, exit codes and folder."""
    folder = tmp_path_factory.mktemp("readme")
    namespace: dict[str, Any] = {"__name__": "__readme__"}
    printed: list[tuple[list[str], list[str]]] = []  # (expected, got) per Python block
    codes: list[int] = []
    langs = []
    with working_folder(folder):
        for match in BLOCK.finditer(section(readme(), "Quickstart")):
            lang, text = match.group("lang"), match.group("text")
            langs.append(lang)
            if lang == "python":
                out = io.StringIO()
                with contextlib.redirect_stdout(out):
                    exec(compile(text, "README.md (Quickstart)", "exec"), namespace)
                printed.append((expected_prints(text), out.getvalue().splitlines()))
            elif lang == "toml" and (name := FILE_LINE.match(text.splitlines()[0])):
                (folder / name.group("name")).write_text(text, encoding="utf-8")
            elif lang == "console":
                codes.extend(run_console(text))
    return {"ns": namespace, "printed": printed, "codes": codes, "langs": langs, "dir": folder}


def test_readme_is_short() -> None:
    lines = readme().splitlines()
    assert len(lines) <= MAX_LINES, f"README.md has {len(lines)} lines, at most {MAX_LINES}"


def test_readme_has_no_commit_hashes_or_history() -> None:
    text = readme()
    assert COMMIT_HASH.findall(text) == []
    assert re.search(r"\bcommit\b", text, re.I) is None


def test_readme_local_links_resolve() -> None:
    targets = [m.group("target") for m in LINK.finditer(readme())]
    local = [t.split("#")[0] for t in targets if not re.match(r"[a-z]+:", t) and t[0] != "#"]
    assert local, "README links to no local file"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert missing == []


def test_readme_picture_is_committed_png() -> None:
    images = re.findall(r"!\[[^\]]*\]\((?P<target>[^)]+)\)", readme())
    assert images, "README shows no picture of a run"
    for image in images:
        assert image.startswith("docs/images/") and image.endswith(".png")
        assert (ROOT / image).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_quickstart_has_python_and_clik_solve(quickstart: dict[str, Any]) -> None:
    assert "python" in quickstart["langs"] and "console" in quickstart["langs"]
    assert "$ clik solve " in section(readme(), "Quickstart")


def test_quickstart_prints_what_it_says(quickstart: dict[str, Any]) -> None:
    assert quickstart["printed"], "the Quickstart has no Python block"
    for expected, got in quickstart["printed"]:
        assert expected, "a Python block prints nothing it promises"
        assert got == expected


def test_quickstart_python_run_keeps_its_promises(quickstart: dict[str, Any]) -> None:
    result = quickstart["ns"]["result"]
    robot = quickstart["ns"]["robot"]
    summary = result.summary()
    assert result.status == "completed" and summary["violations"] == []
    assert summary["min_obstacle_distance"] > OBSTACLE_THRESHOLD - DISTANCE_SLACK
    assert summary["max_velocity_ratio"] <= 1.0
    assert np.all(result.joint_min >= robot.model.lowerPositionLimit)
    assert np.all(result.joint_max <= robot.model.upperPositionLimit)
    saved = clik.TrackingResult.load(quickstart["dir"] / "run.npz")
    np.testing.assert_array_equal(saved.q, result.q)


def test_quickstart_clik_solve_keeps_its_promises(quickstart: dict[str, Any]) -> None:
    assert quickstart["codes"] == [0]
    out = quickstart["dir"] / "run"
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "completed" and summary["violations"] == []
    assert summary["min_obstacle_distance"] > OBSTACLE_THRESHOLD - DISTANCE_SLACK
    assert summary["max_velocity_ratio"] <= 1.0
    robot = quickstart["ns"]["robot"]
    assert np.all(np.asarray(summary["joint_min"]) >= robot.model.lowerPositionLimit)
    assert np.all(np.asarray(summary["joint_max"]) <= robot.model.upperPositionLimit)
    for name in ("trajectory.npz", "tracking_error.png", "obstacle_distance.png", "joints.png"):
        assert (out / name).is_file(), name
    # the file and the Python block describe the same run
    assert summary["max_task_error"] == pytest.approx(quickstart["ns"]["result"].max_task_error)
