"""Peak resident set size of this process: reset where the OS allows it, then read."""

from __future__ import annotations

import sys


def proc_status_kb(field: str) -> int | None:
    """A ``kB`` field of ``/proc/self/status`` (e.g. ``VmRSS``), or None where there is none.

    Args:
        field: Name of the field, without the colon.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def ru_maxrss_bytes() -> int:
    """Peak RSS of this process since it started [bytes] (``getrusage``)."""
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(peak if sys.platform == "darwin" else peak * 1024)


def rss_baseline() -> tuple[int, str]:
    """Reset the peak RSS where the OS allows it; return (baseline [bytes], method).

    Linux: writing 5 to ``/proc/self/clear_refs`` resets ``VmHWM`` (the peak RSS) to
    the current RSS, so the run's own peak is measured even below an earlier peak
    (imports). Elsewhere ``ru_maxrss`` cannot be reset: the growth is a lower bound.
    """
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        rss = proc_status_kb("VmRSS")
        if rss is not None and proc_status_kb("VmHWM") is not None:
            return rss * 1024, "VmHWM after clear_refs"
    except OSError:
        pass
    return ru_maxrss_bytes(), "ru_maxrss (lower bound)"


def peak_rss_bytes(method: str) -> int:
    """Peak RSS [bytes] by the ``method`` :func:`rss_baseline` returned.

    Args:
        method: ``"VmHWM after clear_refs"`` or ``"ru_maxrss (lower bound)"``.
    """
    if method.startswith("VmHWM"):
        hwm = proc_status_kb("VmHWM")
        if hwm is not None:
            return hwm * 1024
    return ru_maxrss_bytes()
