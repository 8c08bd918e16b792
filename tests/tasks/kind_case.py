"""A task kind's case for the generic tests of every kind (``test_task_kinds.py``).

Each kind's case lives with its own tests, in ``tests/tasks/test_<its module>.py``, as a
function ``case()`` returning a :class:`Case`: a kind is added, tests included, in files
of its own (plus the registry, the C++ variant and the docs). :func:`case_of` finds it;
a kind without one fails ``test_every_kind_has_a_case``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from clik.tasks.kind import BaseTask

FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
Q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.8, 0.8])
"""A Panda start away from its singularities."""


@dataclass
class Case:
    """A kind as a goal beside a frame task, its trajectory, and its scenario table."""

    task: BaseTask
    trajectory: Any
    table: str
    """Its ``[[tasks]]`` table (TOML), named ``"kind"``."""
    bad_keys: dict[str, Any]
    """Keys of its table and a value each refused (the key named in the error)."""
    forms: Callable[[np.ndarray], list[Any]]
    """Its tick targets in every form its reader takes, from one reference row."""
    velocity: Callable[[Any, int], Any]
    """Its tick velocity at sample ``k`` of its trajectory's samples."""
    held: Callable[[np.ndarray], np.ndarray]
    """Its reference row at a configuration: where it is there (its error zero)."""
    exact: bool = True
    """Its rows are its error's derivative everywhere (a frame's orientation rows only
    where the error is zero: ``log3``'s derivative is the identity there)."""


def panda() -> clik.Robot:
    return clik.Robot.load("panda", lock=FINGERS)


def hand(robot: clik.Robot) -> clik.Task:
    return clik.Task(robot, "panda_hand", "position")


def linear(s: Any, k: int) -> np.ndarray:
    return np.asarray(s.linear_velocity[k], dtype=float)


def twist(s: Any, k: int) -> np.ndarray:
    return np.concatenate([s.linear_velocity[k], s.angular_velocity[k]])


def pose_row(placement: pin.SE3) -> np.ndarray:
    """A pose's reference row: its position, then its rotation, row-major."""
    return np.concatenate([placement.translation, placement.rotation.ravel()])


def pose_forms(row: np.ndarray) -> list[Any]:
    R = row[3:].reshape(3, 3)
    return [
        pin.SE3(R, row[:3]),
        pin.SE3(R, row[:3]).homogeneous,
        pin.SE3(R, row[:3]).homogeneous.tolist(),
    ]


def point_forms(row: np.ndarray) -> list[Any]:
    return [row[:3].copy(), row[:3].tolist(), pin.SE3(np.eye(3), row[:3])]


def case_of(kind: type[BaseTask]) -> Case:
    """The case of ``kind``: ``case()`` of ``tests/tasks/test_<its module>.py``."""
    module = kind.__module__.rsplit(".", 1)[-1]
    where = f"tests/tasks/test_{module}.py"
    try:
        tests = importlib.import_module(f"tests.tasks.test_{module}")
    except ModuleNotFoundError as e:
        raise AssertionError(f"no case for {kind.__name__}: add {where} with case()") from e
    make = getattr(tests, "case", None)
    if make is None:
        raise AssertionError(f"no case for {kind.__name__}: add case() to {where}")
    case = make()
    assert isinstance(case, Case) and type(case.task) is kind, where
    return case
