"""A controller's memory is bounded in long sessions (issue 40, case 7).

A controller keeps its last ``record_size`` ticks and its last ``event_size`` constraint
events, counting those it dropped: a million ticks with an event at every tick grow its
memory by nothing once the record and the event log are full, and ``result()`` holds
(and costs) only what they keep. The time ``result()`` takes is a ``clik bench`` figure
(``controller_session.result_ms``), not a test's; the scene is the bench's.
"""

from __future__ import annotations

import ctypes
import gc
from collections.abc import Callable

from benchmarks.rss import proc_status_kb
from benchmarks.session_memory import blinking


def memory_in_use() -> tuple[Callable[[], int], str]:
    """A reader of this process's memory in use [bytes], and its name.

    The resident set size, except under AddressSanitizer (``make sanitize``): there freed
    blocks wait in its quarantine, resident, for a later use-after-free to hit them, so
    RSS grows by whatever is freed; ASan's allocator counts the bytes still allocated.
    """
    sanitizer = ctypes.CDLL(None)
    if hasattr(sanitizer, "__sanitizer_get_current_allocated_bytes"):
        allocated = sanitizer.__sanitizer_get_current_allocated_bytes
        allocated.restype = ctypes.c_size_t
        return (lambda: int(allocated())), "ASan's allocated bytes"
    return (lambda: (proc_status_kb("VmRSS") or 0) * 1024), "RSS"


def test_a_long_session_with_events_at_every_tick_keeps_memory_flat() -> None:
    """Memory in use (RSS; under ASan, its allocator's count) after the first 10 % of
    100,000 ticks with two events each (record and event log full by then) grows by less
    than 1 MB to the end (an unbounded log of these 180,000 events grew RSS by 3.5 MB);
    the result holds the last events only.
    ``clik bench`` runs the same for a million ticks (``memory_growth_mb.controller_session``)."""
    ctl, tip, moves = blinking(record_size=100, event_size=10_000)
    n = 100_000
    in_use, name = memory_in_use()
    events = 0
    used_10 = 0
    gc.collect()
    for k in range(n):
        tick = ctl.step(tip, obstacles=moves[k & 1])
        events += len(tick.events)
        if k == n // 10:
            gc.collect()
            used_10 = in_use()
    gc.collect()
    used_end = in_use()
    assert events >= 2 * n - 1
    assert used_10 > 0
    assert used_end - used_10 < 1e6, f"{name}: {(used_end - used_10) / 1e6:.2f} MB"
    result = ctl.result()
    assert len(result.events) == 10_000
    assert result.events_dropped == events - 10_000
    assert result.q.shape[0] == 100
    assert result.violations == []
