"""A pose trajectory: one trajectory for the position, another for the orientation."""

from __future__ import annotations

import numpy as np

from clik.errors import InputError
from clik.trajectory.base import Trajectory
from clik.trajectory.reference import Reference


class PoseTrajectory(Trajectory):
    """Position from one trajectory, orientation from another.

    Its duration is the larger of the two; each part is sampled on the same
    times and clipped to its own duration, so the shorter one holds its final
    value (e.g. ``PoseTrajectory(Line(...), Hold(rotation=R))``).

    Args:
        position: A trajectory giving positions (its rotations, if any, are ignored).
        orientation: A trajectory giving rotations (its positions, if any, are ignored).

    Raises:
        InputError: An argument that is not a :class:`Trajectory` or does not
            give what its role needs (checked by sampling it once at t = 0).
    """

    def __init__(self, position: Trajectory, orientation: Trajectory) -> None:
        for name, part, attribute in (
            ("position", position, "position"),
            ("orientation", orientation, "rotation"),
        ):
            if not isinstance(part, Trajectory):
                raise InputError(name, "a Trajectory", type(part).__name__)
            if getattr(part.sample(np.zeros(1)), attribute) is None:
                raise InputError(
                    name, f"a trajectory that gives a {attribute}", type(part).__name__
                )
        self.position = position
        self.orientation = orientation
        self.duration = max(position.duration, orientation.duration)

    def sample(self, t: np.ndarray) -> Reference:
        """Positions, rotations and their velocities at times ``t`` [s]."""
        times, _ = self._times(t)
        translation = self.position.sample(times)
        rotation = self.orientation.sample(times)
        if translation.position is None or rotation.rotation is None:  # a user's own parts
            return Reference(
                times,
                position=translation.position,
                linear_velocity=translation.linear_velocity,
                rotation=rotation.rotation,
                angular_velocity=rotation.angular_velocity,
            )
        return Reference.of_checked(times, translation, rotation)

    def __repr__(self) -> str:
        return f"PoseTrajectory({self.position!r}, {self.orientation!r})"
