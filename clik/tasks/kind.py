"""What every kind of task says, and what a run asks of it (docs/method.md, "Several tasks").

A task contributes ``m`` rows to the extended task (24)-(25) at every sample: its
error ``e = x_d - x`` (6), its Jacobian ``J`` (3) with ``edot = xdot_d - J qdot`` to
first order, and its reference's velocity ``xdot_d`` as feed-forward. The run owns
the levels, gains and references; a kind owns everything particular to it, and the
loop, the laws, the controller, the scenario runner, the summary and the views ask it
through this protocol, never by its name:

- its ``[[tasks]]`` scenario table (:meth:`BaseTask.read_table`, keys and units), the
  task it describes (:meth:`BaseTask.from_spec`) and the trajectory that table gives,
  starting where the task is at the start (:meth:`BaseTask.trajectory_from`; its
  value held by default);
- its rows' names (:attr:`BaseTask.axes`) and the reference it reads, one vector of
  :attr:`BaseTask.reference_size` floats and :attr:`BaseTask.ff_size` floats of
  feed-forward per sample (:meth:`BaseTask.reference_arrays`, from a trajectory's
  samples);
- its rows at a configuration (:meth:`BaseTask.fill`), the two norms of its error a
  run reports (:meth:`BaseTask.error_norms`) and what they measure
  (:attr:`BaseTask.norms`: the summary's ``task_errors`` words and units);
- its configuration for the compiled engine (:meth:`BaseTask.engine_goal`, one C++
  type in ``src/engine/tasks/``);
- what it takes as a controller's target for one tick (:meth:`BaseTask.tick_target`);
- what the 3-D view draws of it (:meth:`BaseTask.trail`);
- whether it may be a run's *primary* task (:attr:`BaseTask.leads`: a frame in the
  world, whose trail is the run's ``position`` and which the constraint kinds that guard
  "the task" read).

The kinds are listed once, in :mod:`clik.tasks.registry`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:
    from pathlib import Path

    import pinocchio as pin

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.tasks.targets import TickTarget
    from clik.trajectory.base import Trajectory


@dataclass(frozen=True)
class Norm:
    """What one of a task's two error norms measures: ``"position error"``, in ``"m"``.

    Attributes:
        what: In words (a plot's label, a reason's).
        unit: Its unit: ``"m"``, ``"rad"``, or ``"rad, m"`` (a norm over both); the run's
            tolerance is the position one for ``"m"``, the orientation one otherwise.
    """

    what: str
    unit: str


class BaseTask(ABC):
    """A kind of task: its rows, the reference it reads, its rows at a configuration.

    Attributes:
        names: The ``[[tasks]] kind`` names whose tables this class reads.
        robot: The robot.
        kind: The kind's name (one of :attr:`names`).
        m: Rows.
        reference_size: Floats of reference per sample.
        leads: Whether it may be a run's primary task (a frame in the world).
        table_keys: Its ``[[tasks]]`` table's keys and what they mean, in Markdown: its
            row of the scenario guide's table of kinds (docs/guides/scenarios.md, made
            from these by docs/hooks/task_kinds.py). Empty: a kind read from another
            kind's table, documented there.
        table_trajectory: What its ``[tasks.trajectory]`` takes, in Markdown (same row).
        example: A shipped scenario that uses it (``clik.scenarios``), or None.
    """

    names: ClassVar[tuple[str, ...]] = ()
    leads: ClassVar[bool] = False
    table_keys: ClassVar[str] = ""
    table_trajectory: ClassVar[str] = ""
    example: ClassVar[str | None] = None
    robot: Robot
    kind: str
    m: int
    reference_size: int

    @property
    def ff_size(self) -> int:
        """Floats of feed-forward per sample: the rows' own, ``m``.

        A kind whose rows' feed-forward depends on the configuration reads the reference's
        velocity instead (its size), which :meth:`fill` maps to its rows.
        """
        return self.m

    # -- the scenario ------------------------------------------------------------------

    @classmethod
    @abstractmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """Its keys of one ``[[tasks]]`` table and its ``[tasks.trajectory]``, checked.

        ``name``, ``kind``, ``priority`` and ``gain`` are read for every kind.

        Raises:
            ScenarioError: A bad key, named.
        """

    @classmethod
    def builds(cls, spec: dict[str, Any]) -> bool:
        """Whether the task a table read describes is of this kind.

        By default its ``kind`` is one of :attr:`names`; a kind that refines another's
        table (a relative task: a frame table naming ``relative_to``) says when.
        """
        return spec["kind"] in cls.names

    @classmethod
    def leads_spec(cls, spec: dict[str, Any]) -> bool:
        """Whether the task a table describes may be a run's primary task."""
        return cls.leads

    @classmethod
    @abstractmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The task of a table read by :meth:`read_table`.

        Raises:
            InputError: A value the robot refuses (``task.<key>``); FrameNotFound,
                JointNotFound.
        """

    @abstractmethod
    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The trajectory of its ``[tasks.trajectory]``, from where it is at ``q0``.

        Raises:
            InputError: A value of the wrong size or range (its field).
        """

    # -- the rows ----------------------------------------------------------------------

    @property
    @abstractmethod
    def axes(self) -> list[str]:
        """Names of the rows, in row order."""

    @property
    @abstractmethod
    def norms(self) -> tuple[Norm, Norm | None]:
        """What its error norms (:meth:`error_norms`) measure: the first, the second or None."""

    @abstractmethod
    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """The reference per sample (n, reference_size) and its feed-forward (n, ff_size).

        Args:
            ref: What the task's trajectory's ``sample`` gave for ``n`` times.

        Raises:
            InputError: The trajectory lacks what the task reads (named).
        """

    @abstractmethod
    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """Write the rows' Jacobian (m, nv), error (m,) and feed-forward (m,) at ``q``.

        ``data`` holds the kinematics and every joint's Jacobian at ``q``
        (``computeJointJacobians``); ``ref`` and ``ff`` are this sample's.
        """

    @abstractmethod
    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """``(first, second)`` norms of an error (m,), as :attr:`norms` says (second 0 without).

        ``first`` is the error a run judges this task by.
        """

    @abstractmethod
    def engine_goal(self, engine: Any) -> Any:
        """This task as the compiled engine's goal (``_engine.FrameGoal`` ...)."""

    @abstractmethod
    def tick_target(self) -> TickTarget:
        """What it takes as a controller's target for one tick (:mod:`clik.tasks.targets`)."""

    @abstractmethod
    def describe(self) -> str:
        """The task in words, for reasons and reports."""

    # -- the view ----------------------------------------------------------------------

    def trail(
        self, model: pin.Model, data: pin.Data, ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None] | None:
        """The point the 3-D view draws of it at one sample, or None: nothing.

        ``(achieved, reference)`` [m] in the world, the reference None where it has no
        point. ``data`` holds the placements of every frame and the centre of mass at the
        sample; ``ref`` is its reference there (as :meth:`reference_arrays` gives it).
        """
        return None
