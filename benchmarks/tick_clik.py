"""clik's per-tick lines: :class:`clik.Controller` stepped once per tick, as a user would.

Each tick calls ``ctl.step(x_d(t_k), (v_d, w_d)(t_k))``, the target a 4x4 float64
array (the input the README gives for speed; pink and mink get ``pin.SE3``, theirs): the
sample's own target and its feed-forward (law (10) takes both), and records the joints it
returns. The
timed loop is exactly that: one Python call per tick, targets built before the clock
starts (a controller's caller holds its target already).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

import clik
from benchmarks.config import DT
from benchmarks.step_lines import OBSTACLES_ONE_ACTIVE, PSEUDOINVERSE, PandaSetup, obstacle_set
from benchmarks.step_variant import RunOutcome
from benchmarks.tick_variant import TickReference, TickVariant


def _controller_run(
    ctl: clik.Controller, reference: TickReference, q0: np.ndarray, joints: np.ndarray
) -> RunOutcome:
    """One session over the whole reference: ``reset(q0)``, then one ``step`` per sample."""
    ctl.reset(q0)
    # one array per tick, as a caller holds them (pink's and mink's targets are lists too)
    poses, velocities = list(reference.matrices), list(reference.velocities)
    n = reference.ticks
    commanded = [q0]  # each tick's q is its own array: keeping it costs less than a copy
    tick = None
    start = time.perf_counter()
    for k in range(n):
        tick = ctl.step(poses[k], velocities[k])
        commanded.append(tick.q)
    wall = time.perf_counter() - start
    if n > 1 and np.shares_memory(commanded[1], commanded[-1]):
        raise RuntimeError("Controller.step returned one q array for every tick: copy it here")
    joints[:] = commanded
    result = ctl.result()
    info: dict[str, Any] = {
        "status": result.status,
        "violations": len(result.violations),
        "max_task_error": float(result.max_task_error),
        "final_error_m": None if tick is None else float(tick.errors["task"][0]),
        "law": ctl.tracker.law,
        "engine": ctl.tracker.engine,
    }
    if result.active_count is not None:
        info["active_rows_mean"] = float(np.mean(result.active_count))
    return n, wall, info


def clik_tick_variant(
    name: str, description: str, panda: PandaSetup, reference: TickReference, obstacles: bool
) -> TickVariant:
    """One clik tick line: the Panda's pose task, law (10), with or without the spheres.

    Args:
        name: Key of the line (``panda_pose`` or ``panda_pose_obstacles``).
        description: One sentence for ``bench.md``.
        panda: The Panda setup (robot, task, start).
        reference: The reference at every tick.
        obstacles: Whether to add :data:`~benchmarks.step_lines.OBSTACLES_ONE_ACTIVE` and
            the joint-range rows (:func:`~benchmarks.step_lines.obstacle_set`).
    """
    constraints = obstacle_set(panda.robot, OBSTACLES_ONE_ACTIVE) if obstacles else None
    ctl = clik.Controller(
        panda.task,
        law=PSEUDOINVERSE.law,
        gain=PSEUDOINVERSE.gain,
        dt=DT,
        constraints=constraints,
        q0=panda.q0,
    )
    joints = np.zeros((reference.ticks + 1, panda.robot.nq))
    q0 = panda.q0.copy()
    return TickVariant(
        name, description, lambda: _controller_run(ctl, reference, q0, joints), lambda: joints
    )


def clik_tick_variants(panda: PandaSetup, reference: TickReference) -> list[TickVariant]:
    """Clik's two tick lines: the pose task alone, and with three spheres and joint ranges.

    Args:
        panda: The Panda setup.
        reference: The reference at every tick.
    """
    return [
        clik_tick_variant(
            "panda_pose",
            "clik.Controller, Panda pose task, law (10), no constraints; each tick "
            "step(x_d(t_k) 4x4, (v_d, w_d)(t_k))",
            panda, reference, obstacles=False,
        ),
        clik_tick_variant(
            "panda_pose_obstacles",
            "clik.Controller, Panda pose task, law (10), 3 spheres vs all link hulls + "
            "joint-range rows (threshold 0.03 m, 1 row active); each tick "
            "step(x_d(t_k) 4x4, (v_d, w_d)(t_k))",
            panda, reference, obstacles=True,
        ),
    ]  # fmt: skip
