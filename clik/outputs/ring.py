"""A ring record (a controller's: its last samples) unrolled, oldest first."""

from __future__ import annotations

from typing import Any

import numpy as np


def unrolled_slots(kept: int, capacity: int) -> np.ndarray:
    """Slots of a ring of ``capacity`` that kept ``kept`` samples, oldest first."""
    if kept <= capacity:
        return np.arange(kept)
    return np.roll(np.arange(capacity), -(kept % capacity))


def unrolled(value: Any, kept: int, capacity: int) -> Any:
    """Per-sample arrays (first axis ``capacity``) of a record, oldest first; nested."""
    if isinstance(value, dict):
        return {k: unrolled(v, kept, capacity) for k, v in value.items()}
    if isinstance(value, list):
        return [unrolled(v, kept, capacity) for v in value]
    if isinstance(value, np.ndarray) and value.ndim >= 1 and value.shape[0] == capacity:
        return value[unrolled_slots(kept, capacity)]
    return value
