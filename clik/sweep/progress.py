"""A one-line progress bar for many runs: done, failed, rate, time left (stderr, terminal only)."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class RunProgress:
    """Counts finished runs and redraws one line on ``stream`` at most every ``interval`` s.

    Args:
        label: Text before the bar.
        total: Runs to do in this session (skipped ones excluded).
        enabled: Draw at all; default: only when ``stream`` is a terminal.
        stream: Where to draw (default ``sys.stderr``).
        interval: Least time between two redraws [s].
        unit: What is counted (``runs``, ``points``).
        failed_label: What the failed count is called.
    """

    def __init__(
        self,
        label: str,
        total: int,
        enabled: bool | None = None,
        stream: TextIO | None = None,
        interval: float = 0.2,
        unit: str = "runs",
        failed_label: str = "failed",
    ) -> None:
        self.unit = unit
        self.failed_label = failed_label
        self.label = label
        self.total = total
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.interval = interval
        self.done = 0
        self.failed = 0
        self.start = time.perf_counter()
        self._drawn = 0.0

    @property
    def rate(self) -> float:
        """Items finished per second since the start [1/s]."""
        elapsed = time.perf_counter() - self.start
        return self.done / elapsed if elapsed > 0 else 0.0

    def update(self, done: int = 1, failed: int = 0) -> None:
        """Count ``done`` more runs, ``failed`` of which raised; redraw when due."""
        self.done += done
        self.failed += failed
        now = time.perf_counter()
        if self.done >= self.total or now - self._drawn >= self.interval:
            self._drawn = now
            self.draw()

    def line(self) -> str:
        """The text of the bar."""
        width = 24
        filled = int(width * self.done / max(self.total, 1))
        rate = self.rate
        left = (self.total - self.done) / rate if rate > 0 else float("nan")
        eta = f", {left:.0f} s left" if rate > 0 and self.done < self.total else ""
        return (
            f"{self.label} [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} "
            f"done, {self.failed} {self.failed_label}, {rate:.1f} {self.unit}/s{eta}"
        )

    def draw(self) -> None:
        """Redraw the line (a newline once everything is done)."""
        if not self.enabled:
            return
        end = "\n" if self.done >= self.total else ""
        self.stream.write(f"\r{self.line()}\x1b[K{end}")
        self.stream.flush()

    def note(self, text: str) -> None:
        """A line of its own under the bar (only where the bar is drawn)."""
        if self.enabled:
            self.stream.write(f"\n{self.label}: {text}\n")
            self.stream.flush()

    def close(self) -> None:
        """End the line if the bar stopped before the total (an interruption)."""
        if self.enabled and self.done < self.total:
            self.stream.write("\n")
            self.stream.flush()
