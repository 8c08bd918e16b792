"""The 3-D view of a several-task run: each task's path and reference, its colour and name.

The browser check (the lines on screen) is in ``test_task_browser.py``.
"""

from __future__ import annotations

import itertools
import re
import warnings

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.errors import InputError
from clik.outputs.result import TrackingResult
from clik.trajectory import Hold, JointPath, Line, PoseTrajectory
from clik.viz import build_scene, export_html, palette
from clik.viz.commands import color_int
from clik.viz.task_paths import task_paths
from tests.viz.test_viz import MIN_DELTA_E, animated_paths, cielab, html_commands

BAXTER_LOCK = {"head_pan": 0.0, "l_gripper_l_finger_joint": 0.0, "r_gripper_l_finger_joint": 0.0}
TRACKED = 1e-5
"""What the tasks of the first level are tracked to in these runs [m]."""


def baxter() -> clik.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.MimicJointWarning)
        return clik.Robot.load("baxter", lock=BAXTER_LOCK)


def bent_start(robot: clik.Robot) -> np.ndarray:
    """Both arms bent and turned inwards: the hands 35 cm apart, facing each other."""
    q = robot.q_reference.copy()
    for side, s0 in (("left", -0.9), ("right", 0.9)):
        for joint, value in (("s0", s0), ("s1", -0.6), ("e1", 1.2), ("w1", 0.9)):
            q[robot.model.joints[robot.joint_id(f"{side}_{joint}")].idx_q] = value
    return q


def box_goals(robot: clik.Robot, q0: np.ndarray, duration: float = 1.0) -> list[clik.Goal]:
    """Two hands carrying a box up and to the left, its width held; the CoM and posture."""
    shift = np.array([0.0, 0.08, 0.04])

    def line(task: clik.Task) -> PoseTrajectory:
        start = task.placement(q0)
        path = Line(start.translation, start.translation + shift, duration=duration)
        return PoseTrajectory(path, Hold(rotation=start.rotation, duration=duration))

    left = clik.Task(robot, "left_hand_link", "pose")
    right = clik.Task(robot, "right_hand_link", "pose")
    box = clik.RelativeTask(robot, "left_hand_link", "right_hand_link", "position")
    com = clik.ComTask(robot, axes=["x", "y"])
    posture = clik.PostureTask(robot)
    return [
        clik.Goal(box, Hold(position=box.placement(q0).translation, duration=duration), "box"),
        clik.Goal(right, line(right), name="right hand"),
        clik.Goal(left, line(left), name="left hand", priority=2),
        clik.Goal(com, Hold(position=com.position(q0), duration=duration), "com", priority=3),
        clik.Goal(posture, JointPath(posture.angles(q0)), name="posture", priority=4),
    ]


@pytest.fixture(scope="module")
def carry() -> tuple[TrackingResult, list[clik.Goal]]:
    robot = baxter()
    q0 = bent_start(robot)
    goals = box_goals(robot, q0)
    result = clik.track(
        tasks=goals, q0=q0, law="pseudoinverse", gain=200.0, dt=2e-3, engine="python"
    )
    assert result.status == "completed", result.reason
    return result, goals


def objects(commands: list[dict], prefix: str) -> dict[str, dict]:
    return {
        c["path"]: c["object"]
        for c in commands
        if c["type"] == "set_object" and c["path"].startswith(prefix)
    }


class TestTaskPaths:
    def test_paths_follow_the_run_and_leave_out_the_posture(self, carry):
        result, goals = carry
        paths = task_paths(result, goals)
        assert [p.name for p in paths] == ["right hand", "box", "left hand", "com"]
        assert [p.primary for p in paths] == [True, False, False, False]
        right = paths[0]
        np.testing.assert_allclose(right.achieved, result.position, atol=1e-12)
        np.testing.assert_allclose(right.reference, result.reference_position, atol=1e-12)

    def test_achieved_is_the_forward_kinematics_of_the_recorded_configurations(self, carry):
        result, goals = carry
        paths = {p.name: p for p in task_paths(result, goals)}
        model = result.robot.model
        data = model.createData()
        hand = model.getFrameId("left_hand_link")
        for k in (0, len(result.t) // 2, len(result.t) - 1):
            pin.framesForwardKinematics(model, data, result.q[k])
            np.testing.assert_allclose(paths["left hand"].achieved[k], data.oMf[hand].translation)
            np.testing.assert_allclose(paths["box"].achieved[k], data.oMf[hand].translation)
            com = pin.centerOfMass(model, data, result.q[k])
            np.testing.assert_allclose(paths["com"].achieved[k], com, atol=1e-12)

    def test_relative_reference_is_mapped_to_the_world_through_the_other_frame(self, carry):
        result, goals = carry
        paths = {p.name: p for p in task_paths(result, goals)}
        box = paths["box"]
        # The box's reference is a constant point in the right hand's frame: in the world
        # it moves with the right hand (8.9 cm), and the left hand is on it.
        assert np.linalg.norm(box.reference[-1] - box.reference[0]) > 0.08
        assert np.abs(box.reference - box.achieved).max() < TRACKED
        left = paths["left hand"]
        assert np.abs(left.reference - left.achieved).max() < TRACKED
        np.testing.assert_allclose(
            paths["com"].reference, goals[3].trajectory.sample(result.t).position
        )

    def test_goals_in_any_order_and_wrong_goals(self, carry):
        result, goals = carry
        again = task_paths(result, list(reversed(goals)))
        assert [p.name for p in again] == ["right hand", "box", "left hand", "com"]
        with pytest.raises(InputError, match=r"the goals the run was given, named \['right hand'"):
            task_paths(result, goals[:3])
        renamed = [clik.Goal(g.task, g.trajectory, f"other {i}") for i, g in enumerate(goals)]
        with pytest.raises(InputError, match="the goals the run was given"):
            task_paths(result, renamed)
        with pytest.raises(
            InputError, match=r"the list of clik\.Goal the run was given, got 'Goal'"
        ):
            task_paths(result, goals[0])  # type: ignore[arg-type]

    def test_one_task_result_has_no_goals_to_draw(self, carry):
        result, goals = carry
        single = clik.track(
            goals[1].task, goals[1].trajectory, q0=result.q[0], law="pseudoinverse",
            gain=200.0, dt=2e-3,
        )  # fmt: skip
        with pytest.raises(InputError, match=r"info\['tasks'\]"):
            task_paths(single, goals[1:2])


class TestTaskScene:
    def test_each_other_task_has_its_colour_reference_and_growing_trail(self, carry):
        result, goals = carry
        scene = build_scene(result, geometry="collision", tasks=goals)
        drawn = objects(scene.commands, "/meshcat/tasks/")
        tracks = animated_paths(scene.commands)
        for i, name in enumerate(["box", "left hand", "com"]):
            rgb = color_int(palette.TASKS[i])
            reference = drawn[f"/meshcat/tasks/{name}/reference"]
            (material,) = reference["materials"]
            assert material["color"] == rgb
            assert material["transparent"] and material["opacity"] == palette.TASK_REFERENCE_OPACITY
            trail = sorted(p for p in drawn if p.startswith(f"/meshcat/tasks/{name}/trail/"))
            assert len(trail) > 10
            assert {o["materials"][0]["color"] for p, o in drawn.items() if p in trail} == {rgb}
            assert "transparent" not in drawn[trail[0]]["materials"][0]
            assert tracks[trail[-1]] == [".visible"]
        assert not any("posture" in p or "right hand" in p for p in drawn)
        assert [p.name for p in scene.tasks] == ["right hand", "box", "left hand", "com"]

    def test_legend_names_the_tasks(self, carry):
        result, goals = carry
        scene = build_scene(result, geometry="collision", tasks=goals)
        labels = [label for _, label in scene.legend]
        assert labels[:2] == ["reference (right hand)", "path (right hand)"]
        assert labels[-3:] == ["box", "left hand", "com"]
        assert [c for c, _ in scene.legend[-3:]] == list(palette.TASKS[:3])
        plain = build_scene(result, geometry="collision")
        assert plain.legend == list(palette.LEGEND)
        assert not objects(plain.commands, "/meshcat/tasks/")

    def test_exported_page_carries_the_tasks_and_their_swatches(self, carry, tmp_path):
        result, goals = carry
        path = export_html(result, tmp_path / "carry.html", geometry="collision", tasks=goals)
        assert "/meshcat/tasks/left hand/reference" in objects(html_commands(path), "/meshcat/")
        text = path.read_text(encoding="utf-8")
        swatches = re.findall(r'<span style="background:#([0-9a-f]{6})"></span>([^<]*)', text)
        assert (f"{color_int(palette.TASKS[1]):06x}", "left hand") in swatches
        assert (f"{color_int(palette.REFERENCE):06x}", "reference (right hand)") in swatches


def test_task_colours_stay_apart_from_the_legend_and_each_other():
    legend = [(tuple(c), label) for c, label in palette.LEGEND]
    tasks = [(c, f"task colour {i}") for i, c in enumerate(palette.TASKS)]
    assert len(set(palette.TASKS)) == len(palette.TASKS) >= 6
    for (a, la), (b, lb) in itertools.product(tasks, legend + tasks):
        if la == lb:
            continue
        gap = float(np.linalg.norm(cielab(a) - cielab(b)))
        assert gap >= MIN_DELTA_E, f"{la!r} and {lb!r} look alike (Delta E {gap:.1f})"
    for colour, label in tasks:
        for background in (palette.BACKGROUND_TOP, palette.BACKGROUND_BOTTOM):
            assert float(np.linalg.norm(cielab(colour) - cielab(background))) >= MIN_DELTA_E, label
