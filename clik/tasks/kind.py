"""What every kind of task says, and what a run asks of it (docs/method.md, "Several tasks").

A task contributes ``m`` rows to the extended task (24)-(25) at every sample: its
error ``e = x_d - x`` (6), its Jacobian ``J`` (3) with ``edot = xdot_d - J qdot`` to
first order, and its reference's velocity ``xdot_d`` as feed-forward. The run owns
the levels, gains and references; a kind owns:

- its rows' names (:attr:`BaseTask.axes`) and the reference it reads, one vector of
  :attr:`BaseTask.reference_size` floats per sample (:meth:`BaseTask.reference_arrays`,
  from a trajectory's samples);
- its rows at a configuration (:meth:`BaseTask.fill`), and the two norms of its error
  a run reports (:meth:`BaseTask.error_norms`);
- its configuration for the compiled engine (:meth:`BaseTask.engine_goal`, one C++
  type in ``src/engine/tasks/``);
- what it takes as a controller's target for one tick (:meth:`BaseTask.tick_target`).

The kinds: :class:`~clik.tasks.task.Task` (a frame, in the world),
:class:`~clik.tasks.relative_task.RelativeTask` (a frame in another frame),
:class:`~clik.tasks.posture_task.PostureTask` (joints) and
:class:`~clik.tasks.com_task.ComTask` (the centre of mass).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pinocchio as pin

    from clik.model.robot import Robot
    from clik.tasks.targets import TickTarget


class BaseTask(ABC):
    """A kind of task: its rows, the reference it reads, its rows at a configuration.

    Attributes:
        robot: The robot.
        kind: The kind's name (``"pose"``, ``"position"``, ``"orientation"``,
            ``"posture"``, ``"com"``).
        m: Rows.
        reference_size: Floats of reference per sample.
    """

    robot: Robot
    kind: str
    m: int
    reference_size: int

    @property
    @abstractmethod
    def axes(self) -> list[str]:
        """Names of the rows, in row order."""

    @abstractmethod
    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """The reference per sample (n, reference_size) and the rows' feed-forward (n, m).

        Args:
            ref: What the task's trajectory's ``sample`` gave for ``n`` times.

        Raises:
            InputError: The trajectory lacks what the task reads (named).
        """

    @abstractmethod
    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        J: np.ndarray, e: np.ndarray,
    ) -> None:  # fmt: skip
        """Write the rows' Jacobian (m, nv) and error (m,) at ``q``.

        ``data`` holds the kinematics and every joint's Jacobian at ``q``
        (``computeJointJacobians``).
        """

    @abstractmethod
    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """``(first, second)`` norms of an error (m,): position [m] and orientation [rad].

        ``first`` is the error a run judges this task by (the orientation rows' for a
        task without position rows; the joints' [rad or m] for a posture); ``second``
        the orientation rows' (0 without).
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
