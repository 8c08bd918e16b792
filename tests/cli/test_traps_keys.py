"""A typo on a required key names the misspelt key (issue 27), as a typo on an optional one does.

Each test gives the message the user now gets from ``clik solve``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from clik.cli import main
from clik.errors import ScenarioError
from clik.scenarios import scenario_path
from clik.scenarios.scenario import load_scenario

CASE = scenario_path("case_study_obstacle").read_text()

CIRCLE = """
[robot]
source = "planar4r"

[task]
frame = "tip"
kind = "position"
axes = ["x", "y"]

[trajectory]
kind = "circle"
center = [0.6, 0.0, 0.0]
duration = 0.5
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "old", "new", "message"),
    [
        (
            CASE,
            "duration = 3.0\ncruise_speed = 0.12",
            "duraton = 3.0",
            "trajectory.duraton: unknown key; did you mean `duration`? (`duration` is needed)",
        ),
        (
            CASE,
            "radius = 0.0",
            "raduis = 0.0",
            "obstacles[0].raduis: unknown key; did you mean `radius`? (`radius` is needed)",
        ),
        (
            CIRCLE,
            "center =",
            "centre =",
            "trajectory.centre: unknown key; did you mean `center`? (`center` is needed)",
        ),
    ],
)
def test_typo_on_a_required_key_names_the_typo(tmp_path, capsys, text, old, new, message):
    assert old in text
    path = write(tmp_path, text.replace(old, new, 1))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2  # bad input
    assert capsys.readouterr().err.strip() == f"clik: error: {path}: {message}"
    assert not (tmp_path / "out").exists()


def test_typo_on_an_optional_key_suggests_the_key(tmp_path):
    path = write(tmp_path, CIRCLE.replace("duration = 0.5", "duration = 0.5\nnormale = [0, 0, 1]"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.key == "trajectory.normale"
    assert info.value.expected.startswith("unknown key; did you mean `normal`? valid keys here: ")


def test_a_missing_key_without_a_lookalike_is_said_missing(tmp_path):
    path = write(tmp_path, CIRCLE.replace("center = [0.6, 0.0, 0.0]\n", "colour = 1\n"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.key == "trajectory.center"
    assert info.value.expected == "required key is missing"
