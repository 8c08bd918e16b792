"""Scenario texts for the several-task tests: a planar base and its tables."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from clik import ScenarioError
from clik.scenarios.scenario import Scenario, parse_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

HEAD = """
name = "two tasks"
[robot]
source = "planar4r"
[initial]
q = [180, -30, -90, -30]
unit = "deg"
"""

TIP = """
[[tasks]]
name = "tip"
kind = "position"
frame = "tip"
axes = ["x", "y"]
[tasks.trajectory]
kind = "line"
goal = [0.8, -0.2, 0.0]
duration = 0.3
"""

POSTURE = """
[[tasks]]
name = "posture"
kind = "posture"
priority = 2
gain = 10.0
"""

SOLVER = """
[solver]
law = "pseudoinverse"
dt = 0.001
engine = "python"
"""


def parse(text: str, tmp_path: Path) -> Scenario:
    """``text`` parsed as the scenario file ``tmp_path / "s.toml"``."""
    return parse_scenario(tomllib.loads(text), tmp_path / "s.toml")


def planar(tmp_path: Path, *tables: str, solver: str = SOLVER) -> Scenario:
    """The planar arm's tip task, then ``tables``, then ``solver``."""
    return parse(HEAD + TIP + "".join(tables) + solver, tmp_path)


def assert_refused(make: Callable[[], object], key: str, words: str) -> None:
    """``make()`` raises a :class:`ScenarioError` at ``key`` whose message has ``words``."""
    with pytest.raises(ScenarioError) as info:
        make()
    assert info.value.key == key
    assert words in info.value.expected
