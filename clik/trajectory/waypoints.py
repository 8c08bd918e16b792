r"""Polyline through waypoints, corners optionally rounded by circular arcs."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from clik.errors import InputError
from clik.trajectory import _validate
from clik.trajectory.base import Trajectory
from clik.trajectory.profile import TrapezoidalProfile
from clik.trajectory.reference import Reference

_STRAIGHT = 1e-9
"""Corners turning by less than this [rad] are treated as straight (no arc)."""


class Waypoints(Trajectory):
    r"""Path through waypoints, travelled with one trapezoidal profile on its total length.

    The path is parametrised by arc length ``s``, so ``p(t) = P(s(t))`` and
    ``pdot(t) = sdot(t) P'(s(t))`` with ``|P'| = 1``: the speed follows the
    trapezoidal profile exactly and only the direction changes along the path.

    Corners: with ``blend_radius = 0`` (default) the path is the polyline
    itself and passes through every waypoint, but the velocity direction jumps
    at interior waypoints. With ``blend_radius = d > 0`` each interior corner
    is replaced by the circular arc tangent to both segments at distance
    ``d_i = min(d, l_in / 2, l_out / 2)`` from the waypoint (``l`` are the
    adjacent segment lengths, so neighbouring arcs never overlap). An arc
    turning by ``beta`` has radius ``rho_i = d_i / tan(beta / 2)`` and length
    ``rho_i beta``. The path is then tangent-continuous, so the velocity is
    continuous; it no longer passes through the interior waypoints but misses
    each by ``sqrt(d_i^2 + rho_i^2) - rho_i < d_i``. A segment that doubles
    back exactly (``beta = pi``) keeps a sharp corner (the velocity reverses
    there).

    Timing: as :class:`~clik.trajectory.line.Line`, any two of ``duration``,
    ``cruise_speed`` and ``accel_time`` on the total path length, or one of
    the first two.

    Args:
        points: Waypoints in the world frame, shape (K, 3) [m], K >= 2,
            consecutive points distinct.
        duration: Duration [s].
        cruise_speed: Cruise speed along the path [m/s].
        accel_time: Acceleration time [s].
        blend_radius: Corner blend distance d [m], >= 0.

    Attributes:
        points: The waypoints (K, 3) [m].
        blend_radius: d [m].
        length: Total path length [m] (shorter than the polyline when blended).
        breaks: Arc length at the start of each path piece, then the total (P + 1,) [m].
        profile: The trapezoidal profile.
        duration: Duration [s].
    """

    def __init__(
        self,
        points: ArrayLike,
        duration: float | None = None,
        cruise_speed: float | None = None,
        accel_time: float | None = None,
        blend_radius: float = 0.0,
    ) -> None:
        expected = "finite waypoints of shape (K, 3) [m] with K >= 2"
        try:
            array = np.array(points, dtype=float)
        except (TypeError, ValueError):
            raise InputError("points", expected, points) from None
        if array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 2:
            raise InputError("points", expected, f"shape {array.shape}")
        if not np.all(np.isfinite(array)):
            k = int(np.flatnonzero(~np.isfinite(array).all(axis=1))[0])
            raise InputError("points", expected, f"points[{k}] = {array[k].tolist()}")
        segments = np.diff(array, axis=0)
        lengths = np.linalg.norm(segments, axis=1)
        if np.any(lengths < 1e-12):
            k = int(np.flatnonzero(lengths < 1e-12)[0])
            raise InputError(
                "points", "distinct consecutive waypoints", f"points[{k}] == points[{k + 1}]"
            )
        self.points = array
        self.blend_radius = _validate.nonnegative(blend_radius, "blend_radius", "[m]")
        self._build_pieces(segments / lengths[:, None], lengths)
        self.profile = TrapezoidalProfile.resolve(
            self.length, duration, cruise_speed, accel_time, unit="m"
        )
        self.duration = self.profile.duration

    def _build_pieces(self, directions: np.ndarray, lengths: np.ndarray) -> None:
        """Split the path into line and arc pieces, stored as arrays for vectorised sampling.

        With ``sigma`` the arc length from the piece's start, a line piece is
        ``P(sigma) = origin + sigma e2`` and an arc piece is
        ``P(sigma) = origin + rho (cos(sigma / rho) e1 + sin(sigma / rho) e2)``,
        ``origin`` being the arc's center, ``e1`` pointing from it to the arc's
        start and ``e2`` the incoming direction. A Python loop runs over the K
        waypoints once here; sampling is vectorised.
        """
        points = self.points
        k = points.shape[0]
        trim = np.zeros(k)  # tangent length d_i at each waypoint (0 at both ends)
        turn = np.zeros(k)  # turning angle beta_i
        if self.blend_radius > 0.0:
            for i in range(1, k - 1):
                cos_beta = float(np.clip(directions[i - 1] @ directions[i], -1.0, 1.0))
                beta = float(np.arccos(cos_beta))
                if _STRAIGHT < beta < np.pi - _STRAIGHT:
                    turn[i] = beta
                    trim[i] = min(self.blend_radius, 0.5 * lengths[i - 1], 0.5 * lengths[i])
        is_arc, origin, e1, e2, rho, piece_lengths = [], [], [], [], [], []
        for i in range(k - 1):
            if trim[i] > 0.0:  # arc around waypoint i, from segment i - 1 into segment i
                u_in, u_out = directions[i - 1], directions[i]
                radius = trim[i] / np.tan(0.5 * turn[i])
                inward = u_out - (u_out @ u_in) * u_in
                inward /= np.linalg.norm(inward)
                arc_start = points[i] - trim[i] * u_in
                is_arc.append(True)
                origin.append(arc_start + radius * inward)  # the arc's center
                e1.append(-inward)
                e2.append(u_in)
                rho.append(radius)
                piece_lengths.append(radius * turn[i])
            is_arc.append(False)
            origin.append(points[i] + trim[i] * directions[i])
            e1.append(np.zeros(3))
            e2.append(directions[i])
            rho.append(1.0)
            piece_lengths.append(lengths[i] - trim[i] - trim[i + 1])
        self._is_arc = np.array(is_arc)
        self._origin = np.array(origin)
        self._e1 = np.array(e1)
        self._e2 = np.array(e2)
        self._rho = np.array(rho)
        self.breaks = np.concatenate(([0.0], np.cumsum(piece_lengths)))
        self.length = float(self.breaks[-1])

    def sample(self, t: np.ndarray) -> Reference:
        """Positions and velocities at times ``t`` [s] (see :meth:`Trajectory.sample`)."""
        times, clipped = self._times(t)
        s, sdot = self.profile(clipped)
        piece = np.clip(np.searchsorted(self.breaks, s, side="right") - 1, 0, len(self._rho) - 1)
        sigma = s - self.breaks[piece]
        arc = self._is_arc[piece]
        rho = self._rho[piece]
        phi = np.where(arc, sigma / rho, 0.0)
        cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
        e1, e2, origin = self._e1[piece], self._e2[piece], self._origin[piece]
        arc_col = arc[:, None]
        position = np.where(
            arc_col,
            origin + rho[:, None] * (cos * e1 + sin * e2),
            origin + sigma[:, None] * e2,
        )
        tangent = np.where(arc_col, -sin * e1 + cos * e2, e2)
        return Reference(times, position=position, linear_velocity=sdot[:, None] * tangent)

    def __repr__(self) -> str:
        return (
            f"Waypoints({self.points.shape[0]} points, length={self.length:.6g}, "
            f"blend_radius={self.blend_radius:.6g}, duration={self.duration:.6g})"
        )
