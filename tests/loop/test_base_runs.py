"""Runs with a mobile or floating base (issue 26, part 3), in both engines.

tiago on a planar base reaches a hand line its arm alone cannot; talos on a floating
base holds both feet while a hand tracks a line. Each run is checked on its own numbers
and on independent forward kinematics of the recorded joints, and the two engines give
the same joint trajectories.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.loop.tracker import ReachWarning
from clik.model.base import BASE_JOINT
from clik.outputs.result import TrackingResult
from clik.scenarios.runner import run_scenario
from clik.trajectory import Line
from clik.viz.robot_layer import joint_path
from clik.viz.scene import build_scene
from clik.viz.target import rebuild_robot
from tests.base_goals import assert_feet_held_hand_tracked, feet_held_hand_line
from tests.limits_check import assert_completed

ENGINES = ("python", "compiled")
PARITY = 1e-9
"""Largest difference between the engines' recorded joints [m, rad or -]."""
TRACK = 1e-6
"""Largest position error [m] (and rotation error [rad]) over a whole run."""

TIAGO_ARM = {"torso_lift_joint"} | {f"arm_{i}_joint" for i in range(1, 8)}
TIAGO_Q = [0.15, 1.0, 0.0, -1.5, 1.5, 0.0, 0.0, 0.0]
"""Torso [m] and arm [rad]: the hand in front, the joints off their limits."""
REACH = np.array([1.2, 0.0, 0.0])
"""The hand's line, from its start [m]: beyond the arm's reach from a fixed base."""

TALOS_LOCK = {
    "gripper_left_joint": 0.0,
    "gripper_right_joint": 0.0,
    "head_1_joint": 0.0,
    "head_2_joint": 0.0,
    **{f"arm_right_{i}_joint": v for i, v in enumerate([-0.4, -0.24, 0, -0.6, 0, 0, 0.1], 1)},
}
"""talos' grippers, head and right arm locked (the run needs the legs, torso, left arm)."""


def tiago_lock() -> dict[str, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        names = clik.Robot.load("tiago").joint_names
    return {n: 0.0 for n in names if n not in TIAGO_ARM}


def run_both(**kwargs: object) -> dict[str, clik.TrackingResult]:
    return {engine: clik.track(engine=engine, **kwargs) for engine in ENGINES}  # type: ignore[arg-type]


def hand_line(robot: clik.Robot) -> tuple[clik.Task, Line, np.ndarray]:
    q0 = robot.q_reference
    q0[-len(TIAGO_Q) :] = TIAGO_Q
    task = clik.Task(robot, "arm_tool_link", "position")
    start = task.placement(q0).translation
    return task, Line(start, start + REACH, 3.0), q0


@pytest.fixture(scope="module")
def tiago_runs() -> dict[str, tuple[clik.Robot, dict[str, clik.TrackingResult]]]:
    lock = tiago_lock()
    out: dict[str, tuple[clik.Robot, dict[str, clik.TrackingResult]]] = {}
    for base in ("fixed", "planar"):
        robot = clik.Robot.load("tiago", lock=lock, base=base)
        task, line, q0 = hand_line(robot)
        if base == "fixed":  # warned before the run: the line is beyond the arm's reach
            with pytest.warns(ReachWarning, match="out of reach"):
                out[base] = (
                    robot,
                    run_both(task=task, trajectory=line, q0=q0, law="pseudoinverse", gain=500),
                )
            continue
        out[base] = (
            robot,
            run_both(task=task, trajectory=line, q0=q0, law="pseudoinverse", gain=500),
        )
    return out


def test_fixed_tiago_cannot_reach_the_line(tiago_runs) -> None:
    _, runs = tiago_runs["fixed"]
    for result in runs.values():
        assert result.status != "completed"
        assert result.summary()["max_task_error"] > 0.05  # [m], stuck short of the line
    assert "out of reach" in runs["python"].reason


@pytest.mark.parametrize("engine", ENGINES)
def test_planar_tiago_reaches_it_by_moving_its_base(tiago_runs, engine: str) -> None:
    robot, runs = tiago_runs["planar"]
    result = runs[engine]
    assert_completed(result, robot)  # speeds (the base's too), joint ranges, tracking
    assert result.summary()["max_task_error"] <= TRACK
    moved = result.q[-1, :2] - result.q[0, :2]
    assert moved[0] >= 0.3  # [m]: the base drove forward
    # the base's speeds within its own limits (default 1 m/s, 1 rad/s)
    assert np.abs(result.qdot[:, :3]).max() <= 1.0 + 1e-9
    # independent forward kinematics: the hand on the line at every recorded sample
    _, line, _ = hand_line(robot)
    data = robot.model.createData()
    reference = line.sample(result.t[result.t <= line.duration]).position
    assert reference is not None
    frame = robot.frame_id("arm_tool_link")
    for k in range(0, len(reference), 100):
        pin.framesForwardKinematics(robot.model, data, result.q[k])
        assert np.linalg.norm(data.oMf[frame].translation - reference[k]) <= TRACK
    assert np.allclose(np.hypot(result.q[:, 2], result.q[:, 3]), 1.0, atol=1e-12)


def test_planar_runs_agree(tiago_runs) -> None:
    for base in ("fixed", "planar"):
        runs = tiago_runs[base][1]
        assert runs["python"].status == runs["compiled"].status
        assert runs["python"].q.shape == runs["compiled"].q.shape
        assert np.abs(runs["python"].q - runs["compiled"].q).max() <= PARITY


def test_scene_draws_the_base_where_it_went(tiago_runs) -> None:
    """The view's base node follows the recorded base pose (forward kinematics of q)."""
    robot, runs = tiago_runs["planar"]
    result = runs["compiled"]
    scene = build_scene(result, robot, geometry="collision", fps=2.0)
    base = joint_path(robot.model, 1)
    assert base.endswith(BASE_JOINT) and base in scene.robot_nodes
    (animation,) = [c for c in scene.commands if c["type"] == "set_animation"]
    (tracks,) = [a["clip"]["tracks"] for a in animation["animations"] if a["path"] == base]
    (position,) = [t for t in tracks if t["name"] == ".position"]
    values = np.frombuffer(position["values"].data, dtype="<f4").reshape(-1, 3)
    q = result.q[scene.timeline.index]
    np.testing.assert_allclose(values[:, :2], q[:, :2], atol=1e-5)  # float32 keys [m]
    assert values[-1, 0] - values[0, 0] >= 0.3


@pytest.fixture(scope="module")
def talos_runs() -> tuple[clik.Robot, list[clik.Goal], dict[str, clik.TrackingResult]]:
    robot = clik.Robot.load("talos", lock=TALOS_LOCK, base="floating")
    q0 = robot.q_reference
    feet = ("left_sole_link", "right_sole_link")
    goals = feet_held_hand_line(robot, q0, feet, "gripper_left_base_link", [0.15, 0.1, -0.2], 2.0)
    runs = run_both(tasks=goals, q0=q0, law="pseudoinverse", gain=500)
    return robot, goals, runs


@pytest.mark.parametrize("engine", ENGINES)
def test_talos_holds_its_feet_while_a_hand_tracks_a_line(talos_runs, engine: str) -> None:
    robot, goals, runs = talos_runs
    result = runs[engine]
    assert_feet_held_hand_tracked(result, robot, TRACK, moved=0.02)  # [m]: the body leans
    # independent forward kinematics of the recorded joints: the feet never moved
    data = robot.model.createData()
    for goal in goals[:2]:
        frame = goal.task.frame_id
        hold = goal.trajectory
        for q in result.q[::100]:
            pin.framesForwardKinematics(robot.model, data, q)
            placement = data.oMf[frame]
            assert np.linalg.norm(placement.translation - hold.position) <= TRACK
            rotation = pin.log3(hold.rotation.T @ placement.rotation)
            assert np.linalg.norm(rotation) <= TRACK


def test_talos_runs_agree(talos_runs) -> None:
    _, _, runs = talos_runs
    assert runs["python"].status == runs["compiled"].status == "completed"
    assert np.abs(runs["python"].q - runs["compiled"].q).max() <= PARITY


SCENARIO = """\
name = "planar4r on a planar base: a line beyond the arm's reach"

[robot]
source = "planar4r"
base = "planar"
base_speed = [0.5, 1.0]

[initial]
q = [0.0, 0.0, 0.0, 30.0, -60.0, 60.0, -30.0]
unit = "deg"

[task]
frame = "tip"
kind = "position"
axes = ["x", "y"]

[trajectory]
kind = "line"
goal = [2.0, 0.5, 0.0]
duration = 6.0

[solver]
law = "pseudoinverse"
gain = 500.0
engine = "{engine}"
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_scenario_key_robot_base(tmp_path: Path, engine: str) -> None:
    path = tmp_path / "planar_base.toml"
    path.write_text(SCENARIO.format(engine=engine))
    result = run_scenario(path)
    robot = result.robot
    assert robot is not None and robot.base == "planar"
    assert_completed(result, robot)
    assert result.summary()["max_task_error"] <= TRACK
    assert result.q[-1, 0] - result.q[0, 0] >= 0.5  # the base drove toward x = 2 m
    assert np.abs(result.qdot[:, :2]).max() <= 0.5 + 1e-9  # base_speed's linear bound


def test_an_output_reloads_its_base(tmp_path: Path) -> None:
    """``clik show OUT`` rebuilds the robot with its base from the record's info."""
    path = tmp_path / "planar_base.toml"
    path.write_text(SCENARIO.format(engine="compiled"))
    result = run_scenario(path)
    assert result.info["robot_base"] == "planar"
    assert result.info["robot_base_speed"] == [0.5, 1.0]
    path.unlink()  # not the scenario: the record's own info
    saved = result.save(tmp_path / "trajectory.npz")
    loaded = TrackingResult.load(saved)
    robot = rebuild_robot(loaded, saved)
    assert robot.base == "planar" and robot.nq == result.q.shape[1]
    np.testing.assert_array_equal(np.asarray(robot.model.velocityLimit)[:3], [0.5, 0.5, 1.0])
