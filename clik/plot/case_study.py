"""The paper's case-study figures: Figs. 3-5 and a stick drawing per law, as PNGs (``clik demo``).

The case study is the planar 4R arm of ``clik.scenarios.CASE_STUDY``; its joint
``q_3`` has the limit and threshold below.
"""

from __future__ import annotations

import math
from pathlib import Path

from matplotlib.figure import Figure

from clik.outputs.result import TrackingResult
from clik.plot._common import (
    display,
    drop_legend,
    first_joint_limits,
    min_distance,
    new_figure,
    save_figures,
)
from clik.plot.series import joint, obstacle_distance, tracking_error
from clik.plot.stick import planar_stick

CASE_STUDY_JOINT = 2
"""Index of ``q_3`` in the case study's joint vector."""
CASE_STUDY_LIMIT = math.radians(-80.0)
"""The case study's joint limit ``q_3 <= -80 deg`` [rad] (used when a run does not record it)."""
CASE_STUDY_THRESHOLD = math.radians(2.0)
"""The case study's joint-range threshold ``d_q = 2 deg`` [rad]."""

STICK_EVERY = 0.25
"""Time between two drawings of the arm in the stick figure [s]."""

FILES = {
    "fig3": "fig3_tracking_error",
    "fig4": "fig4_obstacle_distance",
    "fig5": "fig5_q3",
    "stick": "stick",
}
"""Figure key of :func:`case_study_plots` -> file name stem (the law's tag follows)."""

_RUN_LABELS = {
    "unconstrained": "1 unconstrained",
    "obstacle": "2 obstacle",
    "joint_limit": "3 joint limit",
    "both": "4 both",
}


def _run_label(name: str) -> str:
    """``case_study_obstacle_pinv`` -> ``2 obstacle``; other names unchanged."""
    label = name.removeprefix("case_study_").removesuffix("_pinv")
    return _RUN_LABELS.get(label, label)


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

    fig = new_figure()
    tracking_error(fig.axes[0], runs, labels)
    fig.axes[0].set_title(f"Fig. 3: tracking error norm, law {law}")
    figs["fig3"] = fig

    if any(min_distance(r) is not None for r in runs):
        fig = new_figure()
        obstacle_distance(fig.axes[0], runs, labels)
        fig.axes[0].set_title(f"Fig. 4: link-obstacle distance, law {law}")
        figs["fig4"] = fig

    if runs[0].q.shape[1] > CASE_STUDY_JOINT:
        figs["fig5"] = _fig5(runs, labels, law)

    with_robot = [(label, r) for label, r in zip(labels, runs, strict=True) if r.robot is not None]
    if with_robot:
        figs["stick"] = _stick_figure(with_robot, law)
    return figs


def _fig5(runs: list[TrackingResult], labels: list[str], law: str) -> Figure:
    """Fig. 5: joint ``q_3`` with the runs' own limit and threshold, or the case study's."""
    used = first_joint_limits(runs)
    upper, d_q = CASE_STUDY_LIMIT, CASE_STUDY_THRESHOLD
    if used is not None and math.isfinite(used[1][CASE_STUDY_JOINT]):
        upper = float(used[1][CASE_STUDY_JOINT])
        d_q = float(used[2][CASE_STUDY_JOINT])
    fig = new_figure()
    joint(fig.axes[0], runs, labels, CASE_STUDY_JOINT, limit=(None, upper), threshold=d_q)
    factor, unit = display(runs[0], CASE_STUDY_JOINT)
    shown = f"{factor * upper:g} {unit}".rstrip()
    fig.axes[0].set_title(f"Fig. 5: joint q3, limit {shown}, law {law}")
    return fig


def _stick_figure(with_robot: list[tuple[str, TrackingResult]], law: str) -> Figure:
    """One stick drawing per (label, run), at most four per row; one legend (the first)."""
    cols = min(len(with_robot), 4)
    rows = math.ceil(len(with_robot) / cols)
    fig = new_figure(rows, cols, size=(3.2 * cols, 3.4 * rows))
    for ax, (label, r) in zip(fig.axes, with_robot, strict=False):
        planar_stick(ax, r, every=STICK_EVERY)
        ax.set_title(label, fontsize="medium")
        if ax is not fig.axes[0]:
            drop_legend(ax)
    for ax in fig.axes[len(with_robot) :]:
        ax.set_visible(False)
    fig.suptitle(f"The arm every {STICK_EVERY:g} s, law {law}")
    return fig


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
    groups = {
        ("9", "law9"): {n: r for n, r in results.items() if not n.endswith("_pinv")},
        ("10", "law10"): {n: r for n, r in results.items() if n.endswith("_pinv")},
    }
    written: list[Path] = []
    for (number, tag), runs in groups.items():
        if runs:
            figs = case_study_plots(runs, f"({number})")
            named = [(f"{FILES[key]}_{tag}.png", fig) for key, fig in figs.items()]
            written += save_figures(named, out)
    if not written:
        Path(out).mkdir(parents=True, exist_ok=True)
    return written
