"""A run's constraint events: every one, or the last ones with a count of those dropped.

An offline run keeps every event (they are bounded by its samples). A controller's
session has no last sample: its log keeps the last ``capacity`` events, like its record
keeps the last ticks, and counts the ones it dropped (``TrackingResult.events_dropped``).
Events are numbered from 0 in the order they happened. The compiled engine's log is
``src/engine/constraints/event_log.hpp``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import Any


class EventLog:
    """The events ``{"t", "constraint", "action"}`` of a run.

    Args:
        capacity: The events kept (the last ones), >= 1; 0: every one.
    """

    def __init__(self, capacity: int = 0) -> None:
        self._events: deque[dict[str, Any]] = deque(maxlen=capacity or None)
        self.total = 0
        """Every event so far."""

    def append(self, event: dict[str, Any]) -> None:
        """One more event (the oldest dropped when a bounded log is full)."""
        self._events.append(event)
        self.total += 1

    @property
    def dropped(self) -> int:
        """Events no longer kept."""
        return self.total - len(self._events)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self._events)

    def __len__(self) -> int:
        return len(self._events)
