"""A run replayed in MuJoCo: the physics check of ``clik simulate`` (docs/method.md (P1)).

The robot compiled by MuJoCo (:mod:`clik.sim.mujoco_model`) follows the run's joints
through the servos of :mod:`clik.sim.servo`, with gravity compensation; the joint
reference is the run's ``q`` interpolated linearly between samples and its slope is the
velocity fed forward. At each of the run's sample times the replay records the joints
MuJoCo reached, each task point's distance from its reference (:mod:`clik.sim.tasks`),
the smallest distance from the robot's geoms to the obstacles
(``mujoco.mj_geomDistance``) and which servos hit their force limit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clik.errors import InputError
from clik.model.robot import Robot
from clik.outputs.result import TrackingResult
from clik.sim.mujoco_model import POINT_RADIUS, MujocoRobot, robot_spec
from clik.sim.obstacles import add_obstacles
from clik.sim.report import Simulation
from clik.sim.servo import KP, KV, TIMESTEP, add_servos, servo_control
from clik.sim.tasks import task_points

DISTANCE_CAP = 10.0
"""Distances [m] beyond this are not resolved (``mj_geomDistance``'s ``distmax``)."""


def mujoco_module() -> Any:
    """The ``mujoco`` module (a dependency of clik; named if it is missing)."""
    try:
        import mujoco
    except ImportError:  # pragma: no cover - a dependency of clik
        raise InputError(
            "mujoco", "the mujoco package (pip install mujoco): clik simulate replays in it"
        ) from None
    return mujoco


def _scenario_run(result: TrackingResult, robot: Robot) -> Any | None:
    """The run's scenario, rebuilt with its robot, when its file is found (else None)."""
    from clik.errors import ClikError
    from clik.scenarios.runner import build

    file = result.info.get("scenario_file")
    if not file or not Path(file).is_file():
        return None
    try:
        return build(file, robot=robot)
    except ClikError:
        return None


def _checked(kp: float, kv: float, timestep: float) -> None:
    for name, value, low in (("kp", kp, 0.0), ("timestep", timestep, 0.0)):
        if isinstance(value, bool) or not (np.isfinite(value) and value > low):
            raise InputError(f"simulate.{name}", "a positive finite number", value)
    if isinstance(kv, bool) or not (np.isfinite(kv) and kv >= 0.0):
        raise InputError("simulate.kv", "a non-negative finite number", kv)


def _substeps(t: np.ndarray, timestep: float) -> tuple[int, float]:
    """Steps per sample interval and the step [s] that divides the interval exactly."""
    if len(t) < 2:
        raise InputError("simulate.result.t", "a run of at least two samples", len(t))
    interval = float(np.median(np.diff(t)))
    if not np.allclose(np.diff(t), interval, rtol=1e-6, atol=1e-12):
        raise InputError("simulate.result.t", "samples evenly spaced in time", "uneven times")
    sub = max(1, int(np.ceil(interval / timestep - 1e-9)))
    return sub, interval / sub


def clearance(
    mujoco: Any, model: Any, data: Any, pairs: list[tuple[int, int]], pads: np.ndarray
) -> float:
    """The smallest distance [m] between the geoms of each pair (capped).

    Args:
        mujoco: The imported ``mujoco`` module.
        model: The compiled model.
        data: Its data, kinematics current.
        pairs: (robot geom, obstacle geom) pairs.
        pads: Per pair, the radii given to geoms of radius 0 for MuJoCo, added back.
    """
    best = DISTANCE_CAP
    fromto = np.zeros(6)
    for (g, o), pad in zip(pairs, pads, strict=True):
        best = min(best, mujoco.mj_geomDistance(model, data, g, o, DISTANCE_CAP, fromto) + pad)
    return best


@dataclass
class Scene:
    """The compiled model and what the replay reads and writes in it."""

    model: Any
    data: Any
    qadr: np.ndarray  # clik's joints' qpos addresses
    dadr: np.ndarray  # their dof addresses
    mocap: list[int]  # each obstacle's mocap index
    pairs: list[tuple[int, int]]  # (robot geom, obstacle geom) measured
    pads: np.ndarray  # per pair, the radii given to geoms of radius 0


def compiled_scene(mujoco: Any, mj: MujocoRobot, obstacles: list[Any], step: float) -> Scene:
    """The robot with its servos (added before) and the obstacles, compiled."""
    spec = mj.spec
    spec.option.timestep = step
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    bodies = add_obstacles(mujoco, spec, obstacles)
    try:
        model = spec.compile()
    except ValueError as exc:
        raise InputError("robot", f"a model MuJoCo compiles ({exc})") from None
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in mj.joints.names]
    body_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in bodies]
    geom_body = np.asarray(model.geom_bodyid)
    held = [int(np.flatnonzero(geom_body == b)[0]) for b in body_ids]
    robot_geoms = [
        g for g in range(model.ngeom)
        if geom_body[g] != 0 and g not in held
        and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]  # fmt: skip
    point = [
        POINT_RADIUS if o.shape == "sphere" and o.params["radius"] == 0 else 0.0 for o in obstacles
    ]
    pairs = [(g, o) for o in held for g in robot_geoms]
    pads = np.array(
        [point[held.index(o)] + mj.pads.get(str(model.geom(g).name), 0.0) for g, o in pairs]
    )
    return Scene(
        model, mujoco.MjData(model), np.array([model.jnt_qposadr[i] for i in ids]),
        np.array([model.jnt_dofadr[i] for i in ids]),
        [int(model.body_mocapid[b]) for b in body_ids], pairs, pads,
    )  # fmt: skip


@dataclass
class _Trace:
    """What the replay records at the run's sample times, and per step."""

    reached: np.ndarray  # joints MuJoCo reached (N, n)
    clearance: np.ndarray  # smallest robot-obstacle distance (N,), NaN without obstacles
    saturated: np.ndarray  # per joint, steps at the force limit
    peak: np.ndarray  # per joint, largest |force| / limit


def _replay(
    mujoco: Any, scene: Scene, t: np.ndarray, angles: np.ndarray, obstacles: list[Any],
    sub: int, limit: np.ndarray, servo: tuple[float, float, bool],
) -> _Trace:  # fmt: skip
    """Step the model along the joint reference: ``sub`` steps per sample interval."""
    model, data = scene.model, scene.data
    kp, kv, feedforward = servo
    rate = np.diff(angles, axis=0) / np.diff(t)[:, None]  # the reference's slope
    n = len(t)
    trace = _Trace(np.empty_like(angles), np.full(n, np.nan), np.zeros(len(limit), int),
                   np.zeros(len(limit)))  # fmt: skip
    data.qpos[scene.qadr] = angles[0]
    data.qvel[scene.dadr] = rate[0] if feedforward else 0.0
    mujoco.mj_forward(model, data)
    for k in range(n):
        trace.reached[k] = data.qpos[scene.qadr]
        if obstacles:
            for o, m in zip(obstacles, scene.mocap, strict=True):
                data.mocap_pos[m] = o.placement(float(t[k])).translation
            mujoco.mj_kinematics(model, data)
            trace.clearance[k] = clearance(mujoco, model, data, scene.pairs, scene.pads)
        if k == n - 1:
            break
        for s in range(sub):
            a = s / sub
            q_r = (1.0 - a) * angles[k] + a * angles[k + 1]
            data.ctrl[:] = servo_control(q_r, rate[k], kp, kv, feedforward)
            mujoco.mj_step(model, data)
            ratio = np.abs(data.actuator_force) / limit
            trace.peak = np.maximum(trace.peak, ratio)
            trace.saturated += ratio >= 1.0 - 1e-9
    return trace


def simulate(
    result: TrackingResult,
    *,
    feedforward: bool = True,
    kp: float = KP,
    kv: float = KV,
    timestep: float = TIMESTEP,
    run: Any | None = None,
) -> Simulation:
    """Replay a run in MuJoCo (position servos of eq. (P1), gravity compensation).

    Args:
        result: A run with its robot (``result.robot``; e.g. from
            :func:`clik.viz.target.load_target` on an output folder of ``clik solve``).
        feedforward: Feed the run's joint velocities forward (else position servos only).
        kp: Servo stiffness [N m / rad or N / m].
        kv: Servo damping [N m s / rad or N s / m].
        timestep: Largest simulation step [s] (the run's sample interval is divided into
            equal steps no longer than this).
        run: The run's scenario (:class:`~clik.scenarios.runner.Run`) for its tasks and
            obstacles; default: rebuilt from ``info["scenario_file"]`` when found.

    Returns:
        The replay's measures (:class:`~clik.sim.report.Simulation`).

    Raises:
        InputError: No robot, a robot MuJoCo cannot drive (a base, a multi-DoF joint, no
            masses), bad gains, or uneven sample times.
    """
    mujoco = mujoco_module()
    _checked(kp, kv, timestep)
    robot = result.robot
    if robot is None:
        raise InputError("simulate.result.robot", "a result with its robot (load_target)")
    if run is None:
        run = _scenario_run(result, robot)
    mj = robot_spec(mujoco, robot)
    sub, step = _substeps(result.t, timestep)
    effort = np.asarray(robot.model.effortLimit)[mj.joints.idx_v]
    add_servos(mujoco, mj.spec, mj.joints.names, kp, kv, effort)
    constraints = getattr(getattr(run, "tracker", None), "constraints", None)
    obstacles = list(constraints.obstacles) if constraints is not None else []
    scene = compiled_scene(mujoco, mj, obstacles, step)
    angles = mj.joints.angles(result.q)
    limit = np.where(np.isfinite(effort) & (effort > 0), effort, np.inf)
    trace = _replay(mujoco, scene, result.t, angles, obstacles, sub, limit, (kp, kv, feedforward))
    q_sim = np.array(
        [mj.joints.configuration(qk, rk) for qk, rk in zip(result.q, trace.reached, strict=True)]
    )
    points = task_points(result, run)
    return Simulation(
        t=result.t, joints=mj.joints.names, q_run=angles, q_sim=trace.reached,
        task_names=[p.name for p in points],
        errors={p.name: p.errors(robot, q_sim) for p in points},
        run_errors={p.name: p.errors(robot, result.q) for p in points},
        min_clearance=trace.clearance if obstacles else None,
        obstacles=[o.name for o in obstacles],
        saturated_steps=trace.saturated, peak_force_ratio=trace.peak,
        steps=(len(result.t) - 1) * sub, feedforward=feedforward, kp=kp, kv=kv,
        timestep=step, dropped=mj.dropped, mujoco_version=str(mujoco.__version__),
    )  # fmt: skip
