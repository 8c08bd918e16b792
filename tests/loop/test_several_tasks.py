"""Several tasks, priority levels and eq. (5) (docs/method.md, "Several tasks").

The acceptance runs of issue 24, in both engines: two hands carry a box (a relative
task holds its width), a lower level leaves a higher one alone, a posture task holds a
redundant arm's elbow, a centre-of-mass task holds a humanoid's CoM, joint-range
centring keeps the joints off their limits.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.loop.levels import prioritized_levels
from clik.trajectory import Circle, Hold, JointPath, Line, PoseTrajectory
from tests.limits_check import assert_completed

ENGINES = ("python", "compiled")


@pytest.fixture(scope="module")
def baxter() -> clik.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return clik.Robot.load(
            "baxter", lock={"l_gripper_l_finger_joint": 0.0, "r_gripper_l_finger_joint": 0.0}
        )


@pytest.fixture(scope="module")
def arm() -> clik.Robot:
    lock = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
    return clik.Robot.load("panda", lock=lock)


def bent(robot: clik.Robot) -> np.ndarray:
    """Baxter with bent elbows (its reference posture is near-singular)."""
    q = robot.q_reference.copy()
    for side in ("left", "right"):
        for joint, value in (("s1", -0.6), ("e1", 1.2), ("w1", 0.9)):
            q[robot.model.joints[robot.joint_id(f"{side}_{joint}")].idx_q] = value
    return q


def pose_line(
    task: clik.Task, q0: np.ndarray, shift: np.ndarray, duration: float
) -> PoseTrajectory:
    start = task.placement(q0)
    line = Line(start.translation, start.translation + shift, duration)
    return PoseTrajectory(line, Hold(rotation=start.rotation))


def box_goals(robot: clik.Robot, q0: np.ndarray) -> tuple[list[clik.Goal], float]:
    """Both hands on one line (a box moved 10 cm), the box's width held, a posture below."""
    left = clik.Task(robot, "left_hand_link", "pose")
    right = clik.Task(robot, "right_hand_link", "pose")
    box = clik.RelativeTask(robot, "left_hand_link", "right_hand_link", "position")
    posture = clik.PostureTask(robot)
    shift = np.array([0.05, 0.0, 0.1])
    width = box.placement(q0).translation
    goals = [
        clik.Goal(left, pose_line(left, q0, shift, 2.0), name="left"),
        clik.Goal(right, pose_line(right, q0, shift, 2.0), name="right"),
        clik.Goal(box, Hold(position=width), name="box"),
        clik.Goal(posture, JointPath(posture.angles(q0)), name="posture", priority=2, gain=10),
    ]
    return goals, float(np.linalg.norm(width))


@pytest.mark.parametrize("engine", ENGINES)
def test_two_hands_carry_a_box(baxter: clik.Robot, engine: str) -> None:
    q0 = bent(baxter)
    goals, width = box_goals(baxter, q0)
    result = clik.track(
        tasks=goals, q0=q0, law="pseudoinverse", gain=100, engine=engine, settle=0.2
    )
    assert_completed(result, baxter)
    errors = result.task_errors
    assert list(errors) == ["left", "right", "box", "posture"]
    for hand in ("left", "right"):
        assert errors[hand]["final"] <= 1e-6
        assert errors[hand]["final_orientation"] <= 1e-6
        assert errors[hand]["max"] <= 1e-5
    assert errors["box"]["max"] <= 1e-4  # the box's width, along the whole line
    # the same, measured on the recorded joints, independently of the run's own numbers
    box = goals[2].task
    widths = [np.linalg.norm(box.placement(q).translation) for q in result.q[::50]]
    assert np.max(np.abs(np.array(widths) - width)) <= 1e-4
    left = goals[0].task
    end = goals[0].trajectory.sample(np.array([2.0]))
    assert np.linalg.norm(left.placement(result.q[-1]).translation - end.position[0]) <= 1e-6
    assert result.extra["task_errors"].shape == (result.t.shape[0], 3, 2)
    summary = result.summary()
    assert set(summary["task_errors"]) == {"left", "right", "box", "posture"}
    assert summary["task_errors"]["posture"]["priority"] == 2


def swivel(robot: clik.Robot, q: np.ndarray) -> float:
    """The Panda's elbow (joint 4) angle about the shoulder-wrist axis [rad]."""
    data = robot.thread_data()
    pin.forwardKinematics(robot.model, data, q)
    s, e, w = (data.oMi[robot.joint_id(f"panda_joint{i}")].translation for i in (2, 4, 6))
    axis = (w - s) / np.linalg.norm(w - s)
    elbow = (e - s) - axis * axis.dot(e - s)
    up = np.array([0.0, 0.0, 1.0]) - axis * axis[2]
    return float(np.arctan2(np.cross(up, elbow).dot(axis), up.dot(elbow)))


ARM_Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])


@pytest.mark.parametrize("engine", ENGINES)
def test_posture_task_holds_the_elbow(arm: clik.Robot, engine: str) -> None:
    hand = clik.Task(arm, "panda_hand", "pose")
    line = pose_line(hand, ARM_Q0, np.array([0.25, 0.2, -0.2]), 3.0)
    alone = clik.track(hand, line, q0=ARM_Q0, law="pseudoinverse", gain=100, engine=engine)
    posture = clik.PostureTask(arm, ["panda_joint3"])
    goals = [
        clik.Goal(hand, line, name="hand"),
        clik.Goal(posture, JointPath(posture.angles(ARM_Q0)), name="elbow", priority=2, gain=10),
    ]
    held = clik.track(tasks=goals, q0=ARM_Q0, law="pseudoinverse", gain=100, engine=engine)
    assert_completed(alone, arm)
    assert_completed(held, arm)
    start = swivel(arm, ARM_Q0)
    drift = max(abs(swivel(arm, q) - start) for q in alone.q[::20])
    kept = max(abs(swivel(arm, q) - start) for q in held.q[::20])
    assert drift > np.radians(2.0)  # without it the elbow wanders
    assert kept < np.radians(1.0)
    assert held.task_errors["hand"]["max"] <= 2e-6


def test_a_lower_level_leaves_the_higher_alone(arm: clik.Robot) -> None:
    """At every state of a run, the posture level changes the hand level's motion by nothing.

    Along the run the hand's error differs from the one-task run only by the
    integration's second-order term (the arm is elsewhere in the null space): it halves
    with ``dt`` (docs/method.md, "Several tasks").
    """
    hand = clik.Task(arm, "panda_hand", "pose")
    posture = clik.PostureTask(arm)
    line = pose_line(hand, ARM_Q0, np.array([0.2, 0.1, -0.1]), 1.0)
    goals = [
        clik.Goal(hand, line, name="hand"),
        clik.Goal(posture, JointPath(arm.q_reference), name="posture", priority=2, gain=5),
    ]
    result = clik.track(tasks=goals, q0=ARM_Q0, law="pseudoinverse", gain=100, engine="python")
    rng = np.random.default_rng(3)
    for q in result.q[::100]:
        J1 = hand.jacobian(q)
        b1 = 0.1 * rng.normal(size=6)
        J = np.vstack([J1, np.eye(7)])
        b = np.concatenate([b1, 5.0 * (arm.q_reference - q)])
        one, two = np.zeros(7), np.zeros(7)
        prioritized_levels(J[:6], b1, [6], np.zeros((0, 7)), np.zeros(0), one, 0.0, 1e-3,
                           np.zeros((2, 7)))  # fmt: skip
        prioritized_levels(J, b, [6, 13], np.zeros((0, 7)), np.zeros(0), two, 0.0, 1e-3,
                           np.zeros((3, 7)))  # fmt: skip
        assert np.abs(J1 @ two - J1 @ one).max() <= 1e-9
        assert np.abs(J1 @ one - b1).max() <= 1e-9  # feasible: level 1 realised exactly
        assert np.abs(two - one).max() > 1e-3  # and the posture did move the arm
    diffs = []
    for dt in (1e-3, 5e-4):
        one_task = clik.track(hand, line, q0=ARM_Q0, law="pseudoinverse", gain=100, dt=dt,
                              engine="python")  # fmt: skip
        both = clik.track(tasks=goals, q0=ARM_Q0, law="pseudoinverse", gain=100, dt=dt,
                          engine="python")  # fmt: skip
        diffs.append(np.abs(both.task_error_norm - one_task.task_error_norm).max())
    assert diffs[0] <= 1e-7
    assert diffs[1] <= 0.6 * diffs[0]


@pytest.fixture(scope="module")
def talos() -> clik.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return clik.Robot.load(
            "talos", lock={"gripper_left_joint": 0.0, "gripper_right_joint": 0.0}
        )


@pytest.mark.parametrize("engine", ENGINES)
def test_com_task_holds_a_humanoid(talos: clik.Robot, engine: str) -> None:
    q0 = talos.q_reference
    hand = clik.Task(talos, "gripper_left_base_link", "position")
    com = clik.ComTask(talos, ["x", "y"])
    feet = [clik.Task(talos, f"{side}_sole_link", "pose") for side in ("left", "right")]
    start = hand.placement(q0).translation
    c0 = com.position(q0)
    line = Line(start, start + np.array([0.15, 0.1, 0.1]), 2.0)

    def holding(task: clik.Task) -> PoseTrajectory:
        placement = task.placement(q0)
        return PoseTrajectory(
            Hold(position=placement.translation), Hold(rotation=placement.rotation)
        )

    goals = [clik.Goal(hand, line, name="hand")]
    goals += [clik.Goal(f, holding(f), name=f.frame) for f in feet]
    free = clik.track(tasks=goals, q0=q0, law="pseudoinverse", gain=100, engine=engine)
    goals.append(clik.Goal(com, Hold(position=c0), name="com"))
    held = clik.track(tasks=goals, q0=q0, law="pseudoinverse", gain=100, engine=engine)
    assert_completed(held, talos)
    drift = max(np.abs(com.position(q)[:2] - c0[:2]).max() for q in free.q[::20])
    kept = max(np.abs(com.position(q)[:2] - c0[:2]).max() for q in held.q[::20])
    assert drift > 5e-3  # the arm alone moves the CoM by millimetres
    assert kept <= 1e-3
    assert held.task_errors["com"]["max"] <= 1e-3
    assert held.task_errors["hand"]["final"] <= 1e-5


def margin(robot: clik.Robot, q: np.ndarray) -> float:
    """The closest joint-limit margin of ``q`` [rad or m]."""
    return float(np.min(np.minimum(q - robot.lower, robot.upper - q)))


@pytest.mark.parametrize("engine", ENGINES)
def test_joint_centering_keeps_joints_off_their_limits(arm: clik.Robot, engine: str) -> None:
    hand = clik.Task(arm, "panda_hand", "position")
    centre = hand.placement(ARM_Q0).translation + np.array([0.0, 0.15, 0.0])
    circle = Circle(centre, 0.15, start_angle=-np.pi / 2, angle=4 * np.pi, duration=12.0)
    assert np.allclose(circle.sample(np.zeros(1)).position[0], hand.placement(ARM_Q0).translation)
    plain = clik.track(hand, circle, q0=ARM_Q0, law="pseudoinverse", gain=100, engine=engine)
    centred = clik.track(
        tasks=[clik.Goal(hand, circle, name="hand")], q0=ARM_Q0, law="pseudoinverse", gain=100,
        engine=engine, objectives=[clik.Objective("joint_centering", gain=0.5)],
    )  # fmt: skip
    assert_completed(centred, arm)
    low_plain = min(margin(arm, q) for q in plain.q)
    low_centred = min(margin(arm, q) for q in centred.q)
    assert low_centred > low_plain + 0.05
    assert centred.task_errors["hand"]["max"] <= 1e-4


def test_bad_stacks_are_refused(arm: clik.Robot) -> None:
    hand = clik.Task(arm, "panda_hand", "pose")
    line = pose_line(hand, ARM_Q0, np.array([0.1, 0.0, 0.0]), 1.0)
    posture = clik.PostureTask(arm)
    two = [clik.Goal(hand, line), clik.Goal(posture, JointPath(ARM_Q0), priority=2)]
    with pytest.raises(clik.InputError, match=r"tasks.priority.*pseudoinverse"):
        clik.Tracker(tasks=two, law="transpose")
    with pytest.raises(clik.InputError, match=r"objectives.*pseudoinverse"):
        clik.Tracker(hand, law="transpose", objectives=[clik.Objective("joint_centering")])
    with pytest.raises(clik.InputError, match=r"tasks.*frame task"):
        clik.Tracker(tasks=[clik.Goal(posture, JointPath(ARM_Q0))], law="pseudoinverse")
    with pytest.raises(clik.InputError, match=r"tasks.name"):
        clik.Tracker(tasks=[clik.Goal(hand, line, name="a"), clik.Goal(posture, line, name="a")])
    with pytest.raises(clik.InputError, match="either task"):
        clik.Tracker(hand, tasks=two)
    with pytest.raises(clik.InputError, match=r"tasks.priority"):
        clik.Goal(hand, line, priority=0)
    with pytest.raises(clik.InputError, match=r"task.relative_to"):
        clik.RelativeTask(arm, "panda_hand", "panda_hand")
    with pytest.raises(clik.InputError, match=r"task.axes"):
        clik.ComTask(arm, ["x", "w"])
    with pytest.raises(clik.JointNotFound):
        clik.PostureTask(arm, ["elbow"])
    with pytest.raises(clik.InputError, match=r"objectives.gain"):
        clik.Objective("posture", gain=-1.0)
    with pytest.raises(clik.InputError, match=r"objectives.kind"):
        clik.Objective("dexterity")  # type: ignore[arg-type]
    wrong = [clik.Goal(hand, line), clik.Goal(posture, JointPath(np.zeros(3)), priority=2)]
    tracker = clik.Tracker(tasks=wrong, law="pseudoinverse", engine="python")
    with pytest.raises(clik.InputError, match="7 joint values"):
        tracker.run(q0=ARM_Q0)
    pose_for_posture = [clik.Goal(hand, line), clik.Goal(posture, line, priority=2)]
    tracker = clik.Tracker(tasks=pose_for_posture, law="pseudoinverse", engine="python")
    with pytest.raises(clik.InputError, match="joint-space trajectory"):
        tracker.run(q0=ARM_Q0)
    with pytest.raises(clik.InputError, match="trajectory"):
        clik.Tracker(tasks=two, law="pseudoinverse", engine="python").run(line, q0=ARM_Q0)


@pytest.mark.parametrize("engine", ENGINES)
def test_deadlock_names_the_tasks(baxter: clik.Robot, engine: str) -> None:
    """Hands pulled apart past their reach: a deadlock naming each task's rows."""
    q0 = bent(baxter)
    left = clik.Task(baxter, "left_hand_link", "position")
    right = clik.Task(baxter, "right_hand_link", "position")
    pl, pr = left.placement(q0).translation, right.placement(q0).translation
    apart = np.array([0.0, 1.5, 0.0])
    goals = [
        clik.Goal(left, Line(pl, pl + apart, 2.0), name="left"),
        clik.Goal(right, Line(pr, pr - apart, 2.0), name="right"),
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ReachWarning)
        result = clik.track(tasks=goals, q0=q0, law="pseudoinverse", gain=100, engine=engine)
    assert result.status == "deadlock"
    assert "task rows that cannot follow: left:y, right:y" in result.reason
    assert result.task_errors["right"]["final"] > 0.3
    assert result.task_errors["left"]["final"] > 0.3


@pytest.mark.parametrize("engine", ENGINES)
def test_solve_reaches_both_hands_poses(baxter: clik.Robot, engine: str) -> None:
    q0 = bent(baxter)
    hands = [clik.Task(baxter, f"{side}_hand_link", "pose") for side in ("left", "right")]
    targets = []
    for hand, dy in zip(hands, (-0.05, 0.05), strict=True):
        start = hand.placement(q0)
        targets.append(pin.SE3(start.rotation, start.translation + np.array([0.1, dy, 0.15])))
    goals = [
        clik.Goal(h, PoseTrajectory(Hold(position=t.translation), Hold(rotation=t.rotation)))
        for h, t in zip(hands, targets, strict=True)
    ]
    posture = clik.PostureTask(baxter)
    goals.append(clik.Goal(posture, JointPath(posture.angles(q0)), priority=2))
    result = clik.solve(tasks=goals, q0=q0, engine=engine, tolerance=1e-6,
                        orientation_tolerance=1e-6, max_iterations=400)  # fmt: skip
    assert result.success, result.reason
    for hand, target in zip(hands, targets, strict=True):
        reached = hand.placement(result.q)
        assert np.linalg.norm(reached.translation - target.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) <= 1e-6
    assert np.all(result.q >= baxter.lower) and np.all(result.q <= baxter.upper)
    with pytest.raises(clik.InputError, match="either task and target"):
        clik.solve(hands[0], targets[0], tasks=goals)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("law", ["transpose", "nonlinear"])
def test_laws_9_and_8_weigh_tasks_by_gain(baxter: clik.Robot, engine: str, law: str) -> None:
    """One level: every task's rows in one extended task, each weighted by its gain."""
    q0 = bent(baxter)
    left = clik.Task(baxter, "left_hand_link", "position")
    right = clik.Task(baxter, "right_hand_link", "position")
    shift = np.array([0.05, 0.0, 0.1])
    pl, pr = left.placement(q0).translation, right.placement(q0).translation
    goals = [
        clik.Goal(left, Line(pl, pl + shift, 2.0), name="left"),
        clik.Goal(right, Line(pr, pr + shift, 2.0), name="right", gain=500),
    ]
    result = clik.track(tasks=goals, q0=q0, law=law, gain=1000, engine=engine)
    assert_completed(result, baxter)
    errors = result.task_errors
    assert errors["left"]["max"] <= 1e-3
    if law == "transpose":  # the lag of (9) goes as 1 / K: half the gain, twice the error
        assert 1.5 <= errors["right"]["max"] / errors["left"]["max"] <= 2.5
