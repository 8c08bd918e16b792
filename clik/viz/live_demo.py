"""Online control, live: a target streamed tick by tick, an obstacle moving on its own.

The Panda's hand follows a target computed one tick at a time, as a teleoperation
device or a planner would stream it: a hand-drawn circle (its velocity given, the
feed-forward of (10)) or a random walk (positions only). A ball crosses the workspace
at constant speed; the controller (:class:`clik.Controller`) runs at 1 kHz, activates
and releases the ball's rows, and prints each event as it happens; a meshcat view on
127.0.0.1 is updated at 30 Hz.

Run it: ``python -m clik.viz.live_demo --target circle --seconds 10 --realtime``
(its URL is printed; ``--no-view`` to run without it).
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from collections.abc import Iterator, Sequence

import numpy as np

import clik
from clik.clouds import CloudObstacle
from clik.constraints import CloudAvoidance, ConstraintSet, JointLimits, Obstacle
from clik.viz.live import stop_server
from clik.viz.live_view import LiveView

DT = 1e-3
"""The control tick [s] (1 kHz)."""
VIEW_EVERY = 33
"""Ticks between two view updates (30 Hz at 1 kHz)."""
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}

Target = tuple[np.ndarray, np.ndarray | None]
"""A tick's target position [m] and, when known, its velocity [m/s]."""


def circle(centre: np.ndarray, radius: float, period: float) -> Iterator[Target]:
    """A circle in the y-z plane drawn at constant speed: position and velocity each tick."""
    w = 2.0 * math.pi / period
    for k in range(10**9):
        a = w * k * DT
        offset = np.array([0.0, math.sin(a), math.cos(a) - 1.0]) * radius
        velocity = np.array([0.0, math.cos(a), -math.sin(a)]) * radius * w
        yield centre + offset, velocity


def random_walk(start: np.ndarray, seed: int, reach: float = 0.12) -> Iterator[Target]:
    """A teleoperation-like target: a smoothed random walk within ``reach`` of ``start`` [m]."""
    rng = np.random.default_rng(seed)
    position, velocity = start.copy(), np.zeros(3)
    while True:
        velocity = 0.995 * velocity + rng.normal(0.0, 0.004, 3)  # [m/s]
        velocity -= 0.5 * DT * (position - start) / reach**2  # pulled back toward the start
        position = position + velocity * DT
        yield position.copy(), None  # a device gives positions only


def box_skin(half: np.ndarray, spacing: float) -> np.ndarray:
    """Points on a box's faces (centred at 0) every ``spacing`` [m]: a depth camera's box."""
    faces = []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        grid = np.meshgrid(*(np.arange(-half[a], half[a] + 1e-9, spacing) for a in (u, v)))
        for sign in (-1.0, 1.0):
            face = np.zeros((grid[0].size, 3))
            face[:, u], face[:, v], face[:, axis] = (
                grid[0].ravel(),
                grid[1].ravel(),
                sign * half[axis],
            )
            faces.append(face)
    return np.vstack(faces)


BOX = box_skin(np.array([0.06, 0.06, 0.12]), 0.005)
"""The sliding box's points in its own frame [m] (about 3,800)."""


def box_at(t: float) -> np.ndarray:
    """The sliding box's centre at time ``t`` [s]: from 0.4 m beside the hand toward the arm."""
    return np.array([0.31, 0.4 - 0.06 * min(t, 2.5), 0.59])


def scene(obstacle: str = "ball") -> tuple[clik.Robot, clik.Task, ConstraintSet]:
    """The Panda, its hand's position task, a ball moving across, and its joint ranges.

    ``obstacle = "cloud"``: a box seen as points instead, sliding toward the arm; each tick
    gives the controller its new points (``ctl.step(..., obstacles={"scan": points})``).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fingers are locked: mimic warning
        robot = clik.Robot.load("panda", lock=FINGERS)
    task = clik.Task(robot, "panda_hand", "position")
    ball = Obstacle(
        "ball", "sphere", [0.36, 0.2, 0.55], radius=0.03, velocity=[0.0, -0.04, 0.0]
    )  # passes just beside the hand's circle, from about 1.5 s
    if obstacle == "cloud":
        cloud = CloudObstacle("scan", BOX + box_at(0.0), voxel=0.01)
        kinds = [CloudAvoidance([cloud], threshold=0.04)]
        return robot, task, ConstraintSet(robot, kinds=kinds, joint_limits=JointLimits(robot))
    constraints = ConstraintSet(
        robot, obstacles=[ball], obstacle_threshold=0.04, joint_limits=JointLimits(robot)
    )
    return robot, task, constraints


def run(
    seconds: float = 10.0, target: str = "circle", view: bool = True, realtime: bool = False,
    seed: int = 0, say: bool = True, obstacle: str = "ball",
) -> tuple[clik.TrackingResult, int]:  # fmt: skip
    """Run the session; returns its result and the number of view updates.

    Args:
        seconds: Length of the session [s].
        target: ``"circle"`` or ``"walk"``.
        view: Update a meshcat view at 30 Hz (its URL is printed).
        realtime: Keep pace with the wall clock (else as fast as it runs).
        seed: The random walk's seed.
        say: Print the events and verdicts as they happen.
        obstacle: ``"ball"`` (a moving sphere) or ``"cloud"`` (a box's points, sliding).
    """
    robot, task, constraints = scene(obstacle)
    q0 = robot.q_reference.copy()
    start = task.placement(q0).translation
    stream = circle(start, 0.06, 4.0) if target == "circle" else random_walk(start, seed)
    ctl = clik.Controller(task, gain=100.0, dt=DT, constraints=constraints, q0=q0)
    live = None
    if view:
        live = LiveView(robot, constraints, targets=["target"])
        print(f"live view: {live.url}")
    verdict, wall0 = "ok", time.perf_counter()
    for k in range(round(seconds / DT)):
        position, velocity = next(stream)
        clouds = {"scan": BOX + box_at(k * DT)} if obstacle == "cloud" else None
        tick = ctl.step(position, velocity, obstacles=clouds)
        if say:
            for e in tick.events:
                print(f"t = {e['t']:7.3f} s  {e['action']:9s} {e['constraint']}")
            if tick.verdict != verdict:
                print(f"t = {tick.t:7.3f} s  verdict {tick.verdict}: {tick.reason}")
        verdict = tick.verdict
        if live is not None and k % VIEW_EVERY == 0:
            live.update(tick.q, tick.t, {"target": position}, clouds)
        if realtime:
            time.sleep(max(0.0, wall0 + (k + 1) * DT - time.perf_counter()))
    return ctl.result(), 0 if live is None else live.frames


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m clik.viz.live_demo``: see the module's docstring."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="session length [s]")
    parser.add_argument("--target", choices=("circle", "walk"), default="circle")
    parser.add_argument("--obstacle", choices=("ball", "cloud"), default="ball")
    parser.add_argument("--no-view", action="store_true", help="no meshcat view")
    parser.add_argument("--realtime", action="store_true", help="keep pace with the clock")
    args = parser.parse_args(argv)
    try:
        result, _ = run(
            args.seconds, args.target, not args.no_view, args.realtime, obstacle=args.obstacle
        )
    finally:
        stop_server()
    print(f"{result.status}: {result.reason}")
    print(f"largest task error {result.max_task_error:.3g} m, {len(result.events)} events")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
