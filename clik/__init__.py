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

from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

from clik import trajectory
from clik.clouds.cloud_obstacle import CloudObstacle, EmptyCloudWarning
from clik.constraints.collision_scene import NoCollisionGeometryWarning, SkippedGeometryWarning
from clik.constraints.joint_thresholds import ThresholdCapWarning
from clik.control import Controller, Tick
from clik.engine import check_installed
from clik.errors import (
    ClikError,
    ClikWarning,
    EngineError,
    ExportError,
    FrameNotFound,
    GeometryError,
    InfeasibleError,
    InputError,
    JointNotFound,
    OutputError,
    OutputExistsError,
    OutputLockedError,
    RobotLoadError,
    ScenarioError,
    UnknownRobotError,
)
from clik.loop.joint_speed import JointSpeed, SpeedLimitWarning
from clik.loop.start_checks import StartWarning
from clik.loop.tracker import ReachWarning, StabilityWarning, Tracker, track
from clik.model.loading import ReferenceClippedWarning
from clik.model.mimic import MimicJointWarning
from clik.model.mjcf_root import EqualityIgnoredWarning, FreeJointWeldedWarning
from clik.model.robot import Robot
from clik.model.srdf import SrdfWarning
from clik.model.srdf_names import SrdfMismatchWarning
from clik.model.visual_meshes import MissingVisualMeshWarning
from clik.model.xacro_expand import XacroWarning
from clik.objectives.objective import Objective
from clik.outputs.result import TrackingResult
from clik.solving.solve_mode import solve
from clik.solving.solve_result import SolveResult
from clik.speed.speed_limits import SpeedLimits
from clik.speed.velocity_limits import track_within_limits
from clik.tasks.com_task import ComTask
from clik.tasks.distance_task import DistanceTask
from clik.tasks.gaze_task import GazeTask
from clik.tasks.goal import Goal
from clik.tasks.posture_task import PostureTask
from clik.tasks.relative_task import RelativeTask
from clik.tasks.task import Task

__all__ = [
    "ClikError",
    "ClikWarning",
    "CloudObstacle",
    "ComTask",
    "Controller",
    "DistanceTask",
    "EmptyCloudWarning",
    "EngineError",
    "EqualityIgnoredWarning",
    "ExportError",
    "FrameNotFound",
    "FreeJointWeldedWarning",
    "GazeTask",
    "GeometryError",
    "Goal",
    "InfeasibleError",
    "InputError",
    "JointNotFound",
    "JointSpeed",
    "MimicJointWarning",
    "MissingVisualMeshWarning",
    "NoCollisionGeometryWarning",
    "Objective",
    "OutputError",
    "OutputExistsError",
    "OutputLockedError",
    "PostureTask",
    "ReachWarning",
    "ReferenceClippedWarning",
    "RelativeTask",
    "Robot",
    "RobotLoadError",
    "ScenarioError",
    "SkippedGeometryWarning",
    "SolveResult",
    "SpeedLimitWarning",
    "SpeedLimits",
    "SrdfMismatchWarning",
    "SrdfWarning",
    "StabilityWarning",
    "StartWarning",
    "Task",
    "ThresholdCapWarning",
    "Tick",
    "Tracker",
    "TrackingResult",
    "UnknownRobotError",
    "XacroWarning",
    "plot",
    "solve",
    "track",
    "track_within_limits",
    "trajectory",
    "viz",
]

try:
    __version__ = version("clik")
    """The installed distribution's version (one source: ``pyproject.toml``)."""
except PackageNotFoundError:  # a source tree on sys.path, not installed
    __version__ = "0+unknown"

check_installed()  # a mismatched engine fails here, with the versions, not later

if TYPE_CHECKING:
    from clik import plot, viz

_LAZY = ("plot", "viz")
"""Submodules imported on first use (matplotlib and meshcat load only when asked)."""


def __getattr__(name: str) -> Any:
    """``clik.plot`` and ``clik.viz`` without importing them in ``import clik``."""
    if name in _LAZY:
        import importlib

        return importlib.import_module(f"clik.{name}")
    raise AttributeError(f"module 'clik' has no attribute {name!r}")
