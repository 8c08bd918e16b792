"""Time series of one or several runs: the task error, the obstacle distance, a joint.

These are the paper's Figs. 3-5 drawn for any run, into an ``Axes`` the caller owns.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes

from clik.errors import InputError
from clik.outputs.result import TrackingResult
from clik.plot._common import (
    Results,
    as_list,
    colors,
    display,
    draw_events,
    finish,
    first_joint_limits,
    min_distance,
    run_labels,
)

Limit = float | tuple[float | None, float | None]
"""A joint limit: one value, or a ``(lower, upper)`` pair (either may be None) [rad or m]."""


def tracking_error(
    ax: Axes,
    results: Results,
    labels: Sequence[str] | None = None,
    *,
    log: bool = True,
    events: bool = True,
) -> Axes:
    """The task error norm ``|e| = |x_d - x|`` against time (the paper's Fig. 3).

    Args:
        ax: Axes to draw into.
        results: One result or several, overlaid.
        labels: Legend label of each result (default: its scenario name).
        log: Logarithmic error axis (zero samples are not drawn).
        events: Mark every constraint event as a vertical line.

    Returns:
        ``ax``, with one data line per result.
    """
    runs = as_list(results)
    names = run_labels(runs, labels)
    for r, name, color in zip(runs, names, colors(len(runs)), strict=True):
        err = np.asarray(r.task_error_norm, dtype=float)
        if log:
            err = np.where(err > 0.0, err, np.nan)
        ax.plot(r.t, err, color=color, label=name)
        if events:
            draw_events(ax, r, color)
    if log:
        ax.set_yscale("log")
    unit = "m" if runs[0].reference_position is not None else "rad"
    return finish(ax, f"tracking error |e| [{unit}]", events, which="both")


def obstacle_distance(
    ax: Axes,
    results: Results,
    labels: Sequence[str] | None = None,
    threshold: float | None = None,
    *,
    by_obstacle: bool = False,
    events: bool = True,
) -> Axes:
    """The minimum link-obstacle distance against time, with ``d_o`` drawn (the paper's Fig. 4).

    Args:
        ax: Axes to draw into.
        results: One result or several, overlaid; runs without obstacles are skipped.
        labels: Legend label of each result.
        threshold: ``d_o`` [m] drawn as a horizontal line; default: the runs' common
            obstacle threshold (``result.info["obstacles"]``), none if they differ.
        by_obstacle: One line per obstacle (``result.extra["obstacle_distance"]``)
            instead of the minimum over obstacles.
        events: Mark the obstacle constraints' events.

    Returns:
        ``ax``; the threshold line has ``gid == "threshold"``.

    Raises:
        InputError: No result has obstacles.
    """
    runs = as_list(results)
    names = run_labels(runs, labels)
    drawn = []
    for r, name, color in zip(runs, names, colors(len(runs)), strict=True):
        d = min_distance(r)
        if d is None:
            continue
        drawn.append(r)
        per = r.extra.get("obstacle_distance")
        if by_obstacle and per is not None:
            _per_obstacle(ax, r, per, name, color if len(runs) > 1 else None)
        else:
            ax.plot(r.t, d, color=color, label=name)
        if events:  # one colour per obstacle when a single run is split: grey events
            single = by_obstacle and per is not None and len(runs) == 1
            draw_events(ax, r, "0.4" if single else color, "obstacle:")
    if not drawn:
        raise InputError("results", "at least one result with obstacles")
    if threshold is None:
        threshold = _obstacle_threshold(drawn)
    if threshold is not None:
        line = ax.axhline(
            threshold,
            color="k",
            linestyle="--",
            linewidth=1.0,
            label=f"threshold d_o = {threshold:g} m",
        )
        line.set_gid("threshold")
    ax.axhline(0.0, color="0.5", linewidth=0.6).set_gid("contact")
    return finish(ax, "link-obstacle distance [m]", events)


def _per_obstacle(
    ax: Axes, r: TrackingResult, per: np.ndarray, name: str, color: str | None
) -> None:
    """One distance line per obstacle of run ``r``.

    ``color`` None (a single run): one colour per obstacle, labelled with its name;
    otherwise the run's colour, one line style per obstacle, labelled ``run: obstacle``.
    """
    styles = ["-", "--", "-.", ":"]
    for i, obstacle in enumerate(r.info["obstacles"]):
        ax.plot(
            r.t,
            per[:, i],
            color=f"C{i}" if color is None else color,
            linestyle="-" if color is None else styles[i % 4],
            label=obstacle["name"] if color is None else f"{name}: {obstacle['name']}",
        )


def _obstacle_threshold(results: list[TrackingResult]) -> float | None:
    """The common threshold ``d_o`` of the results' obstacles [m], or None."""
    values = {
        float(o["threshold"])
        for r in results
        for o in r.info.get("obstacles", [])
        if o.get("threshold") is not None
    }
    return values.pop() if len(values) == 1 else None


def joint(
    ax: Axes,
    results: Results,
    labels: Sequence[str] | None = None,
    joint_index: int = 0,
    limit: Limit | None = None,
    threshold: float | None = None,
    *,
    events: bool = True,
) -> Axes:
    """One joint against time, with its limit and threshold band (the paper's Fig. 5).

    A revolute joint is drawn in degrees, a prismatic joint in metres, a
    continuous joint's cos or sin entry unitless (known from the result's robot;
    a result without its robot is drawn in degrees).

    Args:
        ax: Axes to draw into.
        results: One result or several, overlaid.
        labels: Legend label of each result.
        joint_index: Index of the joint in ``q`` (0-based: the case study's ``q_3`` is 2).
        limit: The joint limit [rad or m]: a ``(lower, upper)`` pair (either may be
            None), or one value, an upper limit when the run starts below it and a
            lower one otherwise. Default: the limits of the runs' joint-range rows
            (``info["summary_extra"]["joint_limits_used"]``) that lie near the plotted
            range, none when the runs had no such rows.
        threshold: ``d_q`` [rad or m]: the band between the limit and ``limit -+ d_q``
            is shaded and its inner edge drawn; default: the runs' own threshold.
        events: Mark the events of this joint's range constraints.

    Returns:
        ``ax``; the limit lines have ``gid == "limit"``, the threshold lines
        ``gid == "threshold"``, the shaded band ``gid == "threshold_band"``.
    """
    runs = as_list(results)
    names = run_labels(runs, labels)
    first = runs[0]
    nq = first.q.shape[1]
    if not (0 <= joint_index < nq):
        raise InputError("joint_index", f"an index in [0, {nq - 1}]", joint_index)
    jname = _joint_name(first, joint_index)
    factor, unit = display(first, joint_index)
    lo_data, hi_data = math.inf, -math.inf
    for r, name, color in zip(runs, names, colors(len(runs)), strict=True):
        q = factor * r.q[:, joint_index]
        lo_data, hi_data = min(lo_data, float(q.min())), max(hi_data, float(q.max()))
        ax.plot(r.t, q, color=color, label=name)
        if events:
            draw_events(ax, r, color, f"joint:{jname}:" if jname else "joint:")
    lower, upper, d_q = _resolve_limits(
        runs, joint_index, limit, threshold, lo_data, hi_data, factor, unit
    )
    for side, value, sign in (("lower", lower, 1.0), ("upper", upper, -1.0)):
        if value is not None:
            _draw_limit(ax, side, value, sign, d_q, factor, unit)
    ylabel = (
        f"q{joint_index + 1}" + (f" ({jname})" if jname else "") + (f" [{unit}]" if unit else "")
    )
    return finish(ax, ylabel, events)


def _joint_name(result: TrackingResult, joint_index: int) -> str | None:
    """Name of the joint of configuration entry ``joint_index``, when the result has its robot."""
    names = getattr(result.robot, "q_joint_names", None)
    if names is not None and joint_index < len(names):
        return str(names[joint_index])
    return None


def _draw_limit(
    ax: Axes,
    side: str,
    value: float,
    sign: float,
    d_q: float | None,
    factor: float,
    unit: str,
) -> None:
    """The ``side`` (lower or upper) limit line at ``value``, and its threshold band.

    ``sign`` points from the limit into the joint's range (+1 for the lower limit);
    ``factor`` and ``unit`` give the displayed unit (see :func:`~clik.plot._common.display`).
    """
    suffix = f" {unit}" if unit else ""
    shown = factor * value
    line = ax.axhline(shown, color="k", linewidth=1.2, label=f"{side} limit {shown:g}{suffix}")
    line.set_gid("limit")
    if d_q is None:
        return
    inner = factor * (value + sign * d_q)
    band = ax.axhspan(min(shown, inner), max(shown, inner), color="0.5", alpha=0.2)
    band.set_gid("threshold_band")
    tline = ax.axhline(
        inner,
        color="k",
        linestyle="--",
        linewidth=1.0,
        label=f"threshold {inner:g}{suffix} (d_q = {factor * d_q:g}{suffix})",
    )
    tline.set_gid("threshold")


def _resolve_limits(
    runs: list[TrackingResult],
    i: int,
    limit: Limit | None,
    threshold: float | None,
    lo_shown: float,
    hi_shown: float,
    factor: float = 180.0 / math.pi,
    unit: str = "deg",
) -> tuple[float | None, float | None, float | None]:
    """Lower and upper limits to draw and ``d_q`` [rad or m].

    ``lo_shown``, ``hi_shown``: the plotted data range in the displayed unit
    (``factor`` times the configuration value); default limits farther than
    half that range (at least 10 deg, or 0.05 m) are not drawn.
    """
    used = first_joint_limits(runs)
    if threshold is None and used is not None and math.isfinite(used[2][i]):
        threshold = float(used[2][i])
    if limit is None:
        if used is None:
            return None, None, None
        min_span, min_margin = (1.0, 10.0) if unit == "deg" else (0.01, 0.05)
        span = max(hi_shown - lo_shown, min_span)
        margin = max(min_margin, 0.5 * span)
        near = (lo_shown - margin, hi_shown + margin)
        pair = [float(used[0][i]), float(used[1][i])]
        lower, upper = (
            v if math.isfinite(v) and near[0] <= factor * v <= near[1] else None for v in pair
        )
        return lower, upper, threshold
    if isinstance(limit, tuple | list):
        if len(limit) != 2:
            raise InputError("limit", "one value or a (lower, upper) pair [rad or m]", limit)
        lo, hi = limit
        return (None if lo is None else float(lo), None if hi is None else float(hi), threshold)
    value = float(limit)
    if runs[0].q[0, i] <= value:
        return None, value, threshold
    return value, None, threshold
