"""What a step costs against joints and rows: ``python -m benchmarks.scaling``.

A family of serial chains of ``n`` revolute joints (10, 20, 40, 80; 1 m long, links of
1 / n m, axes alternating z and y), each run offline in the compiled engine (law (10), gain
100 1/s, 1 ms), the tip's 6-D pose on a 5 cm line, with more of the rows a whole-body
problem has:

- ``pose``: the tip alone (6 rows, one level);
- ``+posture``: a posture task on every joint at level 2 (n unit rows);
- ``+ranges``: joint-range rows too (2 n candidates, active near a limit);
- ``+floating``: the same on a floating base (n + 6 velocities).

Each figure is the smallest of ``ROUNDS`` runs' ``wall_time_s`` over their steps
[us per step] (the machine is shared: the smallest is the least disturbed), with the
kinematics alone (``computeJointJacobians`` from Python's ``pin``, for scale).
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

import clik
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.joint_limits import JointLimits
from clik.trajectory import Hold, JointPath, Line, PoseTrajectory

SIZES = (10, 20, 40, 80)
"""Joints of the chains."""
VARIANTS = ("pose", "+posture", "+ranges", "+floating")
LENGTH = 1.0
"""Length of every chain [m] (links of LENGTH / n)."""
BEND = 0.5
"""Every joint's start [rad] (the tip's smallest singular value 2 to 8 % of its largest row
norm on every chain: law (10)'s regular case, above its 1 % damping band)."""
ROUNDS = 5
DURATION = 0.5
"""Length of each run [s]."""


def chain_urdf(n: int) -> str:
    """A serial chain of n revolute joints (limits +-2.5 rad, 2 rad/s), LENGTH / n links [m]."""
    links = ['<link name="base"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
             'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>']  # fmt: skip
    joints = []
    for i in range(n):
        axis = "0 0 1" if i % 2 == 0 else "0 1 0"
        parent = "base" if i == 0 else f"l{i - 1}"
        links.append(
            f'<link name="l{i}"><inertial><mass value="0.5"/><origin xyz="0 0 0.05"/>'
            '<inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/>'
            "</inertial></link>"
        )
        joints.append(
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="0 0 {0.0 if i == 0 else LENGTH / n}"/><axis xyz="{axis}"/>'
            '<limit lower="-2.5" upper="2.5" effort="10" velocity="2"/></joint>'
        )
    tip = ('<link name="tip"/><joint name="tip_joint" type="fixed"><parent link="l'
           f'{n - 1}"/><child link="tip"/><origin xyz="0 0 {LENGTH / n}"/></joint>')  # fmt: skip
    return f'<robot name="chain{n}">{"".join(links)}{"".join(joints)}{tip}</robot>'


def step_us(n: int, variant: str, folder: Path) -> float:
    """The smallest per-step cost [us] of ``variant`` on the chain of ``n`` joints."""
    path = folder / f"chain{n}.urdf"
    path.write_text(chain_urdf(n))
    base = "floating" if variant == "+floating" else "fixed"
    robot = clik.Robot.load(str(path), base=base)
    q0 = robot.q_reference.copy()
    first = 7 if base == "floating" else 0
    q0[first:] = BEND  # a spiral: the tip's rows well clear of the damping band
    tip = clik.Task(robot, "tip", "pose")
    start = tip.placement(q0)
    line = Line(start.translation, start.translation + np.array([0.05, 0.0, 0.0]), DURATION)
    goals = [clik.Goal(tip, PoseTrajectory(line, Hold(rotation=start.rotation)), name="tip")]
    if variant != "pose":
        posture = clik.PostureTask(robot)
        goals.append(clik.Goal(posture, JointPath(posture.angles(q0)), name="posture",
                               priority=2, gain=10.0))  # fmt: skip
    if base == "floating":  # the base held, as a humanoid's feet hold it
        root = clik.Task(robot, robot.model.frames[2].name, "pose")
        goals.insert(0, clik.Goal(root, PoseTrajectory(
            Line(root.placement(q0).translation, root.placement(q0).translation, DURATION),
            Hold(rotation=root.placement(q0).rotation)), name="base"))  # fmt: skip
    ranges = variant in ("+ranges", "+floating")
    constraints = ConstraintSet(robot, joint_limits=JointLimits(robot)) if ranges else None
    tracker = clik.Tracker(tasks=goals, law="pseudoinverse", gain=100.0, dt=1e-3,
                           constraints=constraints)  # fmt: skip
    best = np.inf
    for _ in range(ROUNDS):
        result = tracker.run(q0=q0)
        if result.status != "completed":
            raise RuntimeError(f"chain {n}, {variant}: {result.status} ({result.reason})")
        best = min(best, result.wall_time_s / result.steps)
    return float(best * 1e6)


def kinematics_us(n: int, folder: Path) -> float:
    """``computeJointJacobians`` on the chain [us per call], for scale."""
    model = pin.buildModelFromXML(chain_urdf(n))
    data, q = model.createData(), pin.neutral(model)
    best = np.inf
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for _ in range(1000):
            pin.computeJointJacobians(model, data, q)
        best = min(best, (time.perf_counter() - start) / 1000)
    return float(best * 1e6)


def main() -> None:
    """Print the table (markdown) of ``docs/guides/performance.md``."""
    warnings.simplefilter("ignore", clik.ClikWarning)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        print("| joints | " + " | ".join(VARIANTS) + " | computeJointJacobians (Python) |")
        print("|---|" + "---|" * (len(VARIANTS) + 1))
        for n in SIZES:
            cells = [f"{step_us(n, v, folder):.1f}" for v in VARIANTS]
            print(f"| {n} | " + " | ".join(cells) + f" | {kinematics_us(n, folder):.1f} |")


if __name__ == "__main__":
    main()
