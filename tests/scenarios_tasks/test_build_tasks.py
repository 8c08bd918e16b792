"""``[[tasks]]`` and ``[[objectives]]`` built against the robot: starts, units, errors, a run."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import clik
from clik import ScenarioError
from clik.scenarios.runner import build
from tests.limits_check import assert_completed
from tests.scenarios_tasks.scenario_text import (
    HEAD,
    POSTURE,
    SOLVER,
    TIP,
    assert_refused,
    parse,
    planar,
)

ATOL = 1e-12
"""Tolerance on values that are copied or converted, not computed by a run."""

PANDA = """
name = "panda tasks"
[robot]
source = "panda"
lock = { panda_finger_joint2 = 0.0 }
[initial]
q = [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8, 0.02]
[[tasks]]
name = "hand"
kind = "position"
frame = "panda_hand"
[tasks.trajectory]
kind = "hold"
duration = 0.1
"""


def panda(tmp_path, *tables, solver=SOLVER):
    return parse(PANDA + "".join(tables) + solver, tmp_path)


def first_sample(run, i):
    """Goal ``i``'s reference at t = 0."""
    return run.goals[i].trajectory.sample(np.array([0.0]))


def test_a_posture_holds_the_start_by_default(tmp_path):
    run = build(planar(tmp_path, POSTURE))
    np.testing.assert_allclose(first_sample(run, 1).q[0], np.radians([180, -30, -90, -30]))
    no_initial = HEAD.replace("q = [180, -30, -90, -30]", "").replace('unit = "deg"', "")
    run = build(parse(no_initial + TIP + POSTURE + SOLVER, tmp_path))
    np.testing.assert_allclose(first_sample(run, 1).q[0], run.robot.q_reference, atol=ATOL)


def test_posture_waypoints_start_at_the_start_and_convert_degrees(tmp_path):
    table = POSTURE + (
        '[tasks.trajectory]\nkind = "waypoints"\nwaypoints = [[170, -20, -80, -20]]\n'
        'times = [0.25]\nunit = "deg"\n'
    )
    run = build(planar(tmp_path, table))
    path = run.goals[1].trajectory
    np.testing.assert_allclose(path.times, [0.0, 0.25])
    np.testing.assert_allclose(path.waypoints[0], np.radians([180, -30, -90, -30]), atol=ATOL)
    np.testing.assert_allclose(path.waypoints[1], np.radians([170, -20, -80, -20]), atol=ATOL)


def test_degrees_turn_revolute_joints_only(tmp_path):
    table = (
        '[[tasks]]\nname = "two"\nkind = "posture"\npriority = 2\n'
        'joints = ["panda_joint1", "panda_finger_joint1"]\n'
        '[tasks.trajectory]\nkind = "hold"\nvalues = [30, 0.03]\nunit = "deg"\nduration = 0.1\n'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.MimicJointWarning)
        run = build(panda(tmp_path, table))
    np.testing.assert_allclose(first_sample(run, 1).q[0], [math.radians(30.0), 0.03], atol=ATOL)
    assert run.goals[1].trajectory.duration == pytest.approx(0.1)


def test_relative_and_com_tasks_hold_where_they_start(tmp_path):
    relative = (
        '[[tasks]]\nname = "rel"\nkind = "pose"\nframe = "panda_hand"\n'
        'relative_to = "panda_link0"\n[tasks.trajectory]\nkind = "hold"\nduration = 0.1\n'
    )
    com = '[[tasks]]\nname = "com"\nkind = "com"\naxes = ["x", "y"]\npriority = 2\n'
    run = build(panda(tmp_path, relative, com))
    rel, com_task = run.goals[1].task, run.goals[2].task
    assert isinstance(rel, clik.RelativeTask) and isinstance(com_task, clik.ComTask)
    start = rel.placement(run.q0)
    ref = first_sample(run, 1)
    np.testing.assert_allclose(ref.position[0], start.translation, atol=ATOL)
    np.testing.assert_allclose(ref.rotation[0], start.rotation, atol=ATOL)
    np.testing.assert_allclose(
        first_sample(run, 2).position[0], com_task.position(run.q0), atol=ATOL
    )
    assert com_task.axes == ["x", "y"]


def test_an_objective_posture_in_degrees(tmp_path):
    objective = (
        '[[objectives]]\nkind = "posture"\ngain = 2.0\nposture = [170, -20, -80, -20]\n'
        'unit = "deg"\npriority = 1\n'
    )
    run = build(planar(tmp_path, objective))
    (obj,) = run.tracker.objectives
    assert obj.kind == "posture" and obj.gain == 2.0 and obj.priority == 1
    np.testing.assert_allclose(obj.posture, np.radians([170, -20, -80, -20]), atol=ATOL)


BUILD_ERRORS = [
    (
        '[[tasks]]\nname = "rel"\nkind = "position"\nframe = "link2"\nrelative_to = "nope"\n'
        '[tasks.trajectory]\nkind = "hold"\nduration = 0.1\n',
        "tasks[1].relative_to",
        "frame 'nope' not found; available frames:",
    ),
    (
        '[[tasks]]\nname = "rel"\nkind = "position"\nframe = "nope"\nrelative_to = "link1"\n'
        '[tasks.trajectory]\nkind = "hold"\nduration = 0.1\n',
        "tasks[1].frame",
        "frame 'nope' not found",
    ),
    (
        '[[tasks]]\nname = "rel"\nkind = "position"\nframe = "tip"\nrelative_to = "tip"\n'
        '[tasks.trajectory]\nkind = "hold"\nduration = 0.1\n',
        "tasks[1].relative_to",
        "a frame other than 'tip'",
    ),
    (
        POSTURE + '[tasks.trajectory]\nkind = "hold"\nvalues = [1.0, 2.0, 3.0]\n',
        "tasks[1].trajectory.values",
        "4 values, one per joint of the posture task (joint1, joint2, joint3, joint4)",
    ),
    (
        POSTURE + 'joints = ["joint1"]\n'
        '[tasks.trajectory]\nkind = "waypoints"\nwaypoints = [[1.0, 2.0]]\nduration = 1.0\n',
        "tasks[1].trajectory.waypoints[0]",
        "1 values, one per joint of the posture task (joint1)",
    ),
    (POSTURE + 'joints = ["joint9"]\n', "tasks[1].joints", "joint9"),
    (POSTURE + 'joints = ["joint1", "joint1"]\n', "tasks[1].joints", "distinct joint names"),
    ('[[tasks]]\nname = "com"\nkind = "com"\n', "tasks[1].kind", "links have mass"),
    (
        TIP.replace('name = "tip"', 'name = "t2"').replace('"tip"', '"link9"'),
        "tasks[1].frame",
        "frame 'link9' not found",
    ),
    (
        '[[objectives]]\nkind = "posture"\ngain = 1.0\nposture = [0.0, 1.0]\n',
        "objectives[0].posture",
        "",
    ),
]


@pytest.mark.parametrize(("tables", "key", "words"), BUILD_ERRORS)
def test_what_the_robot_refuses_names_its_key(tmp_path, tables, key, words):
    assert_refused(lambda: build(planar(tmp_path, tables)), key, words)


def test_a_gain_per_row_of_the_wrong_length_names_the_task(tmp_path):
    with pytest.raises(ScenarioError) as info:
        build(planar(tmp_path, POSTURE.replace("gain = 10.0", "gain = [1.0, 2.0]")))
    assert info.value.key == "tasks[1].gain"


def test_a_planar_run_with_a_posture_and_an_objective(tmp_path):
    objective = '[[objectives]]\nkind = "joint_centering"\ngain = 1.0\n'
    run = build(planar(tmp_path, POSTURE, objective))
    result = run.execute()
    assert_completed(result)
    assert list(result.task_errors) == ["tip", "posture"]
    tip, posture = result.task_errors["tip"], result.task_errors["posture"]
    assert tip["kind"] == "position" and tip["priority"] == 1 and tip["max"] < 1e-3
    assert posture["kind"] == "posture" and posture["priority"] == 2
    assert posture["final"] > 0.0  # it gives way to the tip: the tip's line moves every joint
    assert result.info["task_units"] == {"tip": "m", "posture": "rad"}
    assert result.summary()["task_errors"]["posture"]["final"] == posture["final"]
