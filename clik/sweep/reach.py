r"""Reachability maps: single-pose IK over a grid of target points.

For every point ``p`` of a box sampled every ``step`` metres, :func:`clik.solve`
(law (10), damped, seeded restarts inside the joint limits) looks for ``q``
with the frame at ``p`` (a position task), or at the pose ``(R, p)`` with one
fixed orientation ``R`` (a pose task). Each point gets ``success``, the
``iterations`` used and, where solved, the manipulability

.. math::

    w(q) = \sqrt{\det(J(q) J(q)^T)}

of the task Jacobian ``J`` (``LOCAL_WORLD_ALIGNED``, the task's rows) at the
solution: zero at a singularity, larger where the frame moves freely. For a
position task ``w`` is in [m^m]; mixed units for a pose task.

With a scenario (``ReachSpec.scenario``, ``clik reach --scenario``), the robot, its
obstacles and its constraints come from the scenario file, and each point is solved
with ``constraints=`` (:mod:`clik.solving.constrained_solve`): a point whose unconstrained
pose misses a constraint and that the constrained law cannot reach clear of them is
*blocked*, a category of its own beside *unreachable*.

Points are solved in chunks, as Dask tasks (on the same local or remote cluster
as a sweep, :mod:`clik.sweep.cluster`); a worker loads the robot once (with a scenario, the
spec carries the file's contents, and each worker rebuilds the robot and the
:class:`~clik.constraints.ConstraintSet` from them once). The spec and the
map are in :mod:`clik.sweep.reach_data`; :func:`clik.sweep.reach_output.write_reach`
writes a map's table, description and HTML view.
"""

from __future__ import annotations

import math
import threading
import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError, RobotLoadError, ScenarioError
from clik.sweep.cluster import dask_client
from clik.sweep.progress import RunProgress
from clik.sweep.reach_data import BLOCKED, COLUMNS, ReachMap, ReachSpec

if TYPE_CHECKING:
    from distributed import Client

    from clik.constraints import ConstraintSet
    from clik.model.robot import Robot
    from clik.tasks.task import Task

__all__ = [
    "CHUNK",
    "MAX_POINTS",
    "ReachMap",
    "ReachSpec",
    "check_spec",
    "grid_points",
    "manipulability",
    "reach_map",
    "reach_objects",
    "solve_points",
]

MAX_POINTS = 2_000_000
"""Most points of one map (a guard against a typo in ``step``)."""

CHUNK = 64
"""Points solved per Dask task."""


def grid_points(box: Sequence[float], step: float) -> np.ndarray:
    """Points of ``box`` every ``step`` [m], bounds included, x fastest: (N, 3).

    Raises:
        InputError: ``box`` is not six finite numbers with min <= max, ``step`` is not
            positive, or there would be more than :data:`MAX_POINTS` points.
    """
    values = np.asarray(box, dtype=float).reshape(-1)
    if values.shape != (6,) or not np.all(np.isfinite(values)):
        raise InputError("box", "six finite numbers xmin ymin zmin xmax ymax zmax [m]", list(box))
    low, high = values[:3], values[3:]
    if np.any(high < low):
        raise InputError("box", "xmin <= xmax, ymin <= ymax, zmin <= zmax", list(box))
    if not (isinstance(step, int | float) and math.isfinite(step) and step > 0):
        raise InputError("step", "a positive number [m]", step)
    counts = np.floor((high - low) / step + 1e-9).astype(int) + 1
    total = int(np.prod(counts))
    if total > MAX_POINTS:
        raise InputError("step", f"a step giving at most {MAX_POINTS} points", f"{total} points")
    axes = [lo + step * np.arange(n) for lo, n in zip(low, counts, strict=True)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def manipulability(task: Task, q: np.ndarray) -> float:
    """``sqrt(det(J J^T))`` of the task Jacobian at ``q`` (0 at a singularity)."""
    J = task.jacobian(q)
    return math.sqrt(max(float(np.linalg.det(J @ J.T)), 0.0))


_local = threading.local()


def reach_objects(spec: ReachSpec) -> tuple[Robot, Task, ConstraintSet | None]:
    """The spec's robot, task and constraints (None without any), built once per worker thread.

    Raises:
        RobotLoadError, FrameNotFound, JointNotFound, ScenarioError: from building them.
    """
    key = (
        spec.robot, tuple(sorted(spec.lock.items())), spec.frame, spec.kind, spec.axes,
        spec.scenario, repr(spec.scenario_data),
    )  # fmt: skip
    cached = getattr(_local, "reach", None)
    if cached is None or cached[0] != key:
        cached = _local.reach = (key, *_build(spec))
    return cached[1], cached[2], cached[3]


def _build(spec: ReachSpec) -> tuple[Robot, Task, ConstraintSet | None]:
    """Load the robot, build the task and (with a scenario) its constraints."""
    from clik.model.robot import Robot
    from clik.tasks.task import Task

    axes = list(spec.axes) if spec.axes else None
    if spec.scenario is None:
        robot = Robot.load(spec.robot, lock=spec.lock or None)
        return robot, Task(robot, spec.frame, spec.kind, axes), None
    from clik.scenarios.build_constraints import build_constraints
    from clik.scenarios.scenario import parse_scenario

    scenario = parse_scenario(spec.scenario_data or {}, spec.scenario)
    source = scenario.robot
    lock = {**source["lock"], **spec.lock}
    try:
        robot = Robot.load(
            source["source"],
            package_dirs=source["package_dirs"] or None,
            lock=lock or None,
            srdf=source.get("srdf"),
        )
    except RobotLoadError as exc:
        raise ScenarioError(scenario.file, "robot.source", str(exc)) from None
    task = Task(robot, spec.frame, spec.kind, axes)
    if not scenario.has_constraints:
        return robot, task, None
    return robot, task, build_constraints(scenario, robot, task)


def solve_points(spec: ReachSpec, points: np.ndarray) -> dict[str, list[Any]]:
    """Solve each point (the Dask task); returns the map's columns for these points.

    Its warnings are returned too, under :data:`WARNINGS`, rather than printed by the worker.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = _solve_points(spec, points)
    # a worker process's warnings would print there in Python's raw format, once per worker:
    # they travel back with the columns and reach_map warns each distinct one once, here
    out[WARNINGS] = list(dict.fromkeys((w.category, str(w.message)) for w in caught))
    return out


WARNINGS = "_warnings"
"""Key of :func:`solve_points`'s answer holding its warnings, ``(category, message)`` pairs."""


def _solve_points(spec: ReachSpec, points: np.ndarray) -> dict[str, list[Any]]:
    """:func:`solve_points` without the warnings' bookkeeping."""
    import pinocchio as pin

    from clik.solving.solve_mode import solve

    robot, task, constraints = reach_objects(spec)
    rotation = None if spec.orientation_rpy is None else pin.rpy.rpyToMatrix(*spec.orientation_rpy)
    out: dict[str, list[Any]] = {c: [] for c in (*COLUMNS, BLOCKED)}
    for p in np.asarray(points, dtype=float).reshape(-1, 3):
        target = p if rotation is None else pin.SE3(rotation, p)
        result = solve(
            task,
            target,
            robot.q_reference,
            restarts=spec.restarts,
            tolerance=spec.tolerance,
            orientation_tolerance=spec.orientation_tolerance,
            seed=spec.seed,
            constraints=constraints,
            tracking_attempts=spec.tracking_attempts,
        )
        for name, value in zip(("x", "y", "z"), p, strict=True):
            out[name].append(float(value))
        out["success"].append(bool(result.success))
        out["iterations"].append(int(result.iterations))
        out["attempts"].append(int(result.attempts))
        out["position_error"].append(float(result.position_error))
        out["orientation_error"].append(float(result.orientation_error))
        out["manipulability"].append(manipulability(task, result.q) if result.success else None)
        out[BLOCKED].append(result.blocked)
    return out


def check_spec(spec: ReachSpec) -> np.ndarray:
    """Validate a spec here, before any task is sent; returns its grid points (N, 3).

    Raises:
        InputError: A bad box, step, orientation or tracking_attempts, or moving
            obstacles in the scenario.
        RobotLoadError, UnknownRobotError, FrameNotFound, JointNotFound, ScenarioError:
            from the robot, the task and the scenario's constraints.
    """
    points = grid_points(spec.box, spec.step)
    if not isinstance(spec.restarts, int) or isinstance(spec.restarts, bool) or spec.restarts < 0:
        raise InputError("restarts", "an integer >= 0", spec.restarts)
    if spec.orientation_rpy is not None:
        rpy = np.asarray(spec.orientation_rpy, dtype=float)
        if rpy.shape != (3,) or not np.all(np.isfinite(rpy)):
            raise InputError("orientation", "roll, pitch, yaw: three finite angles", rpy.tolist())
    attempts = spec.tracking_attempts
    if not isinstance(attempts, int) or isinstance(attempts, bool) or attempts < 0:
        raise InputError("tracking_attempts", "an integer >= 0", attempts)
    _, _, constraints = reach_objects(spec)
    moving = [] if constraints is None else [o.name for o in constraints.obstacles if o.moving]
    if moving:
        raise InputError("obstacles", "obstacles at rest in a reachability map", moving)
    return points


def reach_map(
    spec: ReachSpec,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Client | None = None,
    progress: bool | None = None,
) -> ReachMap:
    """Solve every grid point of ``spec`` on Dask (a local cluster, or ``scheduler``).

    Raises:
        InputError, RobotLoadError, FrameNotFound, JointNotFound: see :func:`check_spec`.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        points = check_spec(spec)
    shown = _rewarn([(w.category, str(w.message)) for w in caught], set())
    chunks = [points[i : i + CHUNK] for i in range(0, len(points), CHUNK)]
    bar = RunProgress(
        "reach", len(points), enabled=progress, unit="points", failed_label="unreachable"
    )
    start = time.perf_counter()
    try:
        if client is not None:
            parts = _solve_chunks(client, spec, chunks, bar)
        else:
            with dask_client(workers, scheduler) as own:
                parts = _solve_chunks(own, spec, chunks, bar)
    finally:
        bar.close()
    _rewarn([w for part in parts for w in part.get(WARNINGS, ())], shown)
    columns = {c: [v for part in parts for v in part[c]] for c in (*COLUMNS, BLOCKED)}
    return ReachMap.from_columns(spec, columns, time.perf_counter() - start)


def _rewarn(found: Sequence[tuple[type[Warning], str]], shown: set[str]) -> set[str]:
    """Warn each distinct ``(category, message)`` of ``found`` not yet in ``shown``, once.

    Returns:
        ``shown`` with the messages warned here added.
    """
    for category, message in found:
        if message not in shown:
            shown.add(message)
            warnings.warn(_warning(category, message), stacklevel=3)
    return shown


def _warning(category: type[Warning], message: str) -> Warning:
    """A ``category`` warning saying ``message``, also when its constructor takes more."""
    try:
        return category(message)
    except TypeError:  # MimicJointWarning(message, joints), ...: its data stayed on the worker
        warning = Warning.__new__(category)
        Warning.__init__(warning, message)
        return warning


def _solve_chunks(
    client: Client, spec: ReachSpec, chunks: list[np.ndarray], bar: RunProgress
) -> list[dict[str, list[Any]]]:
    """Solve the chunks as Dask tasks; their columns in chunk order (Ctrl-C cancels them)."""
    from distributed import as_completed

    futures = [client.submit(solve_points, spec, chunk, pure=False) for chunk in chunks]
    index = {f.key: i for i, f in enumerate(futures)}
    parts: list[dict[str, list[Any]] | None] = [None] * len(chunks)
    try:
        for future in as_completed(futures, loop=client.loop):
            part = future.result()
            parts[index[future.key]] = part
            bar.update(len(part["x"]), failed=len(part["x"]) - sum(part["success"]))
    except BaseException:
        client.cancel(futures)
        raise
    return [p for p in parts if p is not None]
