"""The extended task of one run: eqs. (24)-(25) as preallocated arrays.

Rows ``0 .. m`` are the task (``J``, ``e = x_d - x``, gains ``K``, feed-forward
``xdot_d``); rows ``m .. m + v`` are the active constraints' rows, written by the
run's :class:`~clik.constraints.constraint_run.ConstraintRun` each sample. The
run owns this object; constraints fill rows into it and never keep it.
"""

from __future__ import annotations

import numpy as np


class ExtendedTask:
    """``J_e`` (24), ``e_e`` (25), per-row gains and feed-forward, with room for ``rows``.

    Args:
        m: Task rows.
        rows: Largest number of rows (task plus constraints).
        nv: Joint velocity size.
        K_task: The task rows' gains [1/s] (m,).

    Attributes:
        J: Extended Jacobian (rows, nv).
        e: Extended error (rows,).
        K: Gain per row [1/s] (rows,).
        ff: Feed-forward per row, ``xdot_d`` for the task and (14) for obstacles (rows,).
        work, demand_out: The law's scratch rows (rows,); ``jte`` its (nv,) one: the
            run's own, like everything here.
    """

    def __init__(self, m: int, rows: int, nv: int, K_task: np.ndarray) -> None:
        self.m = m
        self.J = np.zeros((rows, nv))
        self.e = np.zeros(rows)
        self.K = np.zeros(rows)
        self.ff = np.zeros(rows)
        self.K[:m] = K_task
        self.work = np.zeros(rows)
        self.demand_out = np.zeros(rows)
        self.jte = np.zeros(nv)

    def demand(self, r: int, out: np.ndarray) -> np.ndarray:
        """``K e + ff`` of the first ``r`` rows (r,): what law (10) asks each row to do."""
        np.multiply(self.K[:r], self.e[:r], out=out)
        out += self.ff[:r]
        return out

    def swap(self, a: int, b: int) -> None:
        """Exchange rows ``a`` and ``b`` (Jacobian, error, gain, feed-forward)."""
        for arr in (self.J, self.e, self.K, self.ff):
            tmp = arr[a].copy()
            arr[a] = arr[b]
            arr[b] = tmp
