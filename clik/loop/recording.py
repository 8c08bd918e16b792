"""The record of a run: every ``record_every``-th sample (and the last), preallocated.

Scalars over the whole run (``joint_min``, ``joint_max``) see every sample, recorded
or not. With decimation, ``qddot`` is the backward difference of ``qdot`` at each
recorded sample (not across the gap); without it, differences of the record.
"""

from __future__ import annotations

import numpy as np

from clik.outputs.ring import unrolled_slots
from clik.trajectory.clock import OPEN


def kept_samples(N: int, every: int) -> int:
    """Samples kept of ``N`` when keeping every ``every``-th and the last."""
    return (N - 1) // every + 1 + (1 if (N - 1) % every else 0)


def bytes_per_sample(nq: int, nv: int, n_obs: int = 0, slots: int = 0) -> int:
    """Memory of one kept sample [bytes].

    The record's arrays, and with constraints the per-obstacle distances and links and
    the active rows' codes and witness points.
    """
    own = 8 * (1 + nq + 2 * nv + 3 + 3 + 1 + 1) + 2 + 8
    return own + n_obs * (8 + 2) + slots * (4 + 8 * 6)


class Recorder:
    """Preallocated arrays for ``N`` samples kept every ``every``-th.

    Args:
        N: Samples in the run.
        every: Keep every ``every``-th sample and the last.
        nq, nv: Configuration and velocity sizes.
        reference: Record the position reference.
        orientation: Record the orientation error norm.
        constraints: Record the active row count and the minimum obstacle distance.
        ring: Keep the last ``ring`` kept samples of an open run (``N`` is then
            :data:`OPEN`): sample ``j`` kept goes to slot ``j % ring``, and
            :meth:`trimmed` gives them oldest first.
    """

    def __init__(
        self,
        N: int,
        every: int,
        nq: int,
        nv: int,
        reference: bool,
        orientation: bool,
        constraints: bool,
        ring: int | None = None,
    ) -> None:
        n = kept_samples(N, every) if ring is None else ring
        self.N, self.every, self.decimated = (N if ring is None else OPEN), every, every > 1
        self.ring = ring is not None
        self.idx = np.empty(n, dtype=np.intp)
        self.q = np.empty((n, nq))
        self.qdot = np.empty((n, nv))
        self.qddot = np.zeros((n, nv))
        self.position = np.empty((n, 3))
        self.reference = np.empty((n, 3)) if reference else None
        self.error = np.empty(n)
        self.orientation_error = np.empty(n) if orientation else None
        self.active = np.zeros(n, dtype=np.int16) if constraints else None
        self.distance = np.full(n, np.inf) if constraints else None
        self.capacity = n
        self.j = 0
        self._qdot_prev = np.zeros(nv)
        self.joint_min = np.empty(nq)
        self.joint_max = np.empty(nq)

    def due(self, k: int) -> bool:
        """Whether sample ``k`` is kept."""
        return k % self.every == 0 or k == self.N - 1

    def start(self, q: np.ndarray) -> None:
        """Initialise the running joint extremes at the start configuration."""
        self.joint_min[:] = q
        self.joint_max[:] = q

    def keep(
        self,
        k: int,
        q: np.ndarray,
        qdot: np.ndarray,
        position: np.ndarray,
        reference: np.ndarray | None,
        error: float,
        orientation_error: float,
    ) -> int:
        """Store sample ``k``; returns its slot (the count kept so far, modulo a ring's size)."""
        j = self.j % self.capacity if self.ring else self.j
        self.idx[j] = k
        self.q[j] = q
        self.qdot[j] = qdot
        self.position[j] = position
        self.error[j] = error
        if self.reference is not None and reference is not None:
            self.reference[j] = reference
        if self.orientation_error is not None:
            self.orientation_error[j] = orientation_error
        if self.decimated:
            np.subtract(qdot, self._qdot_prev, out=self.qddot[j])
        self.j += 1
        return j

    def every_sample(self, q: np.ndarray, qdot: np.ndarray) -> None:
        """Running extremes and the previous ``qdot`` (decimated runs and rings only)."""
        if self.decimated or self.ring:
            np.minimum(self.joint_min, q, out=self.joint_min)
            np.maximum(self.joint_max, q, out=self.joint_max)
            self._qdot_prev[:] = qdot

    def trimmed(self, dt: float) -> dict[str, np.ndarray | None]:
        """The kept samples as result arrays (``qddot`` by differences) [SI units].

        The joints' extremes are taken along the rows of ``q``'s transposed copy: NumPy
        reduces a long (N, nq) array along axis 0 in N short inner loops (measured with
        timeit, (3001, 4): 101 us per ``min(axis=0)``, 9.5 us copy included).
        """
        if self.ring:
            return self._unrolled(dt)
        n = self.j
        sl = slice(0, n)
        qdot = self.qdot[sl]
        if self.decimated:
            qddot = self.qddot[sl] / dt
            joint_min, joint_max = self.joint_min, self.joint_max
        else:
            # qddot[1:] = np.diff(qdot, axis=0) / dt, in place: one new array, not three
            # (each new array's pages are faulted in when first written, ~5 us a page)
            qddot = np.empty_like(qdot)
            qddot[:1] = 0.0
            np.subtract(qdot[1:], qdot[:-1], out=qddot[1:])
            qddot[1:] /= dt
            columns = np.ascontiguousarray(self.q[sl].T)  # contiguous columns: see above
            joint_min, joint_max = columns.min(axis=1), columns.max(axis=1)
        return {
            "q": self.q[sl],
            "qdot": qdot,
            "qddot": qddot,
            "position": self.position[sl],
            "reference_position": None if self.reference is None else self.reference[sl],
            "task_error_norm": self.error[sl],
            "orientation_error_norm": (
                None if self.orientation_error is None else self.orientation_error[sl]
            ),
            "min_obstacle_distance": None if self.distance is None else self.distance[sl],
            "active_count": None if self.active is None else self.active[sl],
            "joint_min": joint_min,
            "joint_max": joint_max,
        }

    def order(self) -> np.ndarray | slice:
        """The slots of the kept samples, oldest first (a ring unrolled)."""
        if not self.ring or self.j <= self.capacity:
            return slice(0, min(self.j, self.capacity))
        return unrolled_slots(self.j, self.capacity)

    def _unrolled(self, dt: float) -> dict[str, np.ndarray | None]:
        """:meth:`trimmed` of a ring: its slots oldest first (``qddot`` as kept, decimated)."""
        order = self.order()
        out: dict[str, np.ndarray | None] = {}
        for key, name in _RECORDED.items():
            array = getattr(self, name)
            out[key] = None if array is None else array[order]
        qdot = out["qdot"]
        assert qdot is not None
        if self.decimated:
            assert out["qddot"] is not None
            out["qddot"] = out["qddot"] / dt
        else:
            qddot = np.zeros_like(qdot)
            np.subtract(qdot[1:], qdot[:-1], out=qddot[1:])
            qddot[1:] /= dt
            out["qddot"] = qddot
        # the running extremes of every tick of the session (not only of the ring's)
        out["joint_min"], out["joint_max"] = self.joint_min.copy(), self.joint_max.copy()
        return out


_RECORDED = {
    "q": "q",
    "qdot": "qdot",
    "qddot": "qddot",
    "position": "position",
    "reference_position": "reference",
    "task_error_norm": "error",
    "orientation_error_norm": "orientation_error",
    "min_obstacle_distance": "distance",
    "active_count": "active",
}
