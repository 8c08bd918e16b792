"""What a task takes as a controller's target for one tick (docs/method.md, "Online control").

At each tick a controller is given each task's target (and, optionally, its velocity, the
feed-forward ``xdot_d`` of (10)). Each kind of task reads them with its reader: the forms
it accepts (their shapes), the checks of their numbers, and the one-sample reference and
feed-forward it writes (the arrays an offline run samples from its trajectory). The
compiled engine's readers are ``src/engine/tasks/targets.hpp``: the same forms, checks
and words, so both engines accept and refuse the same targets.

The numbers reach a reader as a float64 array (the controller converts anything else
once, :func:`clik.control.targets.as_floats`); a reader first says whether it takes the
array's shape (:meth:`FrameTarget.target_size`), then checks and reads the numbers
(:meth:`FrameTarget.read`), or says what is wrong (:class:`Refusal`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ROTATION_TOLERANCE = 1e-6
"""Largest ``|R^T R - I|`` (entrywise) and ``|det R - 1|`` of a rotation given as a target
(as :data:`clik.trajectory._validate.ROTATION_TOLERANCE`)."""

_IDENTITY = np.eye(3)


class Refusal(Exception):
    """What is wrong with a task's target or velocity, in :class:`~clik.errors.InputError`'s words.

    Attributes:
        velocity: The velocity is wrong (else the target).
        expected: What was expected.
        show: What to show as got: ``"values"`` (the numbers) or ``"last_row"`` (a 4x4's).
    """

    def __init__(self, velocity: bool, expected: str, show: str = "values") -> None:
        super().__init__(expected)
        self.velocity, self.expected, self.show = velocity, expected, show


@dataclass(frozen=True)
class FrameTarget:
    """A frame's pose (a frame task, in the world or in another frame), or a position.

    Target: a 4x4 homogeneous pose; a position (3,) [m] for a task without orientation
    rows; a rotation (3, 3) for a task without position rows. Velocity: ``(linear,
    angular)`` (6,) [m/s, rad/s], or (3,) for a task with one of the two.

    Attributes:
        pos: The task has position rows.
        rot: It has orientation rows.
        rows: Its rows among ``(x, y, z, rx, ry, rz)``.
        rotation_ref: Its reference holds a rotation after the position (a pose, 12
            floats); False: the position only (3: a centre of mass).
    """

    pos: bool
    rot: bool
    rows: tuple[int, ...]
    rotation_ref: bool = True

    def target_size(self, shape: tuple[int, ...]) -> int:
        """Floats read of a target of ``shape``, or -1: a form the task does not take."""
        if shape == (4, 4):
            return 16
        if shape == (3,) and not self.rot:
            return 3
        if shape == (3, 3) and not self.pos:
            return 9
        return -1

    def velocity_size(self, shape: tuple[int, ...] | None) -> int:
        """Floats read of a velocity of ``shape`` (None: none given, 0), or -1."""
        if shape is None:
            return 0
        if shape == (6,):
            return 6
        if shape == (3,) and not (self.pos and self.rot):
            return 3
        return -1

    def target_forms(self) -> str:
        """The forms of target it takes, in words."""
        return (
            "a pin.SE3 or a 4x4 pose"
            + ("" if self.rot else ", or a position (3,)")
            + ("" if self.pos else ", or a rotation (3, 3)")
        )

    def velocity_forms(self) -> str:
        """The forms of velocity it takes, in words."""
        return "(linear, angular) (6,) [m/s, rad/s]" + (
            "" if self.pos and self.rot else ", or (3,)"
        )

    def read(
        self, target: np.ndarray, velocity: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The reference (12 or 3,) and feed-forward (m,) of a target and velocity.

        Raises:
            Refusal: A non-finite number, a 4x4 whose last row is not ``0 0 0 1``, a
                rotation that is not one, a non-finite velocity.
        """
        if not np.isfinite(target).all():
            raise Refusal(False, "finite numbers")
        p, R = np.zeros(3), _IDENTITY
        if target.shape == (4, 4):
            if not np.array_equal(target[3], [0.0, 0.0, 0.0, 1.0]):
                raise Refusal(False, "a 4x4 homogeneous pose (its last row 0 0 0 1)", "last_row")
            p, R = target[:3, 3], target[:3, :3]
        elif target.shape == (3,):
            p = target
        else:
            R = target
        if self.rot and not _is_rotation(R):
            raise Refusal(False, "a rotation (R^T R = I and det R = +1, within 1e-06)")
        v6 = np.zeros(6)
        if velocity is not None:
            if not np.isfinite(velocity).all():
                raise Refusal(True, "finite numbers")
            if velocity.shape == (6,):
                v6[:] = velocity
            else:
                v6[0 if self.pos else 3 : 3 if self.pos else 6] = velocity
        R_ref = R if self.rot else _IDENTITY
        ref = np.concatenate([p, R_ref.ravel()]) if self.rotation_ref else p.copy()
        return ref, v6[list(self.rows)]


@dataclass(frozen=True)
class ValuesTarget:
    """Values (a posture's joints, a distance): target (m,), velocity (m,).

    One value may also be given as a number.

    Attributes:
        m: The values.
        what: What they are, in words (``"joint values"``).
        unit: Their unit (``"rad or m"``, ``"m"``).
        rate: What their velocities are (``"joint velocities"``, ``"rate"``).
        rate_unit: Their unit.
    """

    m: int
    what: str = "joint values"
    unit: str = "rad or m"
    rate: str = "joint velocities"
    rate_unit: str = "rad/s or m/s"

    def _size(self, shape: tuple[int, ...]) -> int:
        return self.m if shape == (self.m,) or (self.m == 1 and shape == ()) else -1

    def target_size(self, shape: tuple[int, ...]) -> int:
        """Floats read of a target of ``shape``, or -1: a form the task does not take."""
        return self._size(shape)

    def velocity_size(self, shape: tuple[int, ...] | None) -> int:
        """Floats read of a velocity of ``shape`` (None: none given, 0), or -1."""
        return 0 if shape is None else self._size(shape)

    def _forms(self, what: str, unit: str) -> str:
        if self.m == 1:
            return f"a {what} [{unit}] (a number, or (1,))"
        return f"{self.m} {what} ({self.m},) [{unit}]"

    def target_forms(self) -> str:
        """The forms of target it takes, in words."""
        return self._forms(self.what, self.unit)

    def velocity_forms(self) -> str:
        """The forms of velocity it takes, in words."""
        return self._forms(self.rate, self.rate_unit)

    def read(
        self, target: np.ndarray, velocity: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The reference (m,) and feed-forward (m,) of a target and velocity.

        Raises:
            Refusal: A non-finite value or velocity.
        """
        if not np.isfinite(target).all():
            raise Refusal(False, "finite numbers")
        if velocity is not None and not np.isfinite(velocity).all():
            raise Refusal(True, "finite numbers")
        ref = np.array(target, dtype=float).reshape(self.m)
        ff = np.zeros(self.m) if velocity is None else np.array(velocity, float).reshape(self.m)
        return ref, ff


TickTarget = FrameTarget | ValuesTarget
"""A task's reader of a controller's target."""


def _is_rotation(R: np.ndarray) -> bool:
    """``R^T R = I`` and ``det R = +1`` within :data:`ROTATION_TOLERANCE`."""
    return bool(
        np.max(np.abs(R.T @ R - _IDENTITY)) <= ROTATION_TOLERANCE
        and abs(np.linalg.det(R) - 1.0) <= ROTATION_TOLERANCE
    )
