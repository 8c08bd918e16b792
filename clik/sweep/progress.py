"""A progress bar for many runs (a :mod:`tqdm` bar): done, failed, rate, time left.

Drawn on stderr, and by default only when stderr is a terminal.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

from tqdm import tqdm


class RunProgress:
    """Counts finished runs and shows them as a tqdm bar on ``stream``.

    The bar shows ``label``, the share done, ``done/total``, the time spent and
    left, the rate and how many failed, e.g.
    ``sweep:  40%|####      | 4/10 [00:02<00:03, 1.95runs/s, 1 failed]``.
    The counts are kept whether the bar is drawn or not.

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
        self.done = 0
        self.failed = 0
        self.start = time.perf_counter()
        self._bar = tqdm(
            total=total,
            desc=label,
            unit=unit,
            file=self.stream,
            disable=not self.enabled,
            mininterval=interval,
            dynamic_ncols=True,
            leave=True,
            postfix=self.postfix(),
        )

    @property
    def rate(self) -> float:
        """Items finished per second since the start [1/s]."""
        elapsed = time.perf_counter() - self.start
        return self.done / elapsed if elapsed > 0 else 0.0

    def postfix(self) -> str:
        """The failed count shown after the rate, e.g. ``1 failed``."""
        return f"{self.failed} {self.failed_label}"

    def update(self, done: int = 1, failed: int = 0) -> None:
        """Count ``done`` more runs, ``failed`` of which failed; redraw when due."""
        self.done += done
        self.failed += failed
        if not self.enabled:
            return
        self._bar.set_postfix_str(self.postfix(), refresh=False)
        self._bar.update(done)

    def line(self) -> str:
        """The text of the bar (as tqdm draws it, 80 columns wide)."""
        return tqdm.format_meter(
            self.done,
            self.total,
            time.perf_counter() - self.start,
            ncols=80,
            prefix=self.label,
            unit=self.unit,
            postfix=self.postfix(),
        )

    def draw(self) -> None:
        """Redraw the bar now."""
        if self.enabled:
            self._bar.refresh()

    def note(self, text: str) -> None:
        """A line of its own above the bar (only where the bar is drawn).

        Safe in a signal handler: tqdm's write lock is not taken.
        """
        if self.enabled:
            self._bar.write(f"{self.label}: {text}", file=self.stream, nolock=True)

    def close(self) -> None:
        """Draw the last state and end the bar's line (also after an interruption)."""
        self._bar.close()
