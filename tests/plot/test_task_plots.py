"""Plots of a several-task run: one error panel per task, named by task, from its record."""

from __future__ import annotations

import numpy as np
import pytest

import clik
from clik import plot
from clik.errors import InputError
from clik.model.robot import PANDA_FINGERS
from clik.outputs.result import TrackingResult
from clik.plot.tasks import task_series
from clik.trajectory import Hold, JointPath, Line, PoseTrajectory

TASKS = ["hand", "elbow", "tool tilt", "com"]


@pytest.fixture(scope="module")
def panda_runs() -> tuple[TrackingResult, TrackingResult]:
    """A pose line with an elbow posture, a relative orientation and a CoM; and alone."""
    robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
    q0 = robot.q_reference
    hand = clik.Task(robot, "panda_hand", "pose")
    start = hand.placement(q0)
    line = PoseTrajectory(
        Line(start.translation, start.translation + [0.0, 0.1, -0.05], duration=0.5),
        Hold(rotation=start.rotation, duration=0.5),
    )
    elbow = clik.PostureTask(robot, ["panda_joint3"])
    tilt = clik.RelativeTask(robot, "panda_hand", "panda_link0", "orientation")
    com = clik.ComTask(robot, axes=["x"])
    goals = [
        clik.Goal(hand, line, name="hand"),
        clik.Goal(elbow, JointPath(elbow.angles(q0)), name="elbow", priority=2),
        clik.Goal(tilt, Hold(rotation=tilt.placement(q0).rotation), name="tool tilt", priority=2),
        clik.Goal(com, Hold(position=com.position(q0)), name="com", priority=3),
    ]
    run = {"q0": q0, "law": "pseudoinverse", "gain": 200.0, "dt": 2e-3, "engine": "python"}
    several = clik.track(tasks=goals, **run)
    alone = clik.track(tasks=goals[:1], **run)
    assert several.info["tasks"] == TASKS
    return several, alone


def panels(fig):
    return [ax for ax in fig.axes if ax.get_visible()]


class TestTaskErrors:
    def test_one_log_panel_per_task_named_by_task(self, panda_runs):
        several, _ = panda_runs
        fig = plot.task_errors(several)
        shown = panels(fig)
        assert [ax.get_title().split(" (")[0] for ax in shown] == TASKS
        assert shown[1].get_title() == "elbow (posture, priority 2)"
        assert all(ax.get_yscale() == "log" for ax in shown)
        assert len(fig.axes) == 4 and fig.axes[0].get_ylabel() == "|e| [m], [rad]"
        assert shown[1].get_ylabel() == "|e| [rad]"  # the Panda's joints all revolute
        assert shown[2].get_ylabel() == "|e| [rad]" and shown[3].get_ylabel() == "|e| [m]"

    def test_each_panel_draws_its_own_record(self, panda_runs):
        several, _ = panda_runs
        shown = panels(plot.task_errors(several, log=False))
        record = several.extra["task_errors"]
        for g, ax in enumerate(shown[1:]):
            (first,) = [line for line in ax.lines if line.get_gid() == "first"]
            np.testing.assert_array_equal(first.get_ydata(), record[:, g, 0])
        hand = shown[0]
        (position,) = [line for line in hand.lines if line.get_gid() == "first"]
        (orientation,) = [line for line in hand.lines if line.get_gid() == "orientation"]
        np.testing.assert_array_equal(position.get_ydata(), several.task_error_norm)
        np.testing.assert_array_equal(orientation.get_ydata(), several.orientation_error_norm)
        # Only the pose task has an orientation line: the others have one norm.
        assert all(
            [line.get_gid() for line in ax.lines if line.get_gid()] == ["first"] for ax in shown[1:]
        )

    def test_zero_samples_are_left_out_on_a_log_axis(self, panda_runs):
        several, _ = panda_runs
        ax = panels(plot.task_errors(several))[1]
        (first,) = [line for line in ax.lines if line.get_gid() == "first"]
        record = several.extra["task_errors"][:, 0, 0]
        assert np.any(record == 0.0)  # the elbow's error starts at 0
        assert np.all(np.isnan(first.get_ydata()[record == 0.0]))

    def test_runs_are_overlaid_and_a_task_only_one_run_has_is_drawn_once(self, panda_runs):
        several, alone = panda_runs
        fig = plot.task_errors([alone, several], ["alone", "several"], ncols=3)
        shown = panels(fig)
        assert len(shown) == 4 and len(fig.axes) == 6
        hand_labels = [line.get_label() for line in shown[0].lines]
        assert hand_labels == [
            "alone: position error [m]", "alone: orientation error [rad]",
            "several: position error [m]", "several: orientation error [rad]",
        ]  # fmt: skip
        assert [line.get_label() for line in shown[1].lines] == ["several: joints' error [rad]"]

    def test_one_task_run_has_one_panel(self):
        robot = clik.Robot.load("planar4r")
        task = clik.Task(robot, "tip", "position", axes=["x", "y"])
        q0 = np.radians([180.0, -30.0, -90.0, -30.0])
        line = Line(task.placement(q0).translation, [0.8, -0.2, 0.0], duration=0.3)
        result = clik.track(task, line, q0=q0, law="pseudoinverse", gain=200.0)
        shown = panels(plot.task_errors(result))
        assert [ax.get_title() for ax in shown] == ["task (position, priority 1)"]
        assert len(task_series(result)["task"].first) == len(result.t)


class TestBadInput:
    def test_unknown_task_lists_the_runs_tasks(self, panda_runs):
        several, _ = panda_runs
        import matplotlib.figure

        ax = matplotlib.figure.Figure().subplots()
        with pytest.raises(InputError, match=r"one of \['com', 'elbow', 'hand', 'tool tilt'\]"):
            plot.task_error(ax, several, "wrist")

    def test_a_record_that_does_not_match_the_tasks_is_refused(self, panda_runs):
        several, _ = panda_runs
        broken = TrackingResult(**{**several.__dict__, "extra": {}})
        with pytest.raises(InputError, match=r"the other tasks' error record \(N, 3, 2\)"):
            plot.task_errors(broken)

    def test_bad_ncols(self, panda_runs):
        with pytest.raises(InputError, match="ncols"):
            plot.task_errors(panda_runs[0], ncols=0)
