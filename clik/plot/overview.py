"""Overview figures of any runs, written by ``clik solve --plots``.

The tracking error, the obstacle distance (runs with obstacles) and one panel per joint.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure

from clik.outputs.result import TrackingResult
from clik.plot._common import (
    Results,
    as_list,
    drop_legend,
    min_distance,
    new_figure,
    run_labels,
    save_figures,
)
from clik.plot.series import joint, obstacle_distance, tracking_error


def result_plots(results: Results, names: Sequence[str] | None = None) -> dict[str, Figure]:
    """Figures for ``clik solve --plots``: tracking error, distance (if any), joints.

    Args:
        results: One result or several (overlaid).
        names: Label of each result.

    Returns:
        ``{"tracking_error": ..., "obstacle_distance": ..., "joints": ...}``, the
        distance only when a run has obstacles. The joint figure has one panel per
        configuration entry (revolute joints in degrees, prismatic joints in metres)
        with the joint-range limits and thresholds of runs that had joint-range rows.
    """
    runs = as_list(results)
    labels = run_labels(runs, names)
    figs: dict[str, Figure] = {}
    fig = new_figure()
    tracking_error(fig.axes[0], runs, labels)
    fig.axes[0].set_title("Tracking error norm")
    figs["tracking_error"] = fig
    if any(min_distance(r) is not None for r in runs):
        fig = new_figure()
        obstacle_distance(fig.axes[0], runs, labels)
        fig.axes[0].set_title("Minimum link-obstacle distance")
        figs["obstacle_distance"] = fig
    figs["joints"] = _joints_figure(runs, labels)
    return figs


def _joints_figure(runs: list[TrackingResult], labels: list[str]) -> Figure:
    """One panel per configuration entry, at most three per row; one legend (the first)."""
    nq = runs[0].q.shape[1]
    cols = min(nq, 3)
    rows = math.ceil(nq / cols)
    fig = new_figure(rows, cols, size=(4.0 * cols, 2.8 * rows))
    for i, ax in enumerate(fig.axes):
        if i >= nq:
            ax.set_visible(False)
            continue
        joint(ax, runs, labels, i)
        if i > 0:
            drop_legend(ax)
    fig.suptitle("Joints")
    return fig


def save_result_plots(
    results: Sequence[TrackingResult], out: Path, names: Sequence[str]
) -> list[Path]:
    """Write :func:`result_plots` as PNGs into ``out`` (``clik solve --plots``).

    Files: ``tracking_error.png``, ``obstacle_distance.png`` (runs with obstacles),
    ``joints.png``, ``task_errors.png`` (runs of several tasks: one panel per task).

    Args:
        results: The results (overlaid when several).
        out: Folder to write into (created if missing).
        names: Label of each result.

    Returns:
        The paths written.
    """
    figs = result_plots(results, names)
    if any(len(r.task_errors) > 1 for r in results):
        from clik.plot.tasks import task_errors

        figs["task_errors"] = task_errors(results, list(names))
    return save_figures(((f"{key}.png", fig) for key, fig in figs.items()), out)
