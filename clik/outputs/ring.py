"""A ring record (a controller's: its last samples) unrolled, oldest first."""

from __future__ import annotations

import numpy as np


def unrolled_slots(kept: int, capacity: int) -> np.ndarray:
    """Slots of a ring of ``capacity`` that kept ``kept`` samples, oldest first."""
    if kept <= capacity:
        return np.arange(kept)
    return np.roll(np.arange(capacity), -(kept % capacity))


def unrolled(value: np.ndarray, kept: int, capacity: int) -> np.ndarray:
    """A per-sample array of a ring record (first axis ``capacity``), oldest first."""
    return value[unrolled_slots(kept, capacity)]
