"""A controller's memory is bounded in long sessions (issue 40, case 7).

A controller keeps its last ``record_size`` ticks and its last ``event_size`` constraint
events, counting those it dropped: a million ticks with an event at every tick grow its
memory by nothing once the record and the event log are full, and ``result()`` holds
(and costs) only what they keep. The time ``result()`` takes is a ``clik bench`` figure
(``controller_session.result_ms``), not a test's; the scene is the bench's.
"""

from __future__ import annotations

import gc

from benchmarks.rss import proc_status_kb
from benchmarks.session_memory import blinking


def test_a_long_session_with_events_at_every_tick_keeps_memory_flat() -> None:
    """RSS after the first 10 % of 100,000 ticks with two events each (record and event
    log full by then) grows by less than 1 MB to the end (an unbounded log of these
    180,000 events grew it by 3.5 MB); the result holds the last events only.
    ``clik bench`` runs the same for a million ticks (``memory_growth_mb.controller_session``)."""
    ctl, tip, moves = blinking(record_size=100, event_size=10_000)
    n = 100_000
    events = 0
    rss_10 = 0
    gc.collect()
    for k in range(n):
        tick = ctl.step(tip, obstacles=moves[k & 1])
        events += len(tick.events)
        if k == n // 10:
            gc.collect()
            rss_10 = proc_status_kb("VmRSS") or 0
    gc.collect()
    rss_end = proc_status_kb("VmRSS") or 0
    assert events >= 2 * n - 1
    assert (rss_end - rss_10) * 1024 < 1e6, f"{(rss_end - rss_10) / 1024:.2f} MB"
    result = ctl.result()
    assert len(result.events) == 10_000
    assert result.events_dropped == events - 10_000
    assert result.q.shape[0] == 100
    assert result.violations == []
