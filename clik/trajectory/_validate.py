"""Argument checks shared by the trajectory classes (private).

Every check normalises its input to a float array and raises
:class:`clik.errors.InputError` naming the parameter on failure.
"""

from __future__ import annotations

import math
from typing import SupportsFloat, cast

import numpy as np
import numpy.typing as npt

from clik.errors import InputError

ROTATION_TOLERANCE = 1e-6
"""Largest accepted ``|R^T R - I|`` (entrywise) and ``|det R - 1|`` for a rotation matrix."""


def _shown(value: object) -> object:
    """What to show of a bad value in a message: small values as is, big ones by shape."""
    try:
        shape = np.shape(cast("npt.ArrayLike", value))  # anything: np.shape raises if it must
    except (TypeError, ValueError):  # ragged nested sequences
        return value
    if int(np.prod(shape)) > 12:
        return f"an array of shape {shape}"
    return value


def finite_scalar(value: object, name: str, unit: str) -> float:
    """A finite real number.

    Args:
        value: The value given.
        name: Parameter name for the message.
        unit: Unit shown in the message, e.g. ``"[s]"``.

    Returns:
        The value as a float.
    """
    try:
        number = float(cast("SupportsFloat | str", value))  # anything else raises TypeError
    except (TypeError, ValueError):
        raise InputError(name, f"a finite number {unit}", _shown(value)) from None
    if isinstance(value, bool) or not math.isfinite(number):
        raise InputError(name, f"a finite number {unit}", _shown(value))
    return number


def positive(value: object, name: str, unit: str) -> float:
    """A finite number > 0 (durations, speeds, radii)."""
    number = finite_scalar(value, name, unit)
    if number <= 0.0:
        raise InputError(name, f"a positive finite number {unit}", value)
    return number


def nonnegative(value: object, name: str, unit: str) -> float:
    """A finite number >= 0."""
    number = finite_scalar(value, name, unit)
    if number < 0.0:
        raise InputError(name, f"a non-negative finite number {unit}", value)
    return number


def vector3(value: object, name: str, unit: str) -> np.ndarray:
    """A finite 3-vector.

    Returns:
        A new float array of shape (3,).
    """
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, f"a finite 3-vector {unit} of shape (3,)", _shown(value)) from None
    if array.shape != (3,) or not np.all(np.isfinite(array)):
        raise InputError(name, f"a finite 3-vector {unit} of shape (3,)", _shown(value))
    return array


def unit_vector3(value: object, name: str) -> np.ndarray:
    """A finite non-zero 3-vector, returned normalised."""
    array = vector3(value, name, "(a direction)")
    norm = float(np.linalg.norm(array))
    if norm < 1e-12:
        raise InputError(name, "a non-zero 3-vector (a direction)", value)
    return array / norm


def rotation(value: object, name: str) -> np.ndarray:
    """A rotation matrix: finite, shape (3, 3), orthonormal with determinant +1.

    Returns:
        A new float array of shape (3, 3).
    """
    expected = "a rotation matrix of shape (3, 3) (R^T R = I, det R = +1)"
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, expected, _shown(value)) from None
    if array.shape != (3, 3) or not np.all(np.isfinite(array)):
        raise InputError(name, expected, _shown(value))
    if (
        np.max(np.abs(array.T @ array - np.eye(3))) > ROTATION_TOLERANCE
        or abs(np.linalg.det(array) - 1.0) > ROTATION_TOLERANCE
    ):
        raise InputError(name, expected, value)
    return array


def times(value: object) -> np.ndarray:
    """Sample times: a finite 1-D array [s] (a scalar becomes one sample)."""
    try:
        array = np.atleast_1d(np.array(value, dtype=float))
    except (TypeError, ValueError):
        raise InputError("t", "a finite 1-D array of times [s]", _shown(value)) from None
    if array.ndim != 1 or not np.all(np.isfinite(array)):
        raise InputError("t", "a finite 1-D array of times [s]", _shown(value))
    return array
