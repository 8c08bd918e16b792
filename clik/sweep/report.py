"""What a sweep did: the runs it computed, skipped and lost, and the statuses in its folder.

A sweep *fails* (:attr:`SweepReport.failed`, exit code 1 of ``clik sweep``) when a
run in its folder raised (status :data:`RAISED`) or ended with a status of
:data:`FAILED_STATUSES`; resumed runs count as much as those computed now.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

RAISED = "error"
"""The ``status`` of a run that raised (or whose task failed, e.g. ``KilledWorker``)."""

FAILED_STATUSES = frozenset({"violated", "velocity_limit", "off_track", "diverged"})
"""Run statuses that fail a sweep, as do runs that raised (:data:`RAISED`)."""

STATUS_ORDER = ("completed", "deadlock", "diverged", "violated", "velocity_limit", "off_track")
"""The order of the statuses in :func:`status_line` (others follow, sorted)."""


def status_line(counts: Counter[str]) -> str:
    """Counts per status, e.g. ``completed 118, deadlock 1, violated 1, raised 0``.

    Statuses with runs are listed in :data:`STATUS_ORDER`, then any other
    status (sorted); runs that raised come last as ``raised``, always shown.
    """
    shown = [s for s in STATUS_ORDER if counts.get(s)]
    shown += sorted(s for s, n in counts.items() if n and s != RAISED and s not in STATUS_ORDER)
    return ", ".join([*(f"{s} {counts[s]}" for s in shown), f"raised {counts.get(RAISED, 0)}"])


@dataclass
class SweepReport:
    """What one call of :func:`~clik.sweep.execute.run_sweep` did.

    Attributes:
        out: The output folder.
        results: The results table (``results.parquet`` folder or ``results.csv``).
        total: Runs in the sweep.
        skipped: Runs already in the folder (resume), not computed again.
        computed: Runs computed and written now.
        lost: Runs neither written nor failed (cancelled by the cluster); a rerun computes them.
        statuses: Status counts of the runs written now.
        all_statuses: Status counts of every run in the folder at the end (those
            written now and those resumed), read back from the results table.
        wall_time_s: From the first submission to the last write [s].
        interrupted: The sweep was stopped before its end (Ctrl-C).
    """

    out: Path
    results: Path
    total: int
    skipped: int
    computed: int = 0
    lost: int = 0
    statuses: Counter[str] = field(default_factory=Counter)
    all_statuses: Counter[str] = field(default_factory=Counter)
    wall_time_s: float = 0.0
    interrupted: bool = False

    @property
    def rate(self) -> float:
        """Runs computed per second [1/s]."""
        return self.computed / self.wall_time_s if self.wall_time_s > 0 else 0.0

    @property
    def complete(self) -> bool:
        """Every run of the sweep is in the folder."""
        return self.skipped + self.computed == self.total

    @property
    def failed(self) -> int:
        """Runs in the folder that raised or ended with a status of :data:`FAILED_STATUSES`."""
        return sum(n for s, n in self.all_statuses.items() if s == RAISED or s in FAILED_STATUSES)
