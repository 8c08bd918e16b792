"""Helpers shared by the plots: the runs, their colours and units, axis finishing, saving.

Nothing here draws data: the modules of :mod:`clik.plot` import from this one
and never the other way round.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Literal

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from clik.constraints.joint_limits import limits_by_q
from clik.errors import InputError
from clik.outputs.result import TrackingResult

FIGSIZE = (7.0, 4.0)
"""Size of one plot [in]; with :data:`DPI` a PNG is 840 x 480 pixels."""
DPI = 120
"""Resolution of the PNGs [dots per inch]."""

EVENT_STYLE = {"activate": "-", "release": "--", "skipped": ":"}
"""Line style of a constraint event's vertical line, by action."""

Results = TrackingResult | Sequence[TrackingResult]
"""One result, or several to overlay."""

DISPLAY = {"rad": (180.0 / math.pi, "deg"), "m": (1.0, "m"), "": (1.0, "")}
"""Configuration unit -> (factor to the displayed unit, displayed unit)."""


# -- the runs ----------------------------------------------------------------------------


def as_list(results: Results) -> list[TrackingResult]:
    """``results`` as a non-empty list of results.

    Raises:
        InputError: No result, or an object that is not a result.
    """
    if isinstance(results, TrackingResult):
        return [results]
    results = list(results)
    if not results:
        raise InputError("results", "at least one TrackingResult")
    for r in results:
        if not isinstance(r, TrackingResult):
            raise InputError("results", "TrackingResult objects", type(r).__name__)
    return results


def run_labels(results: list[TrackingResult], labels: Sequence[str] | None) -> list[str]:
    """Legend label of each result: ``labels``, or by default the scenario names.

    Raises:
        InputError: ``labels`` is not one label per result.
    """
    if labels is None:
        return [str(r.info.get("scenario", f"run {i + 1}")) for i, r in enumerate(results)]
    if isinstance(labels, str) or len(labels) != len(results):
        raise InputError("labels", f"{len(results)} labels, one per result", labels)
    return [str(label) for label in labels]


def colors(n: int) -> list[str]:
    """``n`` colours from Matplotlib's colour cycle (repeated when it is shorter)."""
    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    return [cycle[i % len(cycle)] for i in range(n)]


def min_distance(result: TrackingResult) -> np.ndarray | None:
    """The run's minimum link-obstacle distance [m], None when it has no obstacle distance."""
    d = result.min_obstacle_distance
    if d is None or not result.info.get("obstacles") or not np.isfinite(d).any():
        return None
    return d


def joint_limits(result: TrackingResult) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(lower, upper, threshold) of a run's joint-range rows, per configuration entry (nq,).

    NaN where an entry has no row (a continuous joint); None when the run had no
    joint-range rows or they cannot be placed (see
    :func:`~clik.constraints.joint_limits.limits_by_q`) [rad or m].
    """
    used = result.info.get("summary_extra", {}).get("joint_limits_used")
    if not used:
        return None
    return limits_by_q(used, result.robot, result.q.shape[1])


def first_joint_limits(
    results: Iterable[TrackingResult],
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """:func:`joint_limits` of the first result that has joint-range rows, or None."""
    return next((lim for lim in map(joint_limits, results) if lim is not None), None)


def display(result: TrackingResult, joint_index: int) -> tuple[float, str]:
    """(factor, unit) showing configuration entry ``joint_index``.

    A revolute joint is shown in degrees, a prismatic one in metres, a continuous
    joint's cos or sin unitless. Without the robot (a result read back from a
    file) every entry is shown as an angle.
    """
    units = getattr(result.robot, "q_units", None)
    if units is not None and joint_index < len(units):
        return DISPLAY[units[joint_index]]
    return DISPLAY["rad"]


# -- axes --------------------------------------------------------------------------------


def draw_events(
    ax: Axes, result: TrackingResult, color: str, prefix: str | None = None
) -> list[Any]:
    """Vertical lines at the events of ``result`` whose constraint starts with ``prefix``."""
    lines = []
    for event in result.events:
        if prefix is not None and not str(event["constraint"]).startswith(prefix):
            continue
        line = ax.axvline(
            float(event["t"]),
            color=color,
            linestyle=EVENT_STYLE.get(str(event["action"]), "-."),
            linewidth=0.8,
            alpha=0.7,
        )
        line.set_gid("event")
        lines.append(line)
    return lines


def event_legend(ax: Axes) -> None:
    """Legend entries (grey) for the event line styles drawn on the axes."""
    drawn = {line.get_linestyle() for line in ax.lines if line.get_gid() == "event"}
    for action, style in EVENT_STYLE.items():
        if style in drawn:
            ax.plot([], [], color="0.4", linestyle=style, linewidth=0.8, label=action)


def finish(
    ax: Axes, ylabel: str, events: bool, which: Literal["major", "minor", "both"] = "major"
) -> Axes:
    """Time axis, the y label, the events' legend entries, grid and legend."""
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    if events:
        event_legend(ax)
    ax.grid(True, which=which, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def drop_legend(ax: Axes) -> None:
    """Remove the axes' legend, if it has one."""
    legend = ax.get_legend()
    if legend is not None:
        legend.remove()


# -- figures and files -------------------------------------------------------------------


def new_figure(nrows: int = 1, ncols: int = 1, size: tuple[float, float] = FIGSIZE) -> Figure:
    """A figure (no pyplot, no GUI backend) with an ``nrows`` x ``ncols`` grid of axes."""
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    fig.subplots(nrows, ncols, squeeze=False)
    return fig


def save_figures(named: Iterable[tuple[str, Figure]], out: Path) -> list[Path]:
    """Write each (file name, figure) pair into the folder ``out`` (created if missing).

    Returns:
        The paths written, in order.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in named:
        path = out / name
        fig.savefig(path)
        written.append(path)
    return written
