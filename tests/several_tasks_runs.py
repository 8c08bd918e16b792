"""The numbers of issue 24's closing note: ``python -m tests.several_tasks_runs``.

Run from the checkout's root (it imports the bench's ``benchmarks`` package).

Each line is measured here, in the compiled engine, on the acceptance tests' setups
(:mod:`tests.loop.test_several_tasks`): the box's width, the elbow's drift, the CoM's
drift, joint-range centring, a lower level's effect on a higher one against ``dt``,
and the dual-arm step (the bench's ``dual_arm`` problem, timed as ``clik bench`` times
a line: the run's ``wall_time_s`` over its samples, the smallest of 15 runs).
"""

from __future__ import annotations

import warnings

import numpy as np

import clik
from benchmarks.step_dual_arm import dual_arm
from clik.trajectory import Circle, Hold, JointPath, Line, PoseTrajectory
from tests.loop.test_several_tasks import ARM_Q0, bent, box_goals, margin, pose_line, swivel


def main() -> None:
    warnings.simplefilter("ignore")
    baxter = clik.Robot.load(
        "baxter", lock={"l_gripper_l_finger_joint": 0.0, "r_gripper_l_finger_joint": 0.0}
    )
    q0 = bent(baxter)
    goals, width = box_goals(baxter, q0)
    r = clik.track(tasks=goals, q0=q0, law="pseudoinverse", gain=100, settle=0.2)
    e = r.task_errors
    print(f"box: {r.status}; hands final {e['left']['final']:.2e} / {e['right']['final']:.2e} m, "
          f"box width {width:.4f} m held within {e['box']['max']:.2e} m")  # fmt: skip
    arm = clik.Robot.load("panda", lock={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02})
    hand = clik.Task(arm, "panda_hand", "pose")
    line = pose_line(hand, ARM_Q0, np.array([0.25, 0.2, -0.2]), 3.0)
    posture = clik.PostureTask(arm, ["panda_joint3"])
    alone = clik.track(hand, line, q0=ARM_Q0, law="pseudoinverse", gain=100)
    held = clik.track(tasks=[
        clik.Goal(hand, line, name="hand"),
        clik.Goal(posture, JointPath(posture.angles(ARM_Q0)), name="elbow", priority=2, gain=10),
    ], q0=ARM_Q0, law="pseudoinverse", gain=100)  # fmt: skip
    s0 = swivel(arm, ARM_Q0)
    for name, run in (("without", alone), ("with", held)):
        drift = max(abs(swivel(arm, q) - s0) for q in run.q)
        print(f"elbow {name} the posture task: {run.status}, drift {np.degrees(drift):.3g} deg")
    talos = clik.Robot.load("talos", lock={"gripper_left_joint": 0.0, "gripper_right_joint": 0.0})
    tq = talos.q_reference
    th = clik.Task(talos, "gripper_left_base_link", "position")
    com = clik.ComTask(talos, ["x", "y"])
    c0 = com.position(tq)
    start = th.placement(tq).translation
    feet = [clik.Task(talos, f"{side}_sole_link", "pose") for side in ("left", "right")]
    tg = [clik.Goal(th, Line(start, start + np.array([0.15, 0.1, 0.1]), 2.0), name="hand")]
    for f in feet:
        p = f.placement(tq)
        tg.append(
            clik.Goal(
                f,
                PoseTrajectory(Hold(position=p.translation), Hold(rotation=p.rotation)),
                name=f.frame,
            )
        )
    for name, gs in (
        ("without", tg),
        ("with", [*tg, clik.Goal(com, Hold(position=c0), name="com")]),
    ):
        run = clik.track(tasks=gs, q0=tq, law="pseudoinverse", gain=100)
        drift = max(np.abs(com.position(q)[:2] - c0[:2]).max() for q in run.q)
        print(f"CoM {name} the CoM task: {run.status}, drift {drift * 1e3:.3g} mm")
    ph = clik.Task(arm, "panda_hand", "position")
    centre = ph.placement(ARM_Q0).translation + np.array([0.0, 0.15, 0.0])
    circle = Circle(centre, 0.15, start_angle=-np.pi / 2, angle=4 * np.pi, duration=12.0)
    plain = clik.track(ph, circle, q0=ARM_Q0, law="pseudoinverse", gain=100)
    centred = clik.track(tasks=[clik.Goal(ph, circle, name="hand")], q0=ARM_Q0,
                         law="pseudoinverse", gain=100,
                         objectives=[clik.Objective("joint_centering", gain=0.5)])  # fmt: skip
    for name, run in (("without", plain), ("with", centred)):
        low = min(margin(arm, q) for q in run.q)
        print(f"circle {name} joint centring: {run.status}, closest joint-limit margin "
              f"{low:.4f} rad ({np.degrees(low):.1f} deg)")  # fmt: skip
    full = clik.PostureTask(arm)
    short = pose_line(hand, ARM_Q0, np.array([0.25, 0.2, -0.2]), 3.0)
    for dt in (1e-3, 5e-4, 2.5e-4):
        one = clik.track(hand, short, q0=ARM_Q0, law="pseudoinverse", gain=100, dt=dt)
        two = clik.track(tasks=[
            clik.Goal(hand, short, name="hand"),
            clik.Goal(full, JointPath(ARM_Q0), name="posture", priority=2, gain=10),
        ], q0=ARM_Q0, law="pseudoinverse", gain=100, dt=dt)  # fmt: skip
        diff = np.abs(two.task_error_norm - one.task_error_norm).max()
        print(f"hand error with - without a posture level, dt = {dt:g} s: {diff:.3g} m")
    problem = dual_arm(3.0)
    tracker = clik.Tracker(tasks=problem.goals(), law="pseudoinverse", gain=100.0, dt=1e-3)
    times = []
    for _ in range(15):
        run = tracker.run(q0=problem.q0)
        times.append(run.wall_time_s / run.steps * 1e6)
    print(f"dual_arm ({problem.robot.nv} joints): {run.status}, {min(times):.1f} us per sample "
          f"(smallest of 15), median {np.median(times):.1f} us")  # fmt: skip


if __name__ == "__main__":
    main()
