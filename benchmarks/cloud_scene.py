"""The point-cloud scene of the cloud lines (issue 45): a table, a box and a shelf, 50k points.

The points are sampled (fixed seed) on the surfaces of a table top in front of the
Panda, a tall box standing on it (its face toward the robot 0.42 m ahead of the base)
and a shelf's vertical board behind the robot (0.265 m behind the base). One
:class:`~clik.clouds.CloudObstacle` holds them (voxel 0.01 m, threshold 0.05 m); two
placements of that cloud give the two lines:

- ``near`` (the cloud where it was sampled): the arm between the box and the shelf,
  the elbow (``panda_link3``, at times ``panda_link4``) against the shelf and the wrist
  (``panda_link6``) against the box's face, each held at the threshold by its row;
- ``far`` (the same cloud 0.8 m to the robot's left): no link within the threshold.

The hand follows a small circle (the shipped ``panda_circle``'s plane and period, half
its radius: 0.05 m, one turn in 3 s) with a position task: the hand's orientation is left
free, so two cloud rows and the task's three rows fit the Panda's seven joints (with the
pose task, the start orientation kept, only the elbow's one redundant motion is left: the
same scene then holds one row, ``panda_link4``, measured).
A posture objective (the start posture, gain 2/s, in the null space of the rows and the
task) keeps pulling the elbow and the wrist back toward the shelf and the box, so the rows
stay active. Each line starts from its *settled* joints: the controller held at the
circle's first point for :data:`SETTLE_TICKS` ticks (the rows push the links out to the
threshold), untimed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import clik
from benchmarks.config import DT, BenchConfig
from benchmarks.step_lines import PSEUDOINVERSE, panda_setup
from clik.clouds import CloudObstacle
from clik.constraints import ConstraintSet
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.objectives import Objective
from clik.trajectory import time_grid

CLOUD = "scan"
"""The cloud's name (``ctl.update_cloud(CLOUD, points)``)."""
POINTS = 50_000
"""Points of the cloud."""
SEED = 45
"""Seed of the sampling (issue 45)."""
VOXEL = 0.01
"""Voxel edge [m]."""
THRESHOLD = 0.05
"""Threshold ``d_o`` of the cloud's rows [m]."""
POSTURE_GAIN = 2.0
"""Gain of the posture objective [1/s]."""
SETTLE_TICKS = 500
"""Ticks at the circle's first point before a line starts (untimed)."""
RADIUS = 0.05
"""Radius of the hand's circle [m] (half the shipped circle's)."""
PERIOD = 3.0
"""Duration of one turn [s] (the shipped circle's)."""

Point = tuple[float, float, float]
"""Three coordinates [m]."""
Rectangle = tuple[Point, Point, Point]
"""A planar rectangle: a corner and its two edges [m]."""

TABLE: tuple[Rectangle, ...] = (((0.25, -0.6, 0.30), (0.75, 0.0, 0.0), (0.0, 1.2, 0.0)),)
"""The table top, 0.30 m high, from 0.25 m in front of the base."""
BOX: tuple[Rectangle, ...] = (
    ((0.42, -0.25, 0.90), (0.2, 0.0, 0.0), (0.0, 0.7, 0.0)),  # top
    ((0.42, -0.25, 0.30), (0.0, 0.7, 0.0), (0.0, 0.0, 0.6)),  # face toward the robot
    ((0.62, -0.25, 0.30), (0.0, 0.7, 0.0), (0.0, 0.0, 0.6)),  # back
    ((0.42, -0.25, 0.30), (0.2, 0.0, 0.0), (0.0, 0.0, 0.6)),  # right side
    ((0.42, 0.45, 0.30), (0.2, 0.0, 0.0), (0.0, 0.0, 0.6)),  # left side
)
"""A 0.2 x 0.7 x 0.6 m box on the table: its five visible faces."""
SHELF: tuple[Rectangle, ...] = (((-0.265, -0.4, 0.0), (0.0, 0.8, 0.0), (0.0, 0.0, 1.1)),)
"""The shelf's vertical board behind the robot, 0.8 m wide, 1.1 m high."""
SURFACES = {"table": TABLE, "box": BOX, "shelf": SHELF}
"""Every surface sampled, by object."""

PLACEMENTS = {"near": (0.0, 0.0, 0.0), "far": (0.0, 0.8, 0.0)}
"""The cloud frame's origin in the world per line [m] (no rotation)."""


def scene_points(n: int = POINTS, seed: int = SEED) -> np.ndarray:
    """``n`` points on the scene's surfaces, uniform by area (fixed seed).

    Args:
        n: How many points.
        seed: Seed of the generator.

    Returns:
        ``(n, 3)`` points [m] in the cloud's frame.
    """
    rectangles = [r for surfaces in SURFACES.values() for r in surfaces]
    corners, u, v = (np.array([r[i] for r in rectangles]) for i in range(3))
    areas = np.linalg.norm(np.cross(u, v), axis=1)
    rng = np.random.default_rng(seed)
    which = rng.choice(len(rectangles), size=n, p=areas / areas.sum())
    s, t = rng.random((2, n, 1))
    return np.ascontiguousarray(corners[which] + s * u[which] + t * v[which])


@dataclass(frozen=True)
class CloudSetup:
    """The Panda's hand position task on the small circle, and the scene's points.

    Attributes:
        robot: The Panda (fingers locked).
        task: Position task of the hand.
        positions: The hand's desired position at every tick (n, 3) [m].
        velocities: Its feed-forward at every tick (n, 3) [m/s].
        q0: The circle's start configuration (the posture objective's posture).
        points: The cloud's points in its frame (POINTS, 3) [m].
    """

    robot: clik.Robot
    task: clik.Task
    positions: np.ndarray
    velocities: np.ndarray
    q0: np.ndarray
    points: np.ndarray

    @property
    def ticks(self) -> int:
        """Ticks of a run (one per reference sample)."""
        return len(self.positions)


def small_circle(p0: np.ndarray, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """The hand's reference: :data:`RADIUS` circle in the plane x = const from ``p0``.

    One turn in :data:`PERIOD`, started at ``p0`` going up (+z), centred at ``p0 +
    (0, RADIUS, 0)``: the shipped circle's plane and period, half its radius.

    Args:
        p0: The hand's start position [m].
        duration: Length of the run [s] (a turn at most).

    Returns:
        Positions (n, 3) [m] and velocities (n, 3) [m/s] at the ticks ``k dt``.
    """
    t = time_grid(min(duration, PERIOD), DT)
    w = 2.0 * np.pi / PERIOD
    zero = np.zeros_like(t)
    positions = p0 + RADIUS * np.column_stack([zero, 1.0 - np.cos(w * t), np.sin(w * t)])
    velocities = RADIUS * w * np.column_stack([zero, np.sin(w * t), np.cos(w * t)])
    return np.ascontiguousarray(positions), np.ascontiguousarray(velocities)


def cloud_setup(config: BenchConfig) -> CloudSetup:
    """The setup of the cloud lines: the small circle cut to ``config.panda_duration``.

    Args:
        config: Sizes of the suite.
    """
    panda = panda_setup(config)
    task = clik.Task(panda.robot, "panda_hand", "position")
    positions, velocities = small_circle(
        task.placement(panda.q0).translation, config.panda_duration
    )
    return CloudSetup(panda.robot, task, positions, velocities, panda.q0, scene_points())


def cloud_obstacle(setup: CloudSetup, placement: str) -> CloudObstacle:
    """The scene's cloud at one of :data:`PLACEMENTS`.

    Args:
        setup: The setup (its points).
        placement: ``"near"`` or ``"far"``.
    """
    return CloudObstacle(CLOUD, setup.points, voxel=VOXEL, position=PLACEMENTS[placement])


def cloud_controller(setup: CloudSetup, placement: str) -> tuple[clik.Controller, np.ndarray]:
    """The compiled controller of a line, and the settled joints its runs start from.

    Law (10) with the tick lines' gain, the cloud's rows (:class:`CloudAvoidance`,
    threshold :data:`THRESHOLD`) and the posture objective; the settled joints are the
    controller's after :data:`SETTLE_TICKS` ticks at the circle's first point.

    Args:
        setup: The setup.
        placement: ``"near"`` or ``"far"``.
    """
    cloud = cloud_obstacle(setup, placement)
    constraints = ConstraintSet(setup.robot, kinds=[CloudAvoidance([cloud], threshold=THRESHOLD)])
    ctl = clik.Controller(
        setup.task,
        law=PSEUDOINVERSE.law,
        gain=PSEUDOINVERSE.gain,
        dt=DT,
        constraints=constraints,
        objectives=[Objective("posture", gain=POSTURE_GAIN, posture=setup.q0)],
        engine="compiled",
        q0=setup.q0,
    )
    start, at_rest = setup.positions[0], np.zeros(3)
    for _ in range(SETTLE_TICKS):
        ctl.step(start, at_rest)
    settled = ctl.q.copy()
    ctl.reset(settled)
    return ctl, settled
