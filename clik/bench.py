"""``clik bench``: the performance suite of issue 6, with pink side by side, in one process.

What is measured (all through clik's public API, on the machine it runs on):

- **Step cost** [us per sample]: whole runs of :meth:`clik.Tracker.run`,
  ``result.wall_time_s / result.steps`` (the loop's own cost: kinematics, law,
  constraints, recording; the trajectory is sampled before the clock starts).
  Lines: the planar 4R arm on the case study's line (law (9)); the Panda's pose
  task on the shipped circle (``panda_circle``) with law (10) and with law (9)
  (per-row gains inside the explicit-Euler bound); the same with three sphere
  obstacles against every link's convex collision geometry and joint-range
  rows monitored, placed so that no obstacle row, or one, is active; and
  pink's step (``FrameTask`` + ``PostureTask``, ``ConfigurationLimit``,
  ``solve_ik`` + ``integrate_inplace``) on the same model and reference.
- **Single-pose solve**: seeded random reachable Panda poses (forward kinematics
  of random configurations inside the limits), from the reference
  configuration, tolerance 1e-4 m and 1e-3 rad, checked independently of each
  solver (``|p_d - p|`` and ``|log3(R_d R^T)|``): :func:`clik.solve` against
  pink iterated to convergence (capped) on the same targets.
- **Case study**: the eight shipped runs (:data:`clik.demo.CASE_STUDY`), total
  wall time of ``execute()``, with and without building (robot loading).
- **Memory**: peak RSS growth of a 10^6-sample planar run with full recording
  and with ``record_every`` decimation, each in a fresh subprocess.

Fairness: the compared step variants run interleaved, one whole run of each
per round (the order rotates every round) after one warm-up run each, and the
solve benchmark alternates clik and pink target by target. Figures are medians
over rounds (or targets) with p10 and p90; ratios are pink's median over
clik's median from the same rounds.

``run_bench(out)`` writes ``out/bench.json`` and ``out/bench.md``; pink
(``pip install clik[bench]``) is optional: without it its lines are ``null``.
"""

from __future__ import annotations

import gc
import importlib.metadata
import json
import math
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.demo import CASE_STUDY, scenario_path
from clik.result import write_json
from clik.runner import build
from clik.trajectory import Line, Trajectory
from clik.trajectory.reference import Reference

# -- settings -----------------------------------------------------------------------------


@dataclass(frozen=True)
class BenchConfig:
    """Sizes of the suite.

    Attributes:
        rounds: Rounds of the step benchmark (every variant runs once per round).
        panda_duration: Length of the Panda runs [s] (the shipped circle lasts 3 s).
        solve_targets: Random reachable poses for the single-pose solve.
        pink_max_iterations: Iteration cap of pink's solve to convergence.
        case_study_rounds: Repeats of the eight case-study runs.
        memory_samples: Samples of the planar run whose peak RSS is measured.
        memory_record_every: Decimation of the memory run's decimated variant.
        sweep_runs: Runs of the timed sweep (issue 8's sweep line).
        sweep_repeats: Alternations of the 1- and 2-worker sweeps (median taken).
        seed: Seed of the random solve targets.
    """

    rounds: int = 11
    panda_duration: float = 3.0
    solve_targets: int = 1000
    pink_max_iterations: int = 100
    case_study_rounds: int = 5
    memory_samples: int = 1_000_000
    memory_record_every: int = 1000
    sweep_runs: int = 120
    sweep_repeats: int = 3
    seed: int = 6


FULL = BenchConfig()
QUICK = BenchConfig(
    rounds=1,
    panda_duration=0.1,
    solve_targets=4,
    pink_max_iterations=30,
    case_study_rounds=1,
    memory_samples=5_000,
    memory_record_every=100,
    sweep_runs=4,
    sweep_repeats=1,
)
"""Smoke settings (``--quick``): every line runs, with tiny counts, in a few seconds."""

DT = 1e-3
"""Sample time of every run [s]."""
POSITION_TOLERANCE = 1e-4
"""Single-pose solve: position tolerance [m]."""
ORIENTATION_TOLERANCE = 1e-3
"""Single-pose solve: orientation tolerance [rad]."""
PANDA_TRANSPOSE_GAIN = (1000.0, 1000.0, 1000.0, 400.0, 400.0, 400.0)
"""Law (9) gains of the Panda pose task [1/s], position then orientation rows.
``dt lambda_max(K^1/2 J J^T K^1/2)`` stays below 1.6 along the circle (explicit
Euler is stable below 2); one gain of 1000 for all rows gives 3.3 and diverges."""
OBSTACLE_RADIUS = 0.05
"""Radius of the three sphere obstacles [m]."""
OBSTACLES_NONE_ACTIVE = ((0.45, 0.25, 0.55), (-0.3, 0.1, 0.75), (0.3, 0.1, 0.25))
"""Sphere centres [m]: 0.056, 0.090 and 0.082 m from the nearest link along the circle,
inside the monitoring margin (coal is asked every sample) but beyond the 0.03 m threshold."""
OBSTACLES_ONE_ACTIVE = ((0.45, 0.25, 0.55), (-0.2, 0.18, 0.58), (0.3, 0.1, 0.25))
"""The second sphere moved against link 3: its row is active on every sample but the first."""
PINK_POSTURE_COST = 1e-3
"""Cost of pink's posture task in the step benchmark (the frame task's costs are 1)."""
PINK_DAMPING = 1e-8
"""Tikhonov damping of pink's QP (its default 1e-12 makes daqp fail on some solves)."""
PINK_LM_DAMPING = 1e-3
"""Levenberg-Marquardt damping of pink's frame task in the solve benchmark."""

REQUIRED_KEYS = (
    "step_us.planar4r",
    "step_us.panda_pose",
    "step_us.panda_pose_obstacles",
    "step_us.pink_panda_pose",
    "solve.success_rate",
    "solve.median_us",
    "solve.pink_median_us",
    "case_study_all_runs_s",
    "memory_growth_mb.decimated",
    "memory_growth_mb.full",
    "sweep_runs_per_s.1_worker",
    "sweep_runs_per_s.2_workers",
)
"""Dotted key paths ``bench.json`` always holds (pink's are ``null`` without pink)."""

Log = Callable[[str], None]


# -- small helpers ------------------------------------------------------------------------


def _stats(values: list[float] | np.ndarray) -> dict[str, float | int]:
    """Median, p10, p90, mean, min and count of ``values``."""
    arr = np.asarray(values, dtype=float)
    p10, median, p90 = np.percentile(arr, [10.0, 50.0, 90.0])
    return {
        "median": float(median),
        "p10": float(p10),
        "p90": float(p90),
        "mean": float(arr.mean()),
        "min": float(arr.min()),
        "n": int(arr.size),
    }


def _ratio(num: float | None, den: float | None) -> float | None:
    if num is None or den is None or den <= 0.0:
        return None
    return float(num) / float(den)


def _pose_errors(model: pin.Model, data: pin.Data, fid: int, q: np.ndarray, target: pin.SE3):
    """Position [m] and orientation [rad] errors of frame ``fid`` at ``q`` against ``target``."""
    pin.framesForwardKinematics(model, data, q)
    placement = data.oMf[fid]
    dp = target.translation - placement.translation
    rot = pin.log3(target.rotation @ placement.rotation.T)
    return math.sqrt(float(dp @ dp)), math.sqrt(float(rot @ rot))


class _Prefix(Trajectory):
    """The first ``duration`` seconds of a trajectory (``--quick`` runs)."""

    def __init__(self, inner: Trajectory, duration: float) -> None:
        self.inner = inner
        self.duration = min(float(duration), inner.duration)

    def sample(self, t: np.ndarray) -> Reference:
        return self.inner.sample(np.clip(np.asarray(t, dtype=float), 0.0, self.duration))


def _pink() -> tuple[Any, str | None, str | None]:
    """``(pink module, QP solver name, None)`` or ``(None, None, why not)``."""
    try:
        import pink
        import qpsolvers
    except ImportError as exc:
        return None, None, f"pink not installed ({exc}); pip install 'clik[bench]'"
    for solver in ("daqp", "quadprog"):
        if solver in qpsolvers.available_solvers:
            return pink, solver, None
    return None, None, "no daqp or quadprog for pink; pip install daqp"


def machine_info() -> dict[str, Any]:
    """CPU, core count, memory, OS, Python and load average (a noisy machine shows here)."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    memory_gb = None
    try:
        import psutil

        memory_gb = round(psutil.virtual_memory().total / 1e9, 2)
    except ImportError:
        pass
    info: dict[str, Any] = {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory_gb": memory_gb,
        "os": platform.platform(),
        "python": platform.python_version(),
    }
    if hasattr(os, "sched_getaffinity"):
        info["cores_available"] = len(os.sched_getaffinity(0))
    if hasattr(os, "getloadavg"):
        info["load_average_1min_start"] = round(os.getloadavg()[0], 2)
    return info


def _cpu_seconds() -> float:
    """CPU time of this process and its finished children (the memory runs) [s]."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def versions() -> dict[str, str | None]:
    """Versions of clik and of the packages it is compared with or built on."""
    out: dict[str, str | None] = {}
    for name in ("clik", "pin", "coal", "numpy", "pin-pink", "qpsolvers", "daqp", "quadprog"):
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    return out


# -- step cost ----------------------------------------------------------------------------


@dataclass
class _Variant:
    """One line of the step benchmark: ``run()`` returns (steps, wall [s], run info)."""

    name: str
    description: str
    run: Callable[[], tuple[int, float, dict[str, Any]]]


def _clik_variant(
    name: str, description: str, tracker: clik.Tracker, trajectory: Trajectory, q0: np.ndarray
) -> _Variant:
    def run() -> tuple[int, float, dict[str, Any]]:
        result = tracker.run(trajectory, q0)
        info: dict[str, Any] = {
            "status": result.status,
            "violations": len(result.violations),
            "max_task_error": float(result.max_task_error),
            "law": tracker.law,
        }
        if result.active_count is not None:
            info["active_rows_mean"] = float(np.mean(result.active_count))
            info["events"] = len(result.events)
            summary = result.summary()
            info["min_obstacle_distance_m"] = summary.get("min_obstacle_distance")
        return result.steps, result.wall_time_s, info

    return _Variant(name, description, run)


def _pink_step_variant(
    pink: Any,
    solver: str,
    robot: clik.Robot,
    task: clik.Task,
    trajectory: Trajectory,
    q0: np.ndarray,
    default_limits: bool = False,
) -> _Variant:
    """pink's tracking step on the same model, reference and start as clik's Panda lines.

    ``default_limits``: pink's own default (``limits=None``: configuration and velocity
    limits) instead of the configuration limits alone.
    """
    from pink.limits import ConfigurationLimit
    from pink.tasks import FrameTask, PostureTask

    model = robot.model
    t = clik.trajectory.time_grid(trajectory.duration, DT)
    ref = trajectory.sample(t)
    targets = [pin.SE3(R, p) for R, p in zip(ref.rotation, ref.position, strict=True)]
    frame_task = FrameTask(task.frame, position_cost=1.0, orientation_cost=1.0)
    posture_task = PostureTask(cost=PINK_POSTURE_COST)
    posture_task.set_target(q0)
    tasks = [frame_task, posture_task]
    limits = None if default_limits else [ConfigurationLimit(model)]
    configuration = pink.Configuration(model, model.createData(), q0)
    check_data = model.createData()
    n = len(targets)
    q_log = np.zeros((n, model.nq))

    def run() -> tuple[int, float, dict[str, Any]]:
        configuration.update(q0)
        status = "completed"
        steps = n
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            frame_task.set_target(targets[k])
            try:
                velocity = pink.solve_ik(
                    configuration, tasks, DT, solver=solver, damping=PINK_DAMPING, limits=limits
                )
            except Exception as exc:  # NoSolutionFound, NotWithinConfigurationLimits
                status, steps = f"failed: {type(exc).__name__}", k + 1
                break
            configuration.integrate_inplace(velocity, DT)
        wall = time.perf_counter() - start
        errors = [
            _pose_errors(model, check_data, task.frame_id, q_log[k], targets[k])[0]
            for k in range(steps)
        ]
        return steps, wall, {"status": status, "max_task_error": float(max(errors))}

    limits_text = (
        "pink's default limits (configuration + velocity)"
        if default_limits
        else ("ConfigurationLimit")
    )
    return _Variant(
        "pink_panda_pose_default_limits" if default_limits else "pink_panda_pose",
        f"pink {importlib.metadata.version('pin-pink')}: FrameTask + PostureTask "
        f"(cost {PINK_POSTURE_COST:g}), {limits_text}, {solver}, solve_ik + integrate",
        run,
    )


def _panda_setup(config: BenchConfig) -> tuple[clik.Robot, clik.Task, Trajectory, np.ndarray]:
    run = build(scenario_path("panda_circle"))
    trajectory = run.trajectory
    if config.panda_duration < trajectory.duration:
        trajectory = _Prefix(trajectory, config.panda_duration)
    return run.robot, run.task, trajectory, run.q0


def _obstacle_set(robot: clik.Robot, centres: tuple[tuple[float, ...], ...]) -> ConstraintSet:
    obstacles = [
        Obstacle(f"sphere{i}", "sphere", c, radius=OBSTACLE_RADIUS) for i, c in enumerate(centres)
    ]
    return ConstraintSet(robot, obstacles=obstacles, joint_limits=JointLimits(robot))


def step_variants(config: BenchConfig, pink: Any, solver: str | None) -> list[_Variant]:
    """Every line of the step benchmark, built once (robots loaded, trackers preallocated)."""
    planar = build(scenario_path("case_study_unconstrained"))
    both = build(scenario_path("case_study_both"))
    robot, task, trajectory, q0 = _panda_setup(config)
    pinv = {"law": "pseudoinverse", "gain": 1000.0}
    transpose = {"law": "transpose", "gain": PANDA_TRANSPOSE_GAIN}
    variants = [
        _clik_variant(
            "planar4r",
            "planar 4R, position task (x, y), the case study's line, law (9), no constraints",
            clik.Tracker(planar.task, law="transpose", gain=1000.0, dt=DT),
            planar.trajectory,
            planar.q0,
        ),
        _clik_variant(
            "planar4r_case_study_both",
            "planar 4R, case study run 4 (law (9), point obstacle and joint-range rows)",
            both.tracker,
            both.trajectory,
            both.q0,
        ),
        _clik_variant(
            "panda_pose",
            "Panda pose task, circle, law (10), no constraints",
            clik.Tracker(task, **pinv),
            trajectory,
            q0,
        ),
        _clik_variant(
            "panda_pose_transpose",
            "Panda pose task, circle, law (9) with per-row gains, no constraints",
            clik.Tracker(task, **transpose),
            trajectory,
            q0,
        ),
        _clik_variant(
            "panda_pose_obstacles_0_active",
            "Panda pose, law (10), 3 spheres vs all link hulls + joint-range rows, 0 rows active",
            clik.Tracker(task, **pinv, constraints=_obstacle_set(robot, OBSTACLES_NONE_ACTIVE)),
            trajectory,
            q0,
        ),
        _clik_variant(
            "panda_pose_obstacles_1_active",
            "Panda pose, law (10), 3 spheres vs all link hulls + joint-range rows, 1 row active",
            clik.Tracker(task, **pinv, constraints=_obstacle_set(robot, OBSTACLES_ONE_ACTIVE)),
            trajectory,
            q0,
        ),
        _clik_variant(
            "panda_pose_obstacles_transpose",
            "Panda pose, law (9), 3 spheres + joint-range rows, 1 row active",
            clik.Tracker(task, **transpose, constraints=_obstacle_set(robot, OBSTACLES_ONE_ACTIVE)),
            trajectory,
            q0,
        ),
    ]
    if pink is not None and solver is not None:
        variants.append(_pink_step_variant(pink, solver, robot, task, trajectory, q0))
        variants.append(
            _pink_step_variant(pink, solver, robot, task, trajectory, q0, default_limits=True)
        )
    return variants


def bench_steps(config: BenchConfig, pink: Any, solver: str | None, log: Log) -> dict[str, Any]:
    """Interleaved rounds of every step variant; per-variant statistics [us per step]."""
    variants = step_variants(config, pink, solver)
    for v in variants:  # warm-up: caches, lazy imports, first allocations
        v.run()
    samples: dict[str, list[float]] = {v.name: [] for v in variants}
    infos: dict[str, dict[str, Any]] = {}
    steps_of: dict[str, int] = {}
    for r in range(config.rounds):
        shift = r % len(variants)
        for v in variants[shift:] + variants[:shift]:
            gc.collect()
            steps, wall, info = v.run()
            samples[v.name].append(1e6 * wall / max(steps, 1))
            infos[v.name], steps_of[v.name] = info, steps
        log(f"  step round {r + 1}/{config.rounds}")
    out: dict[str, Any] = {}
    for v in variants:
        s = _stats(samples[v.name])
        out[v.name] = {
            "description": v.description,
            "median_us": s["median"],
            "p10_us": s["p10"],
            "p90_us": s["p90"],
            "min_us": s["min"],
            "runs": s["n"],
            "steps_per_run": steps_of[v.name],
            "realtime_factor": DT / (1e-6 * s["median"]),
            **infos[v.name],
        }
    return out


# -- single-pose solve --------------------------------------------------------------------


def solve_targets(robot: clik.Robot, task: clik.Task, count: int, seed: int) -> list[pin.SE3]:
    """Poses of the task frame at seeded random configurations inside the joint limits."""
    rng = np.random.default_rng(seed)
    data = robot.model.createData()
    targets = []
    for _ in range(count):
        q = robot.random_configuration(rng)
        pin.framesForwardKinematics(robot.model, data, q)
        targets.append(data.oMf[task.frame_id].copy())
    return targets


def bench_solve(config: BenchConfig, pink: Any, solver: str | None, log: Log) -> dict[str, Any]:
    """clik.solve and pink to convergence on the same random poses, alternating."""
    robot = clik.Robot.load("panda", lock=clik.robot.PANDA_FINGERS)
    task = clik.Task(robot, "panda_hand", "pose")
    model, fid = robot.model, task.frame_id
    q_ref = robot.q_reference
    targets = solve_targets(robot, task, config.solve_targets, config.seed)
    check = model.createData()

    pink_solve = None
    if pink is not None and solver is not None:
        from pink.limits import ConfigurationLimit
        from pink.tasks import FrameTask

        frame_task = FrameTask(
            task.frame, position_cost=1.0, orientation_cost=1.0, lm_damping=PINK_LM_DAMPING
        )
        limits = [ConfigurationLimit(model)]
        configuration = pink.Configuration(model, model.createData(), q_ref)
        cap = config.pink_max_iterations

        def pink_solve(target: pin.SE3) -> tuple[np.ndarray, int]:
            """Iterate pink's full step (dt = 1, so the velocity is the displacement)."""
            configuration.update(q_ref)
            frame_task.set_target(target)
            p_d, R_d = target.translation, target.rotation
            for it in range(cap + 1):
                placement = configuration.data.oMf[fid]
                dp = p_d - placement.translation
                rot = pin.log3(R_d @ placement.rotation.T)
                if (
                    math.sqrt(float(dp @ dp)) <= POSITION_TOLERANCE
                    and math.sqrt(float(rot @ rot)) <= ORIENTATION_TOLERANCE
                ) or it == cap:
                    break
                try:
                    velocity = pink.solve_ik(
                        configuration,
                        [frame_task],
                        1.0,
                        solver=solver,
                        damping=PINK_DAMPING,
                        limits=limits,
                    )
                except Exception:  # NoSolutionFound: counted as a failure
                    break
                configuration.integrate_inplace(velocity, 1.0)
            return configuration.q, it

    clik.solve(task, targets[0])  # warm-up
    if pink_solve is not None:
        pink_solve(targets[0])
    times, ok, iterations, attempts, reported = [], [], [], [], []
    pink_times, pink_ok, pink_iterations = [], [], []
    failures: list[int] = []
    for i, target in enumerate(targets):
        order = ("clik", "pink") if i % 2 == 0 else ("pink", "clik")
        for who in order:
            if who == "clik":
                start = time.perf_counter()
                res = clik.solve(task, target)
                times.append(time.perf_counter() - start)
                p_err, r_err = _pose_errors(model, check, fid, res.q, target)
                good = p_err <= POSITION_TOLERANCE and r_err <= ORIENTATION_TOLERANCE
                ok.append(good)
                reported.append(res.success)
                iterations.append(res.iterations)
                attempts.append(res.attempts)
                if not good:
                    failures.append(i)
            elif pink_solve is not None:
                start = time.perf_counter()
                q, it = pink_solve(target)
                pink_times.append(time.perf_counter() - start)
                p_err, r_err = _pose_errors(model, check, fid, q, target)
                pink_ok.append(p_err <= POSITION_TOLERANCE and r_err <= ORIENTATION_TOLERANCE)
                pink_iterations.append(it)
        if (i + 1) % max(1, len(targets) // 4) == 0:
            log(f"  solve {i + 1}/{len(targets)}")
    t_us = _stats(1e6 * np.asarray(times))
    ok_arr = np.asarray(ok)
    out: dict[str, Any] = {
        "targets": len(targets),
        "seed": config.seed,
        "tolerance_m": POSITION_TOLERANCE,
        "tolerance_rad": ORIENTATION_TOLERANCE,
        "success_rate": float(ok_arr.mean()),
        "reported_success_rate": float(np.mean(reported)),
        "median_us": t_us["median"],
        "p10_us": t_us["p10"],
        "p90_us": t_us["p90"],
        "mean_us": t_us["mean"],
        "median_us_successes": float(np.median(1e6 * np.asarray(times)[ok_arr]))
        if ok_arr.any()
        else None,
        "iterations_median": float(np.median(iterations)),
        "iterations_mean": float(np.mean(iterations)),
        "restarts_used_fraction": float(np.mean(np.asarray(attempts) > 1)),
        "failed_targets": failures[:20],
        "pink_success_rate": None,
        "pink_median_us": None,
    }
    if pink_times:
        p_us = _stats(1e6 * np.asarray(pink_times))
        pink_ok_arr = np.asarray(pink_ok)
        out.update(
            {
                "pink_success_rate": float(pink_ok_arr.mean()),
                "pink_median_us": p_us["median"],
                "pink_p10_us": p_us["p10"],
                "pink_p90_us": p_us["p90"],
                "pink_mean_us": p_us["mean"],
                "pink_median_us_successes": float(
                    np.median(1e6 * np.asarray(pink_times)[pink_ok_arr])
                )
                if pink_ok_arr.any()
                else None,
                "pink_iterations_median": float(np.median(pink_iterations)),
                "pink_max_iterations": config.pink_max_iterations,
                "pink_setup": (
                    f"FrameTask (lm_damping {PINK_LM_DAMPING:g}) + ConfigurationLimit, {solver}, "
                    f"damping {PINK_DAMPING:g}, dt = 1, from the reference configuration, "
                    "no restarts"
                ),
                "speedup_vs_pink": _ratio(p_us["median"], t_us["median"]),
            }
        )
    return out


# -- case study ---------------------------------------------------------------------------


def bench_case_study(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Wall time of the eight case-study runs, per round; medians over rounds."""
    with_build, execute, loop = [], [], []
    per_run: dict[str, list[float]] = {name: [] for name in CASE_STUDY}
    statuses: dict[str, str] = {}
    for r in range(config.case_study_rounds + 1):  # round 0 is a warm-up
        totals = [0.0, 0.0, 0.0]
        for name in CASE_STUDY:
            gc.collect()
            t0 = time.perf_counter()
            run = build(scenario_path(name))
            t1 = time.perf_counter()
            result = run.execute()
            t2 = time.perf_counter()
            totals[0] += t2 - t0
            totals[1] += t2 - t1
            totals[2] += result.wall_time_s
            statuses[name] = result.status
            if r > 0:
                per_run[name].append(t2 - t1)
        if r > 0:
            with_build.append(totals[0])
            execute.append(totals[1])
            loop.append(totals[2])
            log(f"  case study round {r}/{config.case_study_rounds}")
    s = _stats(execute)
    return {
        "all_runs_s": s["median"],
        "all_runs_p10_s": s["p10"],
        "all_runs_p90_s": s["p90"],
        "all_runs_with_build_s": _stats(with_build)["median"],
        "all_runs_loop_only_s": _stats(loop)["median"],
        "per_run_s": {name: float(np.median(v)) for name, v in per_run.items()},
        "status": statuses,
        "realtime_factor_per_run": 3.0 * len(CASE_STUDY) / s["median"],
        "rounds": config.case_study_rounds,
    }


# -- memory -------------------------------------------------------------------------------


def _proc_status_kb(field: str) -> int | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _rss_baseline() -> tuple[int, str]:
    """Reset the peak RSS where the OS allows it; return (baseline [bytes], method).

    Linux: writing 5 to ``/proc/self/clear_refs`` resets ``VmHWM`` (the peak RSS) to
    the current RSS, so the run's own peak is measured even below an earlier peak
    (imports). Elsewhere ``ru_maxrss`` cannot be reset: the growth is a lower bound.
    """
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        rss = _proc_status_kb("VmRSS")
        if rss is not None and _proc_status_kb("VmHWM") is not None:
            return rss * 1024, "VmHWM after clear_refs"
    except OSError:
        pass
    return _ru_maxrss_bytes(), "ru_maxrss (lower bound)"


def _ru_maxrss_bytes() -> int:
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(peak if sys.platform == "darwin" else peak * 1024)


def _peak_rss_bytes(method: str) -> int:
    if method.startswith("VmHWM"):
        hwm = _proc_status_kb("VmHWM")
        if hwm is not None:
            return hwm * 1024
    return _ru_maxrss_bytes()


def memory_child(samples: int, record_every: int) -> dict[str, Any]:
    """Run in a fresh interpreter: peak-RSS growth of one planar run of ``samples`` samples.

    The baseline is the RSS after loading the robot, building the tracker and a
    10-sample warm-up run (the peak is reset there, see :func:`_rss_baseline`);
    the growth is the peak RSS during the big run (trajectory sampling,
    recording, the result) minus that baseline [MB = 1e6 bytes].
    """
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    start = task.placement(q0).translation
    tracker = clik.Tracker(task, law="transpose", gain=1000.0, dt=DT)
    tracker.run(Line(start, [0.8, -0.2, 0.0], duration=10 * DT), q0)
    duration = (samples - 1) * DT
    line = Line(start, [0.8, -0.2, 0.0], duration=duration)
    gc.collect()
    base, method = _rss_baseline()
    result = tracker.run(line, q0, record_every=record_every)
    peak = _peak_rss_bytes(method)
    return {
        "samples": int(result.steps),
        "record_every": record_every,
        "status": result.status,
        "violations": len(result.violations),
        "method": method,
        "baseline_mb": base / 1e6,
        "peak_mb": peak / 1e6,
        "growth_mb": max(peak - base, 0) / 1e6,
        "recorded_samples": int(result.q.shape[0]),
        "wall_time_s": float(result.wall_time_s),
    }


def _memory_run(samples: int, record_every: int) -> dict[str, Any]:
    code = (
        "import json, sys\n"
        "from clik.bench import memory_child\n"
        "print(json.dumps(memory_child(int(sys.argv[1]), int(sys.argv[2]))))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, str(samples), str(record_every)],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"memory subprocess failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def bench_memory(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Peak RSS growth with full and with decimated recording, each in a fresh process."""
    full = _memory_run(config.memory_samples, 1)
    log("  memory: full recording done")
    decimated = _memory_run(config.memory_samples, config.memory_record_every)
    log("  memory: decimated recording done")
    return {"full": full, "decimated": decimated}


# -- report -------------------------------------------------------------------------------


def bench_sweep(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Runs per second of a sweep on a local Dask cluster of 1 and of 2 workers.

    The two cluster sizes alternate ``sweep_repeats`` times (medians taken), so a
    busy moment of the machine hits both.
    """
    from clik.sweep import sweep_rate

    rates: dict[int, list[float]] = {1: [], 2: []}
    for _ in range(config.sweep_repeats):
        for workers in (1, 2):
            rates[workers].append(sweep_rate(workers, config.sweep_runs))
            log(f"  sweep, {workers} worker(s): {rates[workers][-1]:.2f} runs/s")
    one, two = float(np.median(rates[1])), float(np.median(rates[2]))
    return {
        "runs": config.sweep_runs,
        "runs_per_s_1_worker": one,
        "runs_per_s_2_workers": two,
        "speedup_2_workers": two / one,
        "all_runs_per_s": {str(k): v for k, v in rates.items()},
    }


def _targets(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Issue 6's targets, each with the measured figure and whether it is met."""
    step, solve = report["step_us"], report["solve"]
    pink_step = step["pink_panda_pose"]
    obstacles_ratio = _ratio(pink_step, step["panda_pose_obstacles"])
    solve_ratio = _ratio(solve["pink_median_us"], solve["median_us"])

    def line(name: str, value: float | None, ok: bool | None, target: str) -> dict[str, Any]:
        return {"name": name, "target": target, "value": value, "met": ok}

    return [
        line("panda_pose [us]", step["panda_pose"], step["panda_pose"] <= 8.0, "<= 8 us per step"),
        line(
            "panda_pose_obstacles [us]",
            step["panda_pose_obstacles"],
            step["panda_pose_obstacles"] <= 20.0,
            "<= 20 us per step",
        ),
        line(
            "pink / panda_pose_obstacles",
            obstacles_ratio,
            None if obstacles_ratio is None else obstacles_ratio >= 8.0,
            ">= 8x",
        ),
        line(
            "solve success rate",
            solve["success_rate"],
            solve["success_rate"] >= 0.998,
            ">= 99.8 %",
        ),
        line("solve median [us]", solve["median_us"], solve["median_us"] <= 60.0, "<= 60 us"),
        line(
            "pink solve / clik solve",
            solve_ratio,
            None if solve_ratio is None else solve_ratio >= 10.0,
            ">= 10x",
        ),
        line(
            "case study, 8 runs [s]",
            report["case_study_all_runs_s"],
            report["case_study_all_runs_s"] < 0.5,
            "< 0.5 s",
        ),
        line(
            "sweep speed-up, 2 workers over 1",
            report["sweep"]["speedup_2_workers"],
            report["sweep"]["speedup_2_workers"] >= 1.7,
            ">= 1.7x",
        ),
        line(
            "decimated memory growth [MB]",
            report["memory_growth_mb"]["decimated"],
            report["memory_growth_mb"]["decimated"] < 50.0,
            "< 50 MB",
        ),
    ]


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "**no**"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{value:.{digits}g}"
    return str(value)


def markdown(report: dict[str, Any]) -> str:
    """``bench.md``: the step, solve, case-study, memory and target tables."""
    m = report["machine"]
    v = report["versions"]
    lines = [
        "# clik bench" + (" (quick: a smoke run with tiny counts, not figures)" * report["quick"]),
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, "
        f"load {m.get('load_average_1min_start', '-')} at start, CPU share "
        f"{m.get('cpu_share', '-')} (below 1: other processes ran; figures inflated). "
        f"clik {v['clik']}, pin {v['pin']}, coal {v['coal']}, numpy {v['numpy']}, "
        f"pink {v['pin-pink'] or '-'} ({report['pink']['solver'] or 'not run'}).",
        "",
        f"## Step cost [us per sample] (medians over {report['config']['rounds']} interleaved "
        "rounds of whole runs)",
        "",
        "| line | median | p10 | p90 | pink / this | real-time factor | law | status | "
        "max task error | active rows (mean) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    pink_median = report["step_us"]["pink_panda_pose"]
    for name, s in report["steps"].items():
        ratio = None if name.startswith("pink_") else _ratio(pink_median, s["median_us"])
        lines.append(
            f"| {name} | {s['median_us']:.2f} | {s['p10_us']:.2f} | {s['p90_us']:.2f} | "
            f"{_fmt(ratio)} | {s['realtime_factor']:.0f} | {s.get('law', 'pink')} | "
            f"{s['status']} | {_fmt(s['max_task_error'])} | {_fmt(s.get('active_rows_mean'))} |"
        )
    lines += ["", "Lines:", ""]
    lines += [f"- `{name}`: {s['description']}" for name, s in report["steps"].items()]
    sv = report["solve"]
    lines += [
        "",
        f"## Single-pose solve ({sv['targets']} random reachable Panda poses, "
        f"{sv['tolerance_m']:g} m / {sv['tolerance_rad']:g} rad, from the reference)",
        "",
        "| solver | success | median [us] | p10 [us] | p90 [us] | mean [us] | iterations "
        "(median) |",
        "|---|---|---|---|---|---|---|",
        f"| clik.solve | {100 * sv['success_rate']:.1f} % | {sv['median_us']:.1f} | "
        f"{sv['p10_us']:.1f} | {sv['p90_us']:.1f} | {sv['mean_us']:.1f} | "
        f"{sv['iterations_median']:.0f} |",
    ]
    if sv["pink_median_us"] is not None:
        lines.append(
            f"| pink (cap {sv['pink_max_iterations']}) | {100 * sv['pink_success_rate']:.1f} % | "
            f"{sv['pink_median_us']:.1f} | {sv['pink_p10_us']:.1f} | {sv['pink_p90_us']:.1f} | "
            f"{sv['pink_mean_us']:.1f} | {sv['pink_iterations_median']:.0f} |"
        )
        lines += ["", f"pink: {sv['pink_setup']}. Speed-up: {_fmt(sv['speedup_vs_pink'])}x."]
    cs = report["case_study"]
    mem = report["memory"]
    lines += [
        "",
        "## Case study and memory",
        "",
        "| line | value |",
        "|---|---|",
        f"| case study, 8 runs, execute() [s] (median of {cs['rounds']}) | "
        f"{cs['all_runs_s']:.3f} (p10 {cs['all_runs_p10_s']:.3f}, p90 "
        f"{cs['all_runs_p90_s']:.3f}) |",
        f"| case study, 8 runs, build + execute [s] | {cs['all_runs_with_build_s']:.3f} |",
        f"| case study, 8 runs, loop only (sum of wall_time_s) [s] | "
        f"{cs['all_runs_loop_only_s']:.3f} |",
        f"| Panda {report['panda_obstacles_run']['duration_s']:g} s run, 3 obstacles, 1 row "
        "active: wall [s], real-time factor | "
        f"{report['panda_obstacles_run']['wall_s']:.3f}, "
        f"{report['panda_obstacles_run']['realtime_factor']:.1f} |",
        f"| memory growth, {mem['full']['samples']} samples, full recording [MB] | "
        f"{mem['full']['growth_mb']:.1f} |",
        f"| memory growth, {mem['decimated']['samples']} samples, record_every = "
        f"{mem['decimated']['record_every']} [MB] | {mem['decimated']['growth_mb']:.1f} |",
        "",
        f"| sweep, {report['sweep']['runs']} runs, local Dask cluster [runs/s]: 1 worker, "
        f"2 workers, speed-up | {report['sweep']['runs_per_s_1_worker']:.2f}, "
        f"{report['sweep']['runs_per_s_2_workers']:.2f}, "
        f"{report['sweep']['speedup_2_workers']:.2f}x |",
        "",
        "## Targets (issues 6 and 8)",
        "",
        "| target | measured | wanted | met |",
        "|---|---|---|---|",
    ]
    for t in report["targets"]:
        lines.append(f"| {t['name']} | {_fmt(t['value'])} | {t['target']} | {_fmt(t['met'])} |")
    lines += ["", "Reproduce: `clik bench --out out/bench` (or `make bench`).", ""]
    return "\n".join(lines)


def run_bench(out: Path, quick: bool = False, log: Log | None = None) -> dict[str, Any]:
    """Run the suite and write ``out/bench.json`` and ``out/bench.md``.

    Args:
        out: Output folder (created if missing).
        quick: Smoke settings (:data:`QUICK`): the same report structure in a few seconds.
        log: Called with one line per stage (e.g. ``print``); default silent.

    Returns:
        The report written to ``bench.json``.
    """
    say: Log = log if log is not None else (lambda _line: None)
    config = QUICK if quick else FULL
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    pink, solver, why_not = _pink()
    report: dict[str, Any] = {
        "quick": quick,
        "config": asdict(config),
        "machine": machine_info(),
        "versions": versions(),
        "pink": {"solver": solver, "available": pink is not None, "reason": why_not},
    }
    started = time.perf_counter()
    cpu_started = _cpu_seconds()
    say("step cost (interleaved rounds)")
    steps = bench_steps(config, pink, solver, say)
    say("single-pose solve")
    solve = bench_solve(config, pink, solver, say)
    say("case study")
    case = bench_case_study(config, say)
    say("memory (two subprocesses)")
    memory = bench_memory(config, say)
    say("sweep on a local Dask cluster, 1 and 2 workers")
    sweep = bench_sweep(config, say)

    def median(name: str) -> float | None:
        return steps[name]["median_us"] if name in steps else None

    obstacles = steps["panda_pose_obstacles_1_active"]
    report.update(
        {
            "step_us": {
                "planar4r": median("planar4r"),
                "planar4r_case_study_both": median("planar4r_case_study_both"),
                "panda_pose": median("panda_pose"),
                "panda_pose_transpose": median("panda_pose_transpose"),
                "panda_pose_obstacles": median("panda_pose_obstacles_1_active"),
                "panda_pose_obstacles_0_active": median("panda_pose_obstacles_0_active"),
                "panda_pose_obstacles_1_active": median("panda_pose_obstacles_1_active"),
                "panda_pose_obstacles_transpose": median("panda_pose_obstacles_transpose"),
                "pink_panda_pose": median("pink_panda_pose"),
                "pink_panda_pose_default_limits": median("pink_panda_pose_default_limits"),
            },
            "steps": steps,
            "ratios": {
                "pink_over_panda_pose": _ratio(median("pink_panda_pose"), median("panda_pose")),
                "pink_over_panda_pose_obstacles": _ratio(
                    median("pink_panda_pose"), median("panda_pose_obstacles_1_active")
                ),
                "pink_over_solve": solve.get("speedup_vs_pink"),
            },
            "solve": solve,
            "case_study_all_runs_s": case["all_runs_s"],
            "case_study": case,
            "panda_obstacles_run": {
                "duration_s": config.panda_duration,
                "wall_s": obstacles["median_us"] * 1e-6 * obstacles["steps_per_run"],
                "realtime_factor": obstacles["realtime_factor"],
            },
            "memory_growth_mb": {
                "full": memory["full"]["growth_mb"],
                "decimated": memory["decimated"]["growth_mb"],
            },
            "memory": memory,
            "sweep_runs_per_s": {
                "1_worker": sweep["runs_per_s_1_worker"],
                "2_workers": sweep["runs_per_s_2_workers"],
            },
            "sweep": sweep,
        }
    )
    report["targets"] = _targets(report)
    report["bench_wall_time_s"] = time.perf_counter() - started
    # Below 1, other processes took the CPU during the bench: figures are inflated.
    report["machine"]["cpu_share"] = round(
        (_cpu_seconds() - cpu_started) / report["bench_wall_time_s"], 3
    )
    if hasattr(os, "getloadavg"):
        report["machine"]["load_average_1min_end"] = round(os.getloadavg()[0], 2)
    write_json(out / "bench.json", report)
    text = markdown(report)
    (out / "bench.md").write_text(text)
    return report


if __name__ == "__main__":  # python -m clik.bench --out DIR [--quick]
    import argparse

    parser = argparse.ArgumentParser(prog="python -m clik.bench")
    parser.add_argument("--out", type=Path, default=Path("out/bench"))
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    run_bench(args.out, quick=args.quick, log=print)
    print((args.out / "bench.md").read_text())
