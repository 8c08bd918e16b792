"""The errors of a several-task run, task by task: one panel per task, named by task.

A run with ``tasks=[clik.Goal(...), ...]`` records its primary task's error norms
(``result.task_error_norm`` and ``result.orientation_error_norm``) and the other
tasks' (``result.extra["task_errors"]``, (N, G, 2): ``(first, second)`` per task, in
the order of ``result.info["tasks"][1:]``). Each task's error is drawn as the error
plots draw the primary's (:func:`~clik.plot.series.tracking_error`): against time, on a
log scale, zero samples left out, labelled with what its kind says its norms measure
(``task_errors[name]["error"]`` and ``["unit"]``: the position error [m] of a frame, the
joints' error [rad] of a posture...); a second norm (a pose task's orientation error
[rad]) is drawn dashed on the same panel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from clik.errors import InputError
from clik.outputs.result import TrackingResult
from clik.plot._common import Results, as_list, colors, draw_events, finish, new_figure, run_labels

PANEL_SIZE = (6.0, 3.0)
"""Size of one panel of :func:`task_errors` [in]."""


@dataclass(frozen=True)
class TaskSeries:
    """One task's recorded error norms in a run.

    Attributes:
        name: The task's name.
        kind: Its kind (``"pose"``, ``"posture"``, ...).
        priority: Its priority (1 is the highest).
        first: The first norm at each recorded sample (N,) (see the module docstring).
        second: The second norm (N,) (a pose task's orientation error [rad]), or None.
        words: What each measures and its unit: ``((what, unit), (what, unit) or None)``.
    """

    name: str
    kind: str
    priority: int
    first: np.ndarray
    second: np.ndarray | None
    words: tuple[tuple[str, str], tuple[str, str] | None]


def task_names(result: TrackingResult) -> list[str]:
    """The run's tasks in row order (the primary first); ``["task"]`` for a one-task run."""
    return list(result.info.get("tasks") or result.task_errors or ["task"])


def task_series(result: TrackingResult) -> dict[str, TaskSeries]:
    """Every task's error norms over the run, by name, in row order.

    Raises:
        InputError: A several-task result without its record (``extra["task_errors"]``).
    """
    names = task_names(result)
    entries = result.task_errors
    out: dict[str, TaskSeries] = {}
    record = result.extra.get("task_errors")
    if len(names) > 1 and (record is None or np.shape(record)[1:] != (len(names) - 1, 2)):
        raise InputError(
            "result.extra['task_errors']",
            f"the other tasks' error record (N, {len(names) - 1}, 2)",
            None if record is None else np.shape(record),
        )
    for i, name in enumerate(names):
        entry = entries.get(name, {})
        kind = str(entry.get("kind", result.info.get("task", "")))
        both = "max_orientation" in entry
        words = (
            (str(entry.get("error", "error")), str(entry.get("unit", ""))),
            (str(entry.get("second_error", "orientation error")), str(entry["second_unit"]))
            if "second_unit" in entry
            else None,
        )
        if i == 0:
            first = np.asarray(result.task_error_norm, dtype=float)
            o = result.orientation_error_norm
            second = None if not both or o is None else np.asarray(o, dtype=float)
        else:
            assert record is not None
            first = np.asarray(record[:, i - 1, 0], dtype=float)
            second = np.asarray(record[:, i - 1, 1], dtype=float) if both else None
        out[name] = TaskSeries(name, kind, int(entry.get("priority", 1)), first, second, words)
    return out


def _positive(values: np.ndarray, log: bool) -> np.ndarray:
    return np.where(values > 0.0, values, np.nan) if log else values


def task_error(
    ax: Axes,
    results: Results,
    name: str,
    labels: Sequence[str] | None = None,
    *,
    log: bool = True,
    events: bool = False,
) -> Axes:
    """Task ``name``'s error norms against time, one colour per run.

    Args:
        ax: Axes to draw into.
        results: One result or several, overlaid (runs without the task are skipped).
        name: The task's name (a key of ``result.task_errors``).
        labels: Legend label of each result (default: its scenario name).
        log: Logarithmic error axis (zero samples are not drawn).
        events: Mark every constraint event as a vertical line.

    Returns:
        ``ax``; the first norm's lines are solid (``gid == "first"``), a pose task's
        orientation lines dashed (``gid == "orientation"``).

    Raises:
        InputError: No result has task ``name`` (the message lists theirs).
    """
    runs = as_list(results)
    names = run_labels(runs, labels)
    drawn: TaskSeries | None = None
    for r, label, color in zip(runs, names, colors(len(runs)), strict=True):
        series = task_series(r).get(name)
        if series is None:
            continue
        drawn = series
        (what, unit), second_words = series.words
        prefix = f"{label}: " if len(runs) > 1 else ""
        first_label = f"{prefix}{what} [{unit}]"
        line = ax.plot(r.t, _positive(series.first, log), color=color, label=first_label)
        line[0].set_gid("first")
        if series.second is not None:
            line = ax.plot(
                r.t, _positive(series.second, log), color=color, linestyle="--",
                label=f"{prefix}{second_words[0]} [{second_words[1]}]"
                if second_words is not None else f"{prefix}orientation [rad]",
            )  # fmt: skip
            line[0].set_gid("orientation")
        if events:
            draw_events(ax, r, color)
    if drawn is None:
        known = sorted({n for r in runs for n in task_names(r)})
        raise InputError("name", f"a task of the results, one of {known}", name)
    if log:
        ax.set_yscale("log")
    (_, unit), second_words = drawn.words
    ylabel = f"|e| [{unit}]"
    if drawn.second is not None:
        ylabel += f", [{second_words[1] if second_words is not None else 'rad'}]"
    ax.set_title(f"{name} ({drawn.kind}, priority {drawn.priority})")
    return finish(ax, ylabel, events, which="both")


def task_errors(
    results: Results,
    labels: Sequence[str] | None = None,
    *,
    ncols: int = 2,
    log: bool = True,
    events: bool = False,
) -> Figure:
    """A figure with one error panel per task (:func:`task_error`), named by task.

    The panels follow the first result's tasks in row order (the primary first), then
    any task only another result has.

    Args:
        results: One result or several, overlaid on each panel.
        labels: Legend label of each result.
        ncols: Panels per row.
        log: Logarithmic error axes.
        events: Mark the constraint events.

    Returns:
        The figure (no pyplot): its first ``len(tasks)`` axes are the panels, the
        others are hidden.

    Raises:
        InputError: A bad ``ncols``.
    """
    runs = as_list(results)
    if isinstance(ncols, bool) or not isinstance(ncols, int) or ncols < 1:
        raise InputError("ncols", "an integer >= 1", ncols)
    names: list[str] = []
    for r in runs:
        names += [n for n in task_names(r) if n not in names]
    cols = min(ncols, len(names))
    rows = math.ceil(len(names) / cols)
    fig = new_figure(rows, cols, (PANEL_SIZE[0] * cols, PANEL_SIZE[1] * rows))
    axes = fig.axes
    for ax, name in zip(axes, names, strict=False):
        task_error(ax, runs, name, labels, log=log, events=events)
    for ax in axes[len(names) :]:
        ax.set_visible(False)
    return fig
