"""Plots of tracking results: the paper's Figs. 3-5 for any run, and a planar stick drawing.

Axes-level functions draw into a Matplotlib ``Axes`` that the caller owns
(``plt.subplots()`` in a notebook, or a bare :class:`~matplotlib.figure.Figure`):

- :func:`tracking_error`: the task error norm ``|e|`` against time (Fig. 3).
- :func:`obstacle_distance`: the minimum link-obstacle distance with the
  threshold ``d_o`` drawn (Fig. 4).
- :func:`joint`: one joint against time, with its limit and the threshold band
  ``d_q`` drawn (Fig. 5): a revolute joint in degrees, a prismatic joint in
  metres (a continuous joint's cos and sin as they are).
- :func:`planar_stick`: the arm drawn every ``every`` seconds, projected on a
  plane, with the obstacles and their thresholds.

Each takes one result or several (overlaid, one colour each) and marks the
constraint events (docs/method.md, "Activation and release") as vertical lines in
the colour of their run: solid for ``activate``, dashed for ``release``,
dotted for ``skipped``.

File-level functions build figures with :class:`matplotlib.figure.Figure`
(no GUI backend, no global pyplot state) and write PNGs:
:func:`case_study_figures` (``clik demo``) and :func:`save_result_plots`
(``clik solve --plots``).

Artists clik adds besides the data carry a ``gid`` so that code (and tests)
can find them: ``"threshold"``, ``"limit"``, ``"threshold_band"``,
``"event"``, ``"contact"`` (distance 0), and in stick drawings ``"stick"``,
``"path"``, ``"reference"``, ``"obstacle"``.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

if (
    "matplotlib.pyplot" not in sys.modules
    and not os.environ.get("MPLBACKEND")
    and not os.environ.get("DISPLAY")
    and not os.environ.get("WAYLAND_DISPLAY")
    and sys.platform.startswith("linux")
):
    matplotlib.use("Agg")  # headless: never try a GUI backend

import numpy as np
import pinocchio as pin
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from clik.errors import InputError
from clik.result import TrackingResult

if TYPE_CHECKING:
    from collections.abc import Iterable

__all__ = [
    "CASE_STUDY_JOINT",
    "CASE_STUDY_LIMIT",
    "CASE_STUDY_THRESHOLD",
    "case_study_figures",
    "case_study_plots",
    "joint",
    "obstacle_distance",
    "planar_stick",
    "result_plots",
    "save_result_plots",
    "tracking_error",
]

CASE_STUDY_JOINT = 2
"""Index of ``q_3`` in the case study's joint vector."""
CASE_STUDY_LIMIT = math.radians(-80.0)
"""The case study's joint limit ``q_3 <= -80 deg`` [rad] (used when a run does not record it)."""
CASE_STUDY_THRESHOLD = math.radians(2.0)
"""The case study's joint-range threshold ``d_q = 2 deg`` [rad]."""

FIGSIZE = (7.0, 4.0)
"""Size of one plot [in]; with :data:`DPI` a PNG is 840 x 480 pixels."""
DPI = 120

_EVENT_STYLE = {"activate": "-", "release": "--", "skipped": ":"}
Results = TrackingResult | Sequence[TrackingResult]


# -- helpers -----------------------------------------------------------------------------


def _as_list(results: Results) -> list[TrackingResult]:
    if isinstance(results, TrackingResult):
        return [results]
    results = list(results)
    if not results:
        raise InputError("results", "at least one TrackingResult")
    for r in results:
        if not isinstance(r, TrackingResult):
            raise InputError("results", "TrackingResult objects", type(r).__name__)
    return results


def _labels(results: list[TrackingResult], labels: Sequence[str] | None) -> list[str]:
    if labels is None:
        return [str(r.info.get("scenario", f"run {i + 1}")) for i, r in enumerate(results)]
    if isinstance(labels, str) or len(labels) != len(results):
        raise InputError("labels", f"{len(results)} labels, one per result", labels)
    return [str(label) for label in labels]


def _colors(n: int) -> list[str]:
    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    return [cycle[i % len(cycle)] for i in range(n)]


def _events(ax: Axes, result: TrackingResult, color: str, prefix: str | None = None) -> list[Any]:
    """Vertical lines at the events of ``result`` whose constraint starts with ``prefix``."""
    lines = []
    for event in result.events:
        if prefix is not None and not str(event["constraint"]).startswith(prefix):
            continue
        line = ax.axvline(
            float(event["t"]),
            color=color,
            linestyle=_EVENT_STYLE.get(str(event["action"]), "-."),
            linewidth=0.8,
            alpha=0.7,
        )
        line.set_gid("event")
        lines.append(line)
    return lines


def _event_legend(ax: Axes) -> None:
    """Legend entries (grey) for the event line styles drawn on the axes."""
    drawn = {line.get_linestyle() for line in ax.lines if line.get_gid() == "event"}
    for action, style in _EVENT_STYLE.items():
        if style in drawn:
            ax.plot([], [], color="0.4", linestyle=style, linewidth=0.8, label=action)


def _joint_name(result: TrackingResult, joint_index: int) -> str | None:
    """Name of the joint of configuration entry ``joint_index``, when the result has its robot."""
    names = getattr(result.robot, "q_joint_names", None)
    if names is not None and joint_index < len(names):
        return str(names[joint_index])
    return None


_DISPLAY = {"rad": (180.0 / math.pi, "deg"), "m": (1.0, "m"), "": (1.0, "")}
"""Configuration unit -> (factor to the displayed unit, displayed unit)."""


def _display(result: TrackingResult, joint_index: int) -> tuple[float, str]:
    """(factor, unit) showing configuration entry ``joint_index``: a revolute joint in
    degrees, a prismatic one in metres, a continuous joint's cos or sin unitless.

    Without the robot (a result read back from a file) every entry is shown as an angle.
    """
    units = getattr(result.robot, "q_units", None)
    if units is not None and joint_index < len(units):
        return _DISPLAY[units[joint_index]]
    return _DISPLAY["rad"]


def _obstacle_threshold(results: list[TrackingResult]) -> float | None:
    """The common threshold ``d_o`` of the results' obstacles [m], or None."""
    values = {
        float(o["threshold"])
        for r in results
        for o in r.info.get("obstacles", [])
        if o.get("threshold") is not None
    }
    return values.pop() if len(values) == 1 else None


def _has_distance(result: TrackingResult) -> bool:
    d = result.min_obstacle_distance
    return d is not None and bool(result.info.get("obstacles")) and bool(np.isfinite(d).any())


def _joint_limits(result: TrackingResult) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(lower, upper, threshold) of a run's joint-range rows, per configuration entry (nq,).

    NaN where an entry has no row (a continuous joint); None when the run had no
    joint-range rows or they cannot be placed (see
    :func:`~clik.constraints.joint_limits.limits_by_q`) [rad or m].
    """
    used = result.info.get("summary_extra", {}).get("joint_limits_used")
    if not used:
        return None
    from clik.constraints.joint_limits import limits_by_q

    return limits_by_q(used, result.robot, result.q.shape[1])


# -- axes-level plots --------------------------------------------------------------------


def _finish(ax: Axes, ylabel: str, events: bool, which: str = "major") -> Axes:
    """Time axis, the y label, the events' legend entries, grid and legend."""
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    if events:
        _event_legend(ax)
    ax.grid(True, which=which, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


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
    runs = _as_list(results)
    names = _labels(runs, labels)
    for r, name, color in zip(runs, names, _colors(len(runs)), strict=True):
        err = np.asarray(r.task_error_norm, dtype=float)
        if log:
            err = np.where(err > 0.0, err, np.nan)
        ax.plot(r.t, err, color=color, label=name)
        if events:
            _events(ax, r, color)
    if log:
        ax.set_yscale("log")
    unit = "m" if runs[0].reference_position is not None else "rad"
    return _finish(ax, f"tracking error |e| [{unit}]", events, which="both")


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
    runs = _as_list(results)
    names = _labels(runs, labels)
    drawn = []
    for r, name, color in zip(runs, names, _colors(len(runs)), strict=True):
        if not _has_distance(r):
            continue
        drawn.append(r)
        per = r.extra.get("obstacle_distance")
        if by_obstacle and per is not None:
            styles = ["-", "--", "-.", ":"]
            for i, obstacle in enumerate(r.info["obstacles"]):
                ax.plot(
                    r.t,
                    per[:, i],
                    color=color if len(runs) > 1 else f"C{i}",
                    linestyle=styles[i % 4] if len(runs) > 1 else "-",
                    label=f"{name}: {obstacle['name']}" if len(runs) > 1 else obstacle["name"],
                )
        else:
            ax.plot(r.t, r.min_obstacle_distance, color=color, label=name)
        if events:  # one colour per obstacle when a single run is split: grey events
            single = by_obstacle and per is not None and len(runs) == 1
            _events(ax, r, "0.4" if single else color, "obstacle:")
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
    return _finish(ax, "link-obstacle distance [m]", events)


def joint(
    ax: Axes,
    results: Results,
    labels: Sequence[str] | None = None,
    joint_index: int = 0,
    limit: float | tuple[float | None, float | None] | None = None,
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
    runs = _as_list(results)
    names = _labels(runs, labels)
    first = runs[0]
    nq = first.q.shape[1]
    if not (0 <= joint_index < nq):
        raise InputError("joint_index", f"an index in [0, {nq - 1}]", joint_index)
    jname = _joint_name(first, joint_index)
    factor, unit = _display(first, joint_index)
    lo_data, hi_data = math.inf, -math.inf
    for r, name, color in zip(runs, names, _colors(len(runs)), strict=True):
        q = factor * r.q[:, joint_index]
        lo_data, hi_data = min(lo_data, float(q.min())), max(hi_data, float(q.max()))
        ax.plot(r.t, q, color=color, label=name)
        if events:
            _events(ax, r, color, f"joint:{jname}:" if jname else "joint:")
    lower, upper, d_q = _resolve_limits(
        runs, joint_index, limit, threshold, lo_data, hi_data, factor, unit
    )
    suffix = f" {unit}" if unit else ""
    for side, value, sign in (("lower", lower, 1.0), ("upper", upper, -1.0)):
        if value is None:
            continue
        shown = factor * value
        line = ax.axhline(shown, color="k", linewidth=1.2, label=f"{side} limit {shown:g}{suffix}")
        line.set_gid("limit")
        if d_q is not None:
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
    ylabel = (
        f"q{joint_index + 1}" + (f" ({jname})" if jname else "") + (f" [{unit}]" if unit else "")
    )
    return _finish(ax, ylabel, events)


def _resolve_limits(
    runs: list[TrackingResult],
    i: int,
    limit: float | tuple[float | None, float | None] | None,
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
    used = next((lim for lim in map(_joint_limits, runs) if lim is not None), None)
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
        lower, upper = limit
        return (
            None if lower is None else float(lower),
            None if upper is None else float(upper),
            threshold,
        )
    value = float(limit)
    if runs[0].q[0, i] <= value:
        return None, value, threshold
    return value, None, threshold


def planar_stick(
    ax: Axes,
    result: TrackingResult,
    every: float = 0.25,
    *,
    plane: str = "xy",
    obstacles: bool = True,
    reference: bool = True,
) -> Axes:
    """The arm drawn every ``every`` seconds, projected on a plane, with the obstacles.

    The sticks join the joint origins (Pinocchio forward kinematics on
    ``result.robot``) and end at the task frame; their colour goes from light
    (t = 0) to dark (the end). Obstacles (``result.info["obstacles"]``) are drawn
    at their position at t = 0 with a dashed outline at their threshold ``d_o``
    (spheres, capsules, cylinders), a moving obstacle with an arrow to where it
    is at the end of the run.

    Args:
        ax: Axes to draw into (its aspect is set equal).
        result: A result that still has its robot (not one read back from a file).
        every: Time between two drawings [s] (the first and last samples are always drawn).
        plane: Projection plane, ``"xy"`` (the planar arm's), ``"xz"`` or ``"yz"``.
        obstacles: Draw the obstacles and their thresholds.
        reference: Draw the reference path of the task frame.

    Returns:
        ``ax``; one stick line (``gid == "stick"``) per drawn sample.

    Raises:
        InputError: The result has no robot, or a bad ``every`` or ``plane``.
    """
    if result.robot is None:
        raise InputError("result.robot", "a result with its robot (as returned by track)")
    if not (math.isfinite(every) and every > 0):
        raise InputError("every", "a positive time [s]", every)
    axes_of = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
    if plane not in axes_of:
        raise InputError("plane", "'xy', 'xz' or 'yz'", plane)
    a, b = axes_of[plane]
    model, data = result.robot.model, result.robot.model.createData()
    t = result.t
    picks = sorted({0, len(t) - 1, *np.searchsorted(t, np.arange(t[0], t[-1], every)).tolist()})
    cmap = matplotlib.colormaps["viridis_r"]
    for n, k in enumerate(picks):
        pin.forwardKinematics(model, data, result.q[k])
        points = [data.oMi[j].translation for j in range(1, model.njoints)]
        points.append(result.position[k])
        pts = np.array(points)
        shade = 0.15 + 0.85 * n / max(1, len(picks) - 1)
        (stick,) = ax.plot(
            pts[:, a], pts[:, b], "-o", color=cmap(shade), markersize=2.5, linewidth=1.2, alpha=0.9
        )
        stick.set_gid("stick")
    (trail,) = ax.plot(
        result.position[:, a], result.position[:, b], color="k", linewidth=0.8, label="end effector"
    )
    trail.set_gid("path")
    if reference and result.reference_position is not None:
        (ref,) = ax.plot(
            result.reference_position[:, a],
            result.reference_position[:, b],
            ":",
            color="C3",
            linewidth=1.2,
            label="reference",
        )
        ref.set_gid("reference")
    if obstacles:
        for o in result.info.get("obstacles", []):
            _draw_obstacle(ax, o, a, b, float(t[-1]))
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def _draw_obstacle(ax: Axes, o: dict[str, Any], a: int, b: int, t_end: float) -> None:
    """An obstacle's outline projected on the plane (a, b), its threshold outline, its path."""
    center = np.asarray(o["position"], dtype=float)
    c2 = (center[a], center[b])
    velocity = np.asarray(o.get("velocity", (0.0, 0.0, 0.0)), dtype=float)
    if np.any(velocity != 0.0):  # a moving obstacle: its path until the end of the run
        end = center + t_end * velocity
        ax.annotate(
            "",
            (end[a], end[b]),
            c2,
            arrowprops={"arrowstyle": "->", "color": "0.3", "linestyle": ":"},
        )
        (ghost,) = ax.plot(end[a], end[b], "o", color="0.3", alpha=0.4, markersize=4)
        ghost.set_gid("obstacle")
    d_o = float(o.get("threshold") or 0.0)
    shape = o.get("shape")
    radius = 0.0
    if shape == "box":
        R = pin.rpy.rpyToMatrix(*np.asarray(o.get("rpy", (0, 0, 0)), dtype=float))
        half = 0.5 * np.asarray(o["size"], dtype=float)
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        world = center + (corners * half) @ R.T
        outline = _hull2d(world[:, [a, b]])
        ax.add_patch(Polygon(outline, closed=True, color="0.3", alpha=0.6, gid="obstacle"))
    else:  # sphere, capsule, cylinder: a disk of the radius; mesh: a marker only
        radius = 0.0 if shape == "mesh" else float(o.get("radius", 0.0) or 0.0)
        ax.add_patch(Circle(c2, max(radius, 1e-3), color="0.3", alpha=0.6, gid="obstacle"))
    (mark,) = ax.plot(*c2, "x", color="0.1", markersize=6)
    mark.set_gid("obstacle")
    if d_o > 0 and shape in ("sphere", "capsule", "cylinder"):
        ax.add_patch(
            Circle(c2, radius + d_o, fill=False, linestyle="--", color="0.3", gid="threshold")
        )
    ax.annotate(
        str(o.get("name", "")), c2, textcoords="offset points", xytext=(6, 6), fontsize="small"
    )


def _hull2d(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points (monotone chain), counter-clockwise."""
    pts = sorted(map(tuple, np.round(points, 12)))
    if len(pts) <= 2:
        return np.array(pts)

    def half(seq: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while (
                len(out) >= 2
                and (
                    (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                    - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                )
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])


# -- figures and files -------------------------------------------------------------------


def _figure(nrows: int = 1, ncols: int = 1, size: tuple[float, float] = FIGSIZE) -> Figure:
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    fig.subplots(nrows, ncols, squeeze=False)
    return fig


def _run_label(name: str) -> str:
    """``case_study_obstacle_pinv`` -> ``obstacle``; other names unchanged."""
    label = name.removeprefix("case_study_").removesuffix("_pinv")
    return {
        "unconstrained": "1 unconstrained",
        "obstacle": "2 obstacle",
        "joint_limit": "3 joint limit",
        "both": "4 both",
    }.get(label, label)


def case_study_plots(results: dict[str, TrackingResult], law: str = "(9)") -> dict[str, Figure]:
    """The paper's Figs. 3-5 and a stick drawing for one law's runs, as figures.

    Args:
        results: Run name -> result (e.g. the four case-study runs of one law).
        law: The law's equation number, for the titles.

    Returns:
        ``{"fig3": ..., "fig4": ..., "fig5": ..., "stick": ...}``; ``fig4`` only when a
        run has obstacles, ``fig5`` only when the robot has a third joint, ``stick``
        only when the results still have their robot.
    """
    names = list(results)
    runs = [results[n] for n in names]
    labels = [_run_label(n) for n in names]
    figs: dict[str, Figure] = {}

    fig = _figure()
    tracking_error(fig.axes[0], runs, labels)
    fig.axes[0].set_title(f"Fig. 3: tracking error norm, law {law}")
    figs["fig3"] = fig

    if any(_has_distance(r) for r in runs):
        fig = _figure()
        obstacle_distance(fig.axes[0], runs, labels)
        fig.axes[0].set_title(f"Fig. 4: link-obstacle distance, law {law}")
        figs["fig4"] = fig

    if runs[0].q.shape[1] > CASE_STUDY_JOINT:
        used = next((lim for lim in map(_joint_limits, runs) if lim is not None), None)
        upper, d_q = CASE_STUDY_LIMIT, CASE_STUDY_THRESHOLD
        if used is not None and math.isfinite(used[1][CASE_STUDY_JOINT]):
            upper = float(used[1][CASE_STUDY_JOINT])
            d_q = float(used[2][CASE_STUDY_JOINT])
        fig = _figure()
        joint(fig.axes[0], runs, labels, CASE_STUDY_JOINT, limit=(None, upper), threshold=d_q)
        factor, unit = _display(runs[0], CASE_STUDY_JOINT)
        shown = f"{factor * upper:g} {unit}".rstrip()
        fig.axes[0].set_title(f"Fig. 5: joint q3, limit {shown}, law {law}")
        figs["fig5"] = fig

    with_robot = [(label, r) for label, r in zip(labels, runs, strict=True) if r.robot is not None]
    if with_robot:
        cols = min(len(with_robot), 4)
        rows = math.ceil(len(with_robot) / cols)
        fig = _figure(rows, cols, size=(3.2 * cols, 3.4 * rows))
        for ax, (label, r) in zip(fig.axes, with_robot, strict=False):
            planar_stick(ax, r, every=0.25)
            ax.set_title(label, fontsize="medium")
            if ax.get_legend() is not None and ax is not fig.axes[0]:
                ax.get_legend().remove()
        for ax in fig.axes[len(with_robot) :]:
            ax.set_visible(False)
        fig.suptitle(f"The arm every 0.25 s, law {law}")
        figs["stick"] = fig
    return figs


_FILES = {
    "fig3": "fig3_tracking_error",
    "fig4": "fig4_obstacle_distance",
    "fig5": "fig5_q3",
    "stick": "stick",
}


def case_study_figures(results: dict[str, TrackingResult], out: Path) -> list[Path]:
    """Write the paper's Figs. 3-5 and a stick drawing as PNGs, one set per law.

    Runs whose name ends in ``_pinv`` use law (10), the others law (9). Files are
    ``fig3_tracking_error_law9.png``, ``fig4_obstacle_distance_law9.png``,
    ``fig5_q3_law9.png``, ``stick_law9.png`` and the same with ``law10``.

    Args:
        results: Run name -> result (``clik demo`` passes the eight case-study runs).
        out: Folder to write into (created if missing).

    Returns:
        The paths written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    groups = {
        ("9", "law9"): {n: r for n, r in results.items() if not n.endswith("_pinv")},
        ("10", "law10"): {n: r for n, r in results.items() if n.endswith("_pinv")},
    }
    written = []
    for (number, tag), runs in groups.items():
        if not runs:
            continue
        for key, fig in case_study_plots(runs, f"({number})").items():
            path = out / f"{_FILES[key]}_{tag}.png"
            fig.savefig(path)
            written.append(path)
    return written


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
    runs = _as_list(results)
    labels = _labels(runs, names)
    figs: dict[str, Figure] = {}
    fig = _figure()
    tracking_error(fig.axes[0], runs, labels)
    fig.axes[0].set_title("Tracking error norm")
    figs["tracking_error"] = fig
    if any(_has_distance(r) for r in runs):
        fig = _figure()
        obstacle_distance(fig.axes[0], runs, labels)
        fig.axes[0].set_title("Minimum link-obstacle distance")
        figs["obstacle_distance"] = fig
    nq = runs[0].q.shape[1]
    cols = min(nq, 3)
    rows = math.ceil(nq / cols)
    fig = _figure(rows, cols, size=(4.0 * cols, 2.8 * rows))
    for i, ax in enumerate(fig.axes):
        if i >= nq:
            ax.set_visible(False)
            continue
        joint(ax, runs, labels, i)
        if i > 0 and ax.get_legend() is not None:
            ax.get_legend().remove()
    fig.suptitle("Joints")
    figs["joints"] = fig
    return figs


def save_result_plots(
    results: Sequence[TrackingResult], out: Path, names: Sequence[str]
) -> list[Path]:
    """Write :func:`result_plots` as PNGs into ``out`` (``clik solve --plots``).

    Files: ``tracking_error.png``, ``obstacle_distance.png`` (runs with obstacles),
    ``joints.png``.

    Args:
        results: The results (overlaid when several).
        out: Folder to write into (created if missing).
        names: Label of each result.

    Returns:
        The paths written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for key, fig in result_plots(results, names).items():
        path = out / f"{key}.png"
        fig.savefig(path)
        written.append(path)
    return written
