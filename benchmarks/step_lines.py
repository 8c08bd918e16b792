"""The lines of the step benchmark: planar 4R, Panda pose with and without obstacles, pink.

Every clik line runs in the compiled engine and, as its ``python_`` twin, in the
Python one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import clik
from benchmarks.config import DT, BenchConfig
from benchmarks.pink_backend import Pink
from benchmarks.pink_barrier import pink_obstacles
from benchmarks.step_dual_arm import dual_arm_variants
from benchmarks.step_pink import pink_step_variant
from benchmarks.step_variant import Variant, clik_variant
from benchmarks.whole_body import humanoid_scene, step_variant
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.loop.laws import LawName
from clik.scenarios import scenario_path
from clik.scenarios.runner import Run, build
from clik.trajectory import Trajectory
from clik.trajectory.reference import Reference

PANDA_TRANSPOSE_GAIN = (1000.0, 1000.0, 1000.0, 400.0, 400.0, 400.0)
"""Law (9) gains of the Panda pose task [1/s], position then orientation rows.
``dt lambda_max(K^1/2 J J^T K^1/2)`` stays below 1.6 along the circle (explicit
Euler is stable below 2); one gain of 1000 for all rows gives 3.3 and diverges."""
ENGINES = ("compiled", "python")
"""The engines every clik line runs in, in report order (the compiled line keeps the
line's name; the Python one is prefixed ``python_``)."""
OBSTACLE_RADIUS = 0.05
"""Radius of the three sphere obstacles [m]."""
OBSTACLES_NONE_ACTIVE = ((0.45, 0.25, 0.55), (-0.3, 0.1, 0.75), (0.3, 0.1, 0.25))
"""Sphere centres [m]: 0.056, 0.090 and 0.082 m from the nearest link along the circle,
inside the monitoring margin (coal is asked every sample) but beyond the 0.03 m threshold."""
OBSTACLES_ONE_ACTIVE = ((0.45, 0.25, 0.55), (-0.2, 0.18, 0.58), (0.3, 0.1, 0.25))
"""The second sphere moved against link 3: its row is active on every sample but the first."""


class Prefix(Trajectory):
    """The first ``duration`` seconds of a trajectory (``--quick`` runs)."""

    def __init__(self, inner: Trajectory, duration: float) -> None:
        self.inner = inner
        self.duration = min(float(duration), inner.duration)

    def sample(self, t: np.ndarray) -> Reference:
        """The inner trajectory's samples, held at ``duration`` past it."""
        return self.inner.sample(np.clip(np.asarray(t, dtype=float), 0.0, self.duration))


@dataclass(frozen=True)
class PandaSetup:
    """The Panda's pose task on the shipped circle, shared by its lines.

    Attributes:
        robot: The Panda (fingers locked).
        task: Pose task of the hand.
        trajectory: The circle, cut to the configured duration.
        q0: Start configuration.
    """

    robot: clik.Robot
    task: clik.Task
    trajectory: Trajectory
    q0: np.ndarray


@dataclass(frozen=True)
class PandaLaw:
    """A control law of the Panda lines and its gains.

    Attributes:
        law: Name of the law.
        gain: One gain for every row, or one per row [1/s].
    """

    law: LawName
    gain: float | tuple[float, ...]


PSEUDOINVERSE = PandaLaw("pseudoinverse", 1000.0)
"""Law (10), one gain."""
TRANSPOSE = PandaLaw("transpose", PANDA_TRANSPOSE_GAIN)
"""Law (9), per-row gains inside the explicit-Euler bound."""


def panda_setup(config: BenchConfig) -> PandaSetup:
    """The shipped ``panda_circle`` scenario, cut to ``config.panda_duration``.

    Args:
        config: Sizes of the suite.
    """
    run = build(scenario_path("panda_circle"))
    trajectory = run.trajectory
    if config.panda_duration < trajectory.duration:
        trajectory = Prefix(trajectory, config.panda_duration)
    return PandaSetup(run.robot, run.task, trajectory, run.q0)


def obstacle_set(robot: clik.Robot, centres: tuple[tuple[float, ...], ...]) -> ConstraintSet:
    """Sphere obstacles at ``centres`` against every link, plus joint-range rows.

    Args:
        robot: The robot.
        centres: Sphere centres [m].
    """
    obstacles = [
        Obstacle(f"sphere{i}", "sphere", c, radius=OBSTACLE_RADIUS) for i, c in enumerate(centres)
    ]
    return ConstraintSet(robot, obstacles=obstacles, joint_limits=JointLimits(robot))


def panda_tracker(
    panda: PandaSetup,
    law: PandaLaw,
    centres: tuple[tuple[float, ...], ...] | None = None,
    engine: str = "compiled",
) -> clik.Tracker:
    """A tracker of the Panda's pose task, with its own obstacle set when ``centres`` is given.

    Args:
        panda: The Panda setup.
        law: Law and gains.
        centres: Sphere centres [m], or None for no constraints.
        engine: ``"compiled"`` or ``"python"``.
    """
    constraints = None if centres is None else obstacle_set(panda.robot, centres)
    return clik.Tracker(
        panda.task, law=law.law, gain=law.gain, dt=DT, constraints=constraints, engine=engine
    )


def engine_twin(tracker: clik.Tracker, engine: str) -> clik.Tracker:
    """A tracker with ``tracker``'s task, law, gains, constraints and settings in ``engine``.

    Args:
        tracker: The tracker copied.
        engine: ``"compiled"`` or ``"python"``.
    """
    return clik.Tracker(
        tracker.task,
        law=tracker.law,
        gain=[float(g) for g in tracker.K_task],
        dt=tracker.dt,
        damping=tracker.damping,
        beta_max=tracker.beta_max,
        constraints=tracker.constraints,
        engine=engine,
    )


def line_name(name: str, engine: str) -> str:
    """The key of a clik line in ``engine``: the name, ``python_``-prefixed for that engine.

    Args:
        name: The line's name (its compiled engine's key).
        engine: ``"compiled"`` or ``"python"``.
    """
    return name if engine == "compiled" else f"python_{name}"


def _described(description: str, engine: str) -> str:
    """A line's description, naming the engine when it is the Python one."""
    return description if engine == "compiled" else f"Python engine: {description}"


def planar_variants(planar: Run, both: Run, engine: str = "compiled") -> list[Variant]:
    """The planar 4R lines: the case study's line unconstrained, and its run 4.

    Args:
        planar: The built ``case_study_unconstrained`` scenario.
        both: The built ``case_study_both`` scenario.
        engine: ``"compiled"`` or ``"python"``.
    """
    return [
        clik_variant(
            line_name("planar4r", engine),
            _described(
                "planar 4R, position task (x, y), the case study's line, law (9), no constraints",
                engine,
            ),
            clik.Tracker(planar.task, law="transpose", gain=1000.0, dt=DT, engine=engine),
            planar.trajectory,
            planar.q0,
        ),
        clik_variant(
            line_name("planar4r_case_study_both", engine),
            _described(
                "planar 4R, case study run 4 (law (9), point obstacle and joint-range rows)",
                engine,
            ),
            engine_twin(both.tracker, engine),
            both.trajectory,
            both.q0,
        ),
    ]


PANDA_LINES: tuple[tuple[str, str, PandaLaw, tuple[tuple[float, ...], ...] | None], ...] = (
    ("panda_pose", "Panda pose task, circle, law (10), no constraints", PSEUDOINVERSE, None),
    (
        "panda_pose_transpose",
        "Panda pose task, circle, law (9) with per-row gains, no constraints",
        TRANSPOSE,
        None,
    ),
    (
        "panda_pose_obstacles_0_active",
        "Panda pose, law (10), 3 spheres vs all link hulls + joint-range rows, 0 rows active",
        PSEUDOINVERSE,
        OBSTACLES_NONE_ACTIVE,
    ),
    (
        "panda_pose_obstacles_1_active",
        "Panda pose, law (10), 3 spheres vs all link hulls + joint-range rows, 1 row active",
        PSEUDOINVERSE,
        OBSTACLES_ONE_ACTIVE,
    ),
    (
        "panda_pose_obstacles_transpose",
        "Panda pose, law (9), 3 spheres + joint-range rows, 1 row active",
        TRANSPOSE,
        OBSTACLES_ONE_ACTIVE,
    ),
)
"""The Panda lines of clik: (name, description, law, sphere centres or None)."""


def panda_variants(panda: PandaSetup, engine: str = "compiled") -> list[Variant]:
    """The Panda lines of clik (:data:`PANDA_LINES`), each with its own tracker.

    Args:
        panda: The Panda setup.
        engine: ``"compiled"`` or ``"python"``.
    """
    return [
        clik_variant(
            line_name(name, engine),
            _described(description, engine),
            panda_tracker(panda, law, centres, engine),
            panda.trajectory,
            panda.q0,
        )
        for name, description, law, centres in PANDA_LINES
    ]


def pink_variants(pink: Pink, panda: PandaSetup) -> list[Variant]:
    """The Panda lines of pink: configuration limits, its default limits, and the spheres.

    The third is the first with its collision barrier on :data:`OBSTACLES_ONE_ACTIVE`
    (:mod:`benchmarks.pink_barrier`).

    Args:
        pink: The installed pink and its QP solver.
        panda: The Panda setup.
    """
    args = (pink, panda.robot, panda.task, panda.trajectory, panda.q0)
    spheres = pink_obstacles(panda.robot, OBSTACLES_ONE_ACTIVE, OBSTACLE_RADIUS)
    return [
        pink_step_variant(*args),
        pink_step_variant(*args, default_limits=True),
        pink_step_variant(*args, obstacles=spheres),
    ]


def step_variants(config: BenchConfig, pink: Pink | None) -> list[Variant]:
    """Every line of the step benchmark, built once (robots loaded, trackers preallocated).

    clik's lines in the compiled engine, then their twins in the Python engine
    (``python_``-prefixed), then pink's.

    Args:
        config: Sizes of the suite.
        pink: The installed pink, or None to leave its lines out.
    """
    planar = build(scenario_path("case_study_unconstrained"))
    both = build(scenario_path("case_study_both"))
    panda = panda_setup(config)
    variants: list[Variant] = []
    for engine in ENGINES:
        variants += planar_variants(planar, both, engine) + panda_variants(panda, engine)
    if pink is not None:
        variants += pink_variants(pink, panda)
    humanoid = humanoid_scene()
    whole_body = [step_variant(humanoid, engine) for engine in ENGINES]
    return variants + dual_arm_variants(config, ENGINES, pink) + whole_body
