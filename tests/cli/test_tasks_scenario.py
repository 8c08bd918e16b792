"""The shipped several-task scenario (``baxter_two_hands``) through ``clik solve`` and the API."""

from __future__ import annotations

import contextlib
import io
import json

import pytest

from clik.cli import main
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from tests.limits_check import assert_completed, assert_summary_within_limits

SCENARIO = scenario_path("baxter_two_hands")
HANDS = ("left_hand", "right_hand")
HAND_TOL = 1e-6
"""Largest hand position error the example promises [m]."""
WIDTH_TOL = 1e-4
"""Largest error of the box's width (left hand in the right hand's frame) [m]."""


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """``clik solve`` on the example: exit code, summary.json, printed text."""
    out = tmp_path_factory.mktemp("baxter") / "out"
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        code = main(["solve", str(SCENARIO), "--out", str(out)])
    return code, json.loads((out / "summary.json").read_text()), text.getvalue()


def test_the_example_completes_with_every_task_reported(solved):
    code, summary, _ = solved
    assert code == 0 and summary["status"] == "completed", summary["reason"]
    errors = summary["task_errors"]
    assert list(errors) == ["left_hand", "right_hand", "box_width", "posture"]
    for hand in HANDS:
        assert errors[hand]["kind"] == "pose" and errors[hand]["priority"] == 1
        assert errors[hand]["max"] <= HAND_TOL and errors[hand]["final"] <= HAND_TOL
        assert errors[hand]["max_orientation"] <= HAND_TOL
    assert errors["box_width"]["kind"] == "position" and errors["box_width"]["max"] <= WIDTH_TOL
    assert errors["posture"]["kind"] == "posture" and errors["posture"]["priority"] == 2
    assert summary["info"]["task_units"]["posture"] == "rad"


def test_solve_prints_one_line_per_task(solved):
    _, summary, text = solved
    lines = [line for line in text.splitlines() if line.startswith("  task ")]
    assert len(lines) == 4
    for line, (name, e) in zip(lines, summary["task_errors"].items(), strict=True):
        assert line.split()[1:5] == [name, e["kind"], "priority", str(e["priority"])]
        assert f"max {e['max']:.3e} " in line and f"final {e['final']:.3e} " in line
    assert lines[0].endswith("rad") and "orientation max" in lines[0]
    assert lines[2].endswith(" m") and lines[3].endswith(" rad")


def test_the_example_is_within_the_robots_limits():
    run = build(SCENARIO)
    assert run.tracker.law == "pseudoinverse" and run.tracker.engine == "compiled"
    result = run.execute()
    assert_completed(result)
    assert_summary_within_limits(result.summary(), result.robot)
    for hand in HANDS:
        assert result.task_errors[hand]["max"] <= HAND_TOL
