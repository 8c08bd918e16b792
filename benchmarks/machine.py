"""The machine a bench ran on: CPU, memory, load, CPU time and package versions."""

from __future__ import annotations

import importlib.metadata
import os
import platform
from typing import Any


def _cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what :mod:`platform` knows."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return cpu


def _memory_gb() -> float | None:
    """Total memory [GB], when psutil is installed."""
    try:
        import psutil
    except ImportError:
        return None
    return round(psutil.virtual_memory().total / 1e9, 2)


def machine_info() -> dict[str, Any]:
    """CPU, core count, memory, OS, Python and load average (a noisy machine shows here)."""
    info: dict[str, Any] = {
        "cpu": _cpu_name(),
        "cores": os.cpu_count(),
        "memory_gb": _memory_gb(),
        "os": platform.platform(),
        "python": platform.python_version(),
    }
    if hasattr(os, "sched_getaffinity"):
        info["cores_available"] = len(os.sched_getaffinity(0))
    if hasattr(os, "getloadavg"):
        info["load_average_1min_start"] = round(os.getloadavg()[0], 2)
    return info


def cpu_seconds() -> float:
    """CPU time of this process and its finished children (the memory runs) [s]."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def versions() -> dict[str, str | None]:
    """Versions of clik and of the packages it is compared with or built on."""
    out: dict[str, str | None] = {}
    names = ("clik", "pin", "coal", "numpy", "pin-pink", "mink", "mujoco", "qpsolvers", "daqp",
             "quadprog")  # fmt: skip
    for name in names:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    return out
