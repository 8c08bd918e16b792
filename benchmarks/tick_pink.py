"""pink's per-tick lines: one ``solve_ik`` + ``integrate_inplace`` per tick, as its examples run.

The same pink setting as the step lines (:mod:`benchmarks.step_pink`), given each
tick the look-ahead target ``x_d(t_k+1)``: pink's (and mink's) examples set the
target, then solve for the next configuration; ``x_d(t_k)`` would add one tick of
lag to its tracking error. With the spheres, its collision barrier
(:mod:`benchmarks.pink_barrier`).
"""

from __future__ import annotations

from benchmarks.pink_backend import Pink
from benchmarks.pink_barrier import pink_obstacles
from benchmarks.step_lines import OBSTACLE_RADIUS, OBSTACLES_ONE_ACTIVE, PandaSetup
from benchmarks.step_pink import pink_setup_text, pink_tracking
from benchmarks.tick_variant import TickVariant

LOOK_AHEAD = "each tick given x_d(t_k+1)"


def pink_tick_variant(pink: Pink, panda: PandaSetup, obstacles: bool) -> TickVariant:
    """Pink's tick line on the Panda's circle, with or without the spheres' barrier.

    Args:
        pink: The installed pink and its QP solver.
        panda: The Panda setup.
        obstacles: Whether to add the barrier on
            :data:`~benchmarks.step_lines.OBSTACLES_ONE_ACTIVE`.
    """
    barrier = (
        pink_obstacles(panda.robot, OBSTACLES_ONE_ACTIVE, OBSTACLE_RADIUS) if obstacles else None
    )
    tracking = pink_tracking(
        pink, panda.robot, panda.task, panda.trajectory, panda.q0, obstacles=barrier, lead=1
    )
    text = f"{pink_setup_text(pink)}, {LOOK_AHEAD}"
    name = "pink_panda_pose"
    if barrier is not None:
        name, text = "pink_panda_pose_obstacles", f"{text}; {barrier.description}"
    return TickVariant(name, text, tracking.run, tracking.joints)


def pink_tick_variants(pink: Pink, panda: PandaSetup) -> list[TickVariant]:
    """Pink's two tick lines: the pose task alone, and with the spheres' barrier.

    Args:
        pink: The installed pink and its QP solver.
        panda: The Panda setup.
    """
    return [pink_tick_variant(pink, panda, False), pink_tick_variant(pink, panda, True)]
