r"""Desired task trajectories ``x_d(t)``, ``xdot_d(t)`` (docs/method.md, eq. (6)-(7)).

Contract: a :class:`Trajectory` has a ``duration`` [s] and a ``sample(t)``
method that evaluates the whole time grid ``t`` (N,) [s] at once (vectorised,
no Python loop over samples, except :class:`Function` which calls user code
per sample unless ``vectorized=True``) and returns a :class:`Reference`:

- ``position`` (N, 3) [m] and ``linear_velocity`` (N, 3) [m/s] of the frame
  origin, in the world frame, for position trajectories;
- ``rotation`` (N, 3, 3) (world <- frame) and ``angular_velocity`` (N, 3)
  [rad/s] in the world frame (``LOCAL_WORLD_ALIGNED``), for orientation
  trajectories;
- both pairs for a :class:`PoseTrajectory`; the missing pair is ``None``.

Times are clipped to ``[0, duration]``: the trajectory holds its end values,
with zero velocity, outside it. Velocities are analytic derivatives of the
positions (chain rule through a :func:`trapezoidal_profile` of the path
coordinate), not finite differences. Bad arguments raise
:class:`clik.errors.InputError` naming the parameter; non-finite samples raise
``InputError("trajectory", "finite values", ...)`` naming the array and time.

Example (the paper's case study)::

    line = Line((0.5598, -0.15, 0.0), (0.8, -0.2, 0.0), duration=3.0, cruise_speed=0.12)
    reference = line.sample(time_grid(line.duration, 1e-3))
"""

from clik.trajectory.base import Trajectory
from clik.trajectory.circle import Circle
from clik.trajectory.function import Function
from clik.trajectory.grid import time_grid
from clik.trajectory.hold import Hold
from clik.trajectory.joint_path import JointPath, JointReference
from clik.trajectory.line import Line
from clik.trajectory.pose import PoseTrajectory
from clik.trajectory.profile import TrapezoidalProfile, trapezoidal_profile
from clik.trajectory.reference import Reference
from clik.trajectory.retimed import Retimed
from clik.trajectory.slerp import Slerp
from clik.trajectory.waypoints import Waypoints

__all__ = [
    "Circle",
    "Function",
    "Hold",
    "JointPath",
    "JointReference",
    "Line",
    "PoseTrajectory",
    "Reference",
    "Retimed",
    "Slerp",
    "Trajectory",
    "TrapezoidalProfile",
    "Waypoints",
    "time_grid",
    "trapezoidal_profile",
]
