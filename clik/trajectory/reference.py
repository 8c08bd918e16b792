"""The desired task trajectory, sampled on a time grid."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clik.errors import InputError
from clik.trajectory._validate import ROTATION_TOLERANCE

TRAILING_SHAPES: dict[str, tuple[int, ...]] = {
    "position": (3,),
    "linear_velocity": (3,),
    "rotation": (3, 3),
    "angular_velocity": (3,),
}
"""Each array of a :class:`Reference` has the shape ``(N, *TRAILING_SHAPES[name])``."""


@dataclass(frozen=True, eq=False)
class Reference:
    """A desired task trajectory sampled on a time grid (N samples).

    This is what the solver tracks: ``x_d(t_k)`` and ``xdot_d(t_k)`` of
    docs/method.md for every sample ``k``. Position and linear velocity come
    together (both or neither), and so do rotation and angular velocity;
    at least one of the two pairs is given. Velocities are expressed in the
    world frame (``LOCAL_WORLD_ALIGNED``).

    The arrays are converted to float arrays on construction and checked:
    shapes consistent with ``t``, finite values, and rotation matrices
    orthonormal with determinant +1 (to within ``1e-6``).

    Attributes:
        t: Sample times, shape (N,) [s].
        position: Desired frame origin in the world frame, shape (N, 3) [m], or None.
        linear_velocity: Its time derivative, shape (N, 3) [m/s], or None.
        rotation: Desired frame orientation (world <- frame), shape (N, 3, 3), or None.
        angular_velocity: Desired angular velocity in the world frame,
            shape (N, 3) [rad/s], or None.

    Raises:
        InputError: ``trajectory: expected finite values, got '<array>[k] = ... at t = ... s'``
            for NaN or inf, and an error naming the array for a bad shape or a
            bad rotation matrix.
    """

    t: np.ndarray
    position: np.ndarray | None = None
    linear_velocity: np.ndarray | None = None
    rotation: np.ndarray | None = None
    angular_velocity: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=float)
        if t.ndim != 1:
            raise InputError("trajectory.t", "a 1-D array of times [s]", f"shape {t.shape}")
        if not np.all(np.isfinite(t)):
            k = int(np.flatnonzero(~np.isfinite(t))[0])
            raise InputError("trajectory", "finite values", f"t[{k}] = {t[k]}")
        object.__setattr__(self, "t", t)
        n = t.shape[0]
        for name, trailing in TRAILING_SHAPES.items():
            value = getattr(self, name)
            if value is None:
                continue
            array = np.array(value, dtype=float)
            if array.shape != (n, *trailing):
                raise InputError(
                    f"trajectory.{name}",
                    f"shape {(n, *trailing)} for {n} samples",
                    f"shape {array.shape}",
                )
            finite = np.isfinite(array)
            if not finite.all():  # the row, only then (a reduction along rows is slow)
                k = int(np.flatnonzero(~finite.reshape(n, -1).all(axis=1))[0])
                shown = np.array2string(array[k], separator=", ").replace("\n", "")
                raise InputError(
                    "trajectory", "finite values", f"{name}[{k}] = {shown} at t = {t[k]:.6g} s"
                )
            object.__setattr__(self, name, array)
        for first, second in (("position", "linear_velocity"), ("rotation", "angular_velocity")):
            if (getattr(self, first) is None) != (getattr(self, second) is None):
                raise InputError("trajectory", f"{first} and {second} both given or both None")
        if self.position is None and self.rotation is None:
            raise InputError("trajectory", "a position or a rotation (or both)")
        if self.rotation is not None and n > 0:
            rotation = self.rotation
            bad = (_orthonormality(rotation) > ROTATION_TOLERANCE) | (
                np.abs(_det3(rotation) - 1.0) > ROTATION_TOLERANCE
            )
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise InputError(
                    "trajectory.rotation",
                    "rotation matrices (R^T R = I, det R = +1)",
                    f"a non-rotation at sample {k}, t = {t[k]:.6g} s",
                )

    @classmethod
    def of_checked(
        cls,
        t: np.ndarray,
        position: Reference,
        rotation: Reference,
    ) -> Reference:
        """The position part of one checked reference and the rotation part of another.

        Both were checked when they were built, on the same times ``t``: nothing is
        checked again (a pose trajectory's sample, every run).
        """
        out = object.__new__(cls)
        for name, value in (
            ("t", np.asarray(t, dtype=float)),
            ("position", position.position),
            ("linear_velocity", position.linear_velocity),
            ("rotation", rotation.rotation),
            ("angular_velocity", rotation.angular_velocity),
        ):
            object.__setattr__(out, name, value)
        return out

    def __len__(self) -> int:
        """Number of samples N."""
        return int(self.t.shape[0])

    @property
    def has_position(self) -> bool:
        """Whether the reference gives a position (and a linear velocity)."""
        return self.position is not None


def _det3(R: np.ndarray) -> np.ndarray:
    """Determinants of 3x3 matrices (N, 3, 3), by cofactors (LAPACK's is 30x slower here)."""
    a, b, c = R[:, 0, 0], R[:, 0, 1], R[:, 0, 2]
    d, e, f = R[:, 1, 0], R[:, 1, 1], R[:, 1, 2]
    g, h, i = R[:, 2, 0], R[:, 2, 1], R[:, 2, 2]
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _orthonormality(R: np.ndarray) -> np.ndarray:
    """``max |R^T R - I|`` of each matrix (N, 3, 3), column by column (no batched matmul)."""
    c = [R[:, :, i] for i in range(3)]
    worst = np.zeros(R.shape[0])
    for i in range(3):
        for k in range(i, 3):
            g = np.einsum("nj,nj->n", c[i], c[k]) - (1.0 if i == k else 0.0)
            np.maximum(worst, np.abs(g), out=worst)
    return worst
