"""clik: closed-loop inverse kinematics for redundant manipulators.

Sciavicco and Siciliano's dynamic solution of the inverse kinematic problem
(docs/method.md): the joint trajectory is the solution of a dynamical system whose
error dynamics are stable, with obstacle and joint-range constraints as extra
task rows.

Example:
    >>> import numpy as np, clik
    >>> robot = clik.Robot.load("planar4r")
    >>> task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    >>> q0 = np.radians([180, -30, -90, -30])
    >>> line = clik.trajectory.Line(task.placement(q0).translation, [0.8, -0.2, 0], 3.0, 0.12)
    >>> result = clik.track(task, line, q0=q0, law="transpose", gain=1000, dt=1e-3)
"""

from clik import trajectory
from clik.errors import (
    ClikError,
    FrameNotFound,
    GeometryError,
    InfeasibleError,
    InputError,
    JointNotFound,
    OutputExistsError,
    RobotLoadError,
    ScenarioError,
    UnknownRobotError,
)
from clik.result import TrackingResult
from clik.robot import MimicJointWarning, Robot
from clik.solve_mode import SolveResult, solve
from clik.task import Task
from clik.tracking import ReachWarning, StabilityWarning, Tracker, track

__all__ = [
    "ClikError",
    "FrameNotFound",
    "GeometryError",
    "InfeasibleError",
    "InputError",
    "JointNotFound",
    "MimicJointWarning",
    "OutputExistsError",
    "ReachWarning",
    "Robot",
    "RobotLoadError",
    "ScenarioError",
    "SolveResult",
    "StabilityWarning",
    "Task",
    "Tracker",
    "TrackingResult",
    "UnknownRobotError",
    "solve",
    "track",
    "trajectory",
]

__version__ = "0.1.0"
