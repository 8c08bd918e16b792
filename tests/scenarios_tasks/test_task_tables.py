"""``[[tasks]]`` and ``[[objectives]]`` as read from a file: every key, its default, its errors."""

from __future__ import annotations

import math

import pytest

from clik import ScenarioError
from clik.scenarios import scenario_path
from clik.scenarios.scenario import load_scenario
from clik.tasks.registry import kind_names
from tests.scenarios_tasks.scenario_text import (
    HEAD,
    POSTURE,
    SOLVER,
    TIP,
    assert_refused,
    parse,
    planar,
)

RELATIVE = """
[[tasks]]
name = "link2_in_link1"
kind = "pose"
frame = "link2"
relative_to = "link1"
axes = ["x", "rz"]
gain = [100.0, 200.0]
[tasks.trajectory]
kind = "hold"
duration = 0.1
goal_rpy = [0.0, 0.0, 10.0]
unit = "deg"
"""

WAYPOINTS = """
[[tasks]]
name = "elbow"
kind = "posture"
joints = ["joint2", "joint3"]
priority = 3
[tasks.trajectory]
kind = "waypoints"
waypoints = [[-30, -90], [-20, -80]]
times = [0.2, 0.5]
unit = "deg"
"""

COM = """
[[tasks]]
name = "com"
kind = "com"
axes = ["x", "y"]
priority = 2
"""

OBJECTIVES = """
[[objectives]]
kind = "joint_centering"
gain = 5.0
[[objectives]]
kind = "manipulability"
gain = 2.0
priority = 1
[[objectives]]
kind = "posture"
gain = 1.0
posture = [180, -30, -90, -30]
unit = "deg"
"""


def test_every_task_key_and_its_default(tmp_path):
    s = planar(tmp_path, RELATIVE, WAYPOINTS, COM, POSTURE, OBJECTIVES)
    tip, rel, elbow, com, posture = s.tasks
    assert [t["name"] for t in s.tasks] == ["tip", "link2_in_link1", "elbow", "com", "posture"]
    assert tip["kind"] == "position" and tip["frame"] == "tip" and tip["axes"] == ["x", "y"]
    assert tip["priority"] == 1 and tip["gain"] is None and tip["relative_to"] is None
    assert tip["trajectory"]["kind"] == "line" and tip["trajectory"]["goal"] == [0.8, -0.2, 0.0]
    assert rel["relative_to"] == "link1" and rel["axes"] == ["x", "rz"]
    assert rel["gain"] == [100.0, 200.0]
    assert rel["trajectory"]["goal_rpy"] == pytest.approx([0.0, 0.0, math.radians(10.0)])
    assert elbow["joints"] == ["joint2", "joint3"] and elbow["priority"] == 3
    assert elbow["trajectory"] == {
        "kind": "waypoints", "unit": "deg", "values": None,
        "waypoints": [[-30.0, -90.0], [-20.0, -80.0]], "times": [0.2, 0.5], "duration": 0.5,
    }  # fmt: skip
    assert com["axes"] == ["x", "y"]
    assert com["trajectory"] == {
        "kind": "hold", "start": None, "goal": None, "duration": 0.0, "goal_rpy": None,
    }  # fmt: skip
    assert posture["joints"] is None and posture["gain"] == 10.0 and posture["priority"] == 2
    assert posture["trajectory"]["kind"] == "hold" and posture["trajectory"]["values"] is None
    assert posture["trajectory"]["duration"] == 0.0 and posture["trajectory"]["unit"] == "rad"
    centering, manipulability, objective = s.objectives
    assert centering == {
        "kind": "joint_centering", "gain": 5.0, "priority": None, "posture": None, "unit": "rad",
    }  # fmt: skip
    assert manipulability["priority"] == 1
    assert objective["posture"] == [180.0, -30.0, -90.0, -30.0] and objective["unit"] == "deg"


def test_the_primary_task_is_the_first_world_frame_task_of_the_highest_priority(tmp_path):
    first = POSTURE.replace("priority = 2", "priority = 1")
    second = TIP.replace('"tip"', '"link3"')
    s = parse(HEAD + RELATIVE + first + TIP + second + SOLVER, tmp_path)
    assert s.task == {"frame": "tip", "kind": "position", "axes": ["x", "y"]}
    assert s.trajectory is s.tasks[2]["trajectory"]
    assert s.solver["engine"] == "python"


def test_posture_hold_values_and_duration(tmp_path):
    held = POSTURE + '[tasks.trajectory]\nkind = "hold"\nvalues = [3, -0.5, -1.5, -0.5]\n'
    s = planar(tmp_path, held.replace("gain = 10.0\n", "gain = 10.0\n") + "duration = 0.4\n")
    trajectory = s.tasks[1]["trajectory"]
    assert trajectory["values"] == [3.0, -0.5, -1.5, -0.5] and trajectory["duration"] == 0.4


def test_the_solver_step_is_checked_against_the_longest_task(tmp_path):
    slow = TIP.replace('name = "tip"', 'name = "slow"').replace("duration = 0.3", "duration = 50.0")
    s = planar(tmp_path, slow, solver=SOLVER.replace("dt = 0.001", "dt = 0.2"))
    assert s.solver["dt"] == 0.2  # 0.2 s > 0.3 s / 2 for "tip", but the run lasts 50 s


def test_a_single_task_scenario_is_unchanged():
    s = load_scenario(scenario_path("case_study_unconstrained_pinv"))
    assert s.tasks == [] and s.objectives == []
    assert s.task == {"frame": "tip", "kind": "position", "axes": ["x", "y"]}


def test_objectives_with_a_single_task(tmp_path):
    text = scenario_path("case_study_unconstrained_pinv").read_text()
    s = parse(text + '\n[[objectives]]\nkind = "joint_centering"\ngain = 3.0\n', tmp_path)
    assert s.tasks == [] and [o["kind"] for o in s.objectives] == ["joint_centering"]


ERRORS = [
    # (tables after the tip task, key, words in the message)
    (
        POSTURE.replace('kind = "posture"', 'kind = "joints"'),
        "tasks[1].kind",
        "expected one of 'position', 'orientation', 'pose', 'posture', 'com', "  # then the
        + "".join(f"'{name}', " for name in kind_names()[5:])  # kinds added since
        + "got 'joints'",
    ),
    (POSTURE.replace("priority = 2", "prority = 2"), "tasks[1].prority", "unknown key"),
    (POSTURE.replace('name = "posture"', 'nmae = "posture"'), "tasks[1].name", "required key"),
    (TIP.replace('frame = "tip"\n', ""), "tasks[1].frame", "required key is missing"),
    (TIP.replace('frame = "tip"', 'frame = "link1"'), "tasks[1].name", "a name no other task"),
    (POSTURE.replace("priority = 2", "priority = 0"), "tasks[1].priority", "integer >= 1"),
    (POSTURE.replace("gain = 10.0", "gain = 1e8"), "tasks[1].gain", "gain * solver.dt"),
    (POSTURE + 'frame = "tip"\n', "tasks[1].frame", "unknown key; valid keys here: gain"),
    (
        POSTURE + '[tasks.trajectory]\nkind = "line"\n',
        "tasks[1].trajectory.kind",
        "one of 'hold', 'waypoints'",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "hold"\nvalues = [1.0]\nunit = "grad"\n',
        "tasks[1].trajectory.unit",
        "one of 'rad', 'deg'",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "hold"\ngoal = [1.0, 0.0, 0.0]\n',
        "tasks[1].trajectory.goal",
        "unknown key",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "waypoints"\nwaypoints = [[1.0]]\n',
        "tasks[1].trajectory.duration",
        "a duration [s] or times",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "waypoints"\nwaypoints = [[1.0], [2.0]]\n'
        "times = [0.5, 0.5]\n",
        "tasks[1].trajectory.times",
        "2 increasing times > 0 [s]",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "waypoints"\nwaypoints = [[1.0, 2.0], [2.0]]\n'
        "duration = 1.0\n",
        "tasks[1].trajectory.waypoints[1]",
        "a list of 2 numbers",
    ),
    (COM.replace('["x", "y"]', '["x", "q"]'), "tasks[1].axes", "distinct names among"),
    (
        RELATIVE.replace('kind = "pose"', 'kind = "position"').replace('["x", "rz"]', '["x"]'),
        "tasks[1].trajectory.goal_rpy",
        "no goal_rpy: the task has no orientation rows",
    ),
    (
        TIP.replace('name = "tip"', 'name = "t2"').replace("[tasks.trajectory]", "[tasks.x]"),
        "tasks[1].trajectory",
        "required key is missing",
    ),
    (OBJECTIVES.replace('"manipulability"', '"speed"'), "objectives[1].kind", "'manipulability'"),
    (
        OBJECTIVES.replace("gain = 5.0\n", "gain = 5.0\nposture = [0.0]\n"),
        "objectives[0].posture",
        "unknown key",
    ),
    (OBJECTIVES.replace("gain = 5.0\n", ""), "objectives[0].gain", "required key is missing"),
    (
        "[constraints.velocity_limits]\nenabled = true\n",
        "constraints.velocity_limits.enabled",
        "false with [[tasks]]",
    ),
]


@pytest.mark.parametrize(("tables", "key", "words"), ERRORS)
def test_a_bad_table_names_its_key(tmp_path, tables, key, words):
    assert_refused(lambda: planar(tmp_path, tables), key, words)


def test_task_and_tasks_together_are_refused(tmp_path):
    single = '[task]\nframe = "tip"\n'
    with pytest.raises(ScenarioError) as info:
        planar(tmp_path, single)
    assert info.value.key == "task"
    assert "either [task] (one task) or [[tasks]] (several), not both" in info.value.expected
    with pytest.raises(ScenarioError) as info:
        planar(tmp_path, '[trajectory]\nkind = "hold"\nduration = 1.0\n')
    assert info.value.key == "trajectory" and "[tasks.trajectory]" in info.value.expected


def test_several_tasks_need_a_world_frame_task_at_the_highest_priority(tmp_path):
    with pytest.raises(ScenarioError) as info:
        parse(HEAD + RELATIVE + POSTURE + TIP.replace("[[tasks]]", "[[tasks]]\npriority = 2") +
              SOLVER, tmp_path)  # fmt: skip
    assert info.value.key == "tasks"
    assert "a frame task in the world" in info.value.expected and "priority 1" in str(info.value)


@pytest.mark.parametrize("law", ["transpose", "nonlinear"])
def test_laws_9_and_8_refuse_priority_levels_and_objectives(tmp_path, law):
    solver = SOLVER.replace('"pseudoinverse"', repr(law).replace("'", '"'))
    with pytest.raises(ScenarioError) as info:
        planar(tmp_path, POSTURE, solver=solver)
    assert info.value.key == "tasks[1].priority"
    assert f"solver.law = {law!r}" in info.value.expected
    with pytest.raises(ScenarioError) as info:
        planar(tmp_path, OBJECTIVES, solver=solver)
    assert info.value.key == "objectives[0]" and "needs law 'pseudoinverse'" in str(info.value)
    same_level = planar(tmp_path, POSTURE.replace("priority = 2", "priority = 1"), solver=solver)
    assert [t["priority"] for t in same_level.tasks] == [1, 1]
