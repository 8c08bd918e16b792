"""clik.plot: the paper's Figs. 3-5, stick drawings, and the PNGs of ``clik demo``/``clik solve``.

Plots are checked on their Figure objects (lines, their data, threshold and
limit values, labels) and on the PNG files (size in pixels).
"""

from __future__ import annotations

import math
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

import clik
from clik import plot
from clik.errors import InputError
from clik.outputs.result import TrackingResult
from clik.scenarios import CASE_STUDY, scenario_path
from clik.scenarios.runner import build

LAW9 = [n for n in CASE_STUDY if not n.endswith("_pinv")]
LAW10 = [n for n in CASE_STUDY if n.endswith("_pinv")]
PNG_SIZE = (840, 480)  # FIGSIZE (7 x 4 in) at 120 dpi [pixels]
THRESHOLD_D_O = 0.03  # [m]
Q3_LIMIT_DEG, Q3_THRESHOLD_DEG = -80.0, -82.0


@pytest.fixture(scope="module")
def case_study() -> dict[str, TrackingResult]:
    """The eight shipped case-study runs (laws (9) and (10)), about 2 s."""
    return {name: build(scenario_path(name)).execute() for name in CASE_STUDY}


@pytest.fixture(scope="module")
def plain(planar4r) -> TrackingResult:
    """The case-study line without constraints (no obstacle recorded)."""
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    line = clik.trajectory.Line(task.placement(q0).translation, [0.8, -0.2, 0.0], 3.0, 0.12)
    return clik.track(task, line, q0=q0, law="transpose", gain=1000.0, dt=1e-3)


def new_axes():
    return Figure().subplots()


def lines(ax, gid: str | None = None) -> list:
    """The axes' lines with this gid (None: the data lines, which have no gid)."""
    return [
        line
        for line in ax.lines
        if line.get_gid() == gid and line.get_label() not in ("activate", "release", "skipped")
    ]


def png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    return struct.unpack(">II", data[16:24])


# ------------------------------------------------------------------ tracking error


def test_tracking_error_overlays_one_line_per_run(case_study):
    runs = [case_study[n] for n in LAW9]
    ax = plot.tracking_error(new_axes(), runs, ["a", "b", "c", "d"])
    data = lines(ax)
    assert [line.get_label() for line in data] == ["a", "b", "c", "d"]
    for line, run in zip(data, runs, strict=True):
        np.testing.assert_array_equal(line.get_xdata(), run.t)
        # Zero errors (t = 0) cannot be drawn on a log axis: they are left out (NaN).
        expected = np.where(run.task_error_norm > 0, run.task_error_norm, np.nan)
        np.testing.assert_allclose(line.get_ydata(), expected)
    assert ax.get_yscale() == "log"
    assert ax.get_xlabel() == "t [s]" and "[m]" in ax.get_ylabel()


def test_events_are_vertical_lines_at_their_times(case_study):
    run = case_study["case_study_both"]
    ax = plot.tracking_error(new_axes(), run, ["both"])
    events = lines(ax, "event")
    assert len(events) == len(run.events) == 3
    assert sorted(line.get_xdata()[0] for line in events) == sorted(e["t"] for e in run.events)
    styles = {e["action"]: line.get_linestyle() for e, line in zip(run.events, events, strict=True)}
    assert styles == {"activate": "-", "release": "--"}
    assert not lines(plot.tracking_error(new_axes(), run, ["both"], events=False), "event")


def test_labels_must_match_the_results(case_study):
    with pytest.raises(InputError, match="labels"):
        plot.tracking_error(new_axes(), [case_study["case_study_both"]], ["a", "b"])
    with pytest.raises(InputError, match="results"):
        plot.tracking_error(new_axes(), [], None)


# ------------------------------------------------------------------ obstacle distance


def test_obstacle_distance_draws_the_threshold(case_study):
    runs = [case_study[n] for n in LAW9]
    ax = plot.obstacle_distance(new_axes(), runs, LAW9)
    assert len(lines(ax)) == 4
    (threshold,) = lines(ax, "threshold")
    np.testing.assert_allclose(threshold.get_ydata(), [THRESHOLD_D_O, THRESHOLD_D_O])
    assert "0.03" in threshold.get_label()
    np.testing.assert_allclose(lines(ax)[1].get_ydata(), runs[1].min_obstacle_distance)
    # Only obstacle events (activations): run 4's joint-limit events are not drawn here,
    # and the legend has no "release" entry.
    assert [t.get_text() for t in ax.get_legend().get_texts()][-1] == "activate"
    assert len(lines(ax, "event")) == sum(
        e["constraint"].startswith("obstacle:") for r in runs for e in r.events
    )


def test_obstacle_distance_threshold_given_and_by_obstacle(case_study):
    run = case_study["case_study_obstacle"]
    ax = plot.obstacle_distance(new_axes(), run, ["obstacle"], threshold=0.05, by_obstacle=True)
    (threshold,) = lines(ax, "threshold")
    np.testing.assert_allclose(threshold.get_ydata(), [0.05, 0.05])
    (per_obstacle,) = lines(ax)
    assert per_obstacle.get_label() == "pin"
    np.testing.assert_allclose(per_obstacle.get_ydata(), run.extra["obstacle_distance"][:, 0])


def test_obstacle_distance_needs_obstacles(plain):
    with pytest.raises(InputError, match="obstacles"):
        plot.obstacle_distance(new_axes(), plain, ["plain"])


# ------------------------------------------------------------------ joints


def test_joint_in_degrees_with_limit_and_threshold_band(case_study):
    runs = [case_study[n] for n in LAW9]
    ax = plot.joint(
        new_axes(),
        runs,
        LAW9,
        joint_index=2,
        limit=math.radians(-80.0),
        threshold=math.radians(2.0),
    )
    for line, run in zip(lines(ax), runs, strict=True):
        np.testing.assert_allclose(line.get_ydata(), np.degrees(run.q[:, 2]))
    (limit,) = lines(ax, "limit")
    (threshold,) = lines(ax, "threshold")
    np.testing.assert_allclose(limit.get_ydata(), [Q3_LIMIT_DEG] * 2)
    np.testing.assert_allclose(threshold.get_ydata(), [Q3_THRESHOLD_DEG] * 2)
    assert "upper" in limit.get_label()
    (band,) = [p for p in ax.patches if p.get_gid() == "threshold_band"]
    y = band.get_path().transformed(band.get_patch_transform()).vertices[:, 1]
    np.testing.assert_allclose([y.min(), y.max()], [Q3_THRESHOLD_DEG, Q3_LIMIT_DEG], atol=1e-9)
    assert ax.get_ylabel() == "q3 (joint3) [deg]"
    # Events: the joint3 row of run 3 and run 4 (activate, and release in run 4).
    assert len(lines(ax, "event")) == 3


def test_joint_limits_default_to_the_runs_own(case_study):
    ax = plot.joint(new_axes(), case_study["case_study_joint_limit"], ["3"], joint_index=2)
    (limit,) = lines(ax, "limit")
    (threshold,) = lines(ax, "threshold")
    np.testing.assert_allclose(limit.get_ydata(), [Q3_LIMIT_DEG] * 2)
    np.testing.assert_allclose(threshold.get_ydata(), [Q3_THRESHOLD_DEG] * 2)
    # Joint 1's limits (+-360 deg) are far from its data: not drawn.
    ax = plot.joint(new_axes(), case_study["case_study_joint_limit"], ["3"], joint_index=0)
    assert not lines(ax, "limit")


def test_joint_without_joint_rows_draws_no_limit(plain):
    ax = plot.joint(new_axes(), plain, ["plain"], joint_index=2)
    assert not lines(ax, "limit") and not lines(ax, "threshold")
    with pytest.raises(InputError, match="joint_index"):
        plot.joint(new_axes(), plain, ["plain"], joint_index=4)


def test_joint_single_limit_side_follows_the_start(plain):
    # q3 starts at -90 deg: a limit above it is an upper limit, one below a lower limit.
    ax = plot.joint(
        new_axes(), plain, ["p"], 2, limit=math.radians(-80.0), threshold=math.radians(2.0)
    )
    assert lines(ax, "limit")[0].get_label().startswith("upper")
    ax = plot.joint(
        new_axes(), plain, ["p"], 2, limit=math.radians(-100.0), threshold=math.radians(2.0)
    )
    assert lines(ax, "limit")[0].get_label().startswith("lower")
    np.testing.assert_allclose(lines(ax, "threshold")[0].get_ydata(), [-98.0, -98.0])


# ------------------------------------------------------------------ stick drawing


def test_planar_stick_draws_the_arm_and_the_obstacle(case_study):
    run = case_study["case_study_both"]
    ax = plot.planar_stick(new_axes(), run, every=0.25)
    sticks = lines(ax, "stick")
    assert len(sticks) == 13  # t = 0, 0.25, ..., 2.75 and the last sample (3 s)
    first = sticks[0]
    np.testing.assert_allclose(first.get_xydata()[0], [0.0, 0.0], atol=1e-12)  # the base
    np.testing.assert_allclose(first.get_xydata()[-1], run.position[0, :2])  # the tip
    assert len(first.get_xydata()) == 5  # 4 joints and the tip
    obstacle = [p for p in ax.patches if p.get_gid() == "obstacle"]
    (shell,) = [p for p in ax.patches if p.get_gid() == "threshold"]
    assert len(obstacle) == 1
    np.testing.assert_allclose(shell.center, [0.7, -0.28])
    assert shell.radius == pytest.approx(THRESHOLD_D_O)
    assert len(lines(ax, "reference")) == 1 and len(lines(ax, "path")) == 1


def test_planar_stick_needs_the_robot(case_study, tmp_path):
    loaded = TrackingResult.load(case_study["case_study_both"].save(tmp_path / "run.npz"))
    with pytest.raises(InputError, match="robot"):
        plot.planar_stick(new_axes(), loaded)
    with pytest.raises(InputError, match="every"):
        plot.planar_stick(new_axes(), case_study["case_study_both"], every=0.0)


# ------------------------------------------------------------------ files


def test_case_study_plots_titles_and_content(case_study):
    figs = plot.case_study_plots({n: case_study[n] for n in LAW9}, "(9)")
    assert set(figs) == {"fig3", "fig4", "fig5", "stick"}
    titles = {k: f.axes[0].get_title() for k, f in figs.items() if k != "stick"}
    assert titles == {
        "fig3": "Fig. 3: tracking error norm, law (9)",
        "fig4": "Fig. 4: link-obstacle distance, law (9)",
        "fig5": "Fig. 5: joint q3, limit -80 deg, law (9)",
    }
    labels = [line.get_label() for line in lines(figs["fig3"].axes[0])]
    assert labels == ["1 unconstrained", "2 obstacle", "3 joint limit", "4 both"]
    np.testing.assert_allclose(
        lines(figs["fig4"].axes[0], "threshold")[0].get_ydata()[0], THRESHOLD_D_O
    )
    np.testing.assert_allclose(
        lines(figs["fig5"].axes[0], "threshold")[0].get_ydata()[0], Q3_THRESHOLD_DEG
    )
    assert len(figs["stick"].axes) == 4


def test_case_study_figures_writes_one_set_per_law(case_study, tmp_path):
    written = plot.case_study_figures(dict(case_study), tmp_path / "out")
    names = sorted(p.name for p in written)
    expected = sorted(
        f"{stem}_{law}.png"
        for law in ("law9", "law10")
        for stem in ("fig3_tracking_error", "fig4_obstacle_distance", "fig5_q3", "stick")
    )
    assert names == expected
    for path in written:
        assert path.is_file() and path.parent == tmp_path / "out"
        if not path.name.startswith("stick"):
            assert png_size(path) == PNG_SIZE


def test_save_result_plots(case_study, plain, tmp_path):
    written = plot.save_result_plots([case_study["case_study_both"]], tmp_path, ["both"])
    assert [p.name for p in written] == [
        "tracking_error.png",
        "obstacle_distance.png",
        "joints.png",
    ]
    assert png_size(written[0]) == PNG_SIZE
    written = plot.save_result_plots([plain, plain], tmp_path / "two", ["a", "b"])
    assert [p.name for p in written] == ["tracking_error.png", "joints.png"]  # no obstacles
    figs = plot.result_plots([plain, plain], ["a", "b"])
    assert len(lines(figs["tracking_error"].axes[0])) == 2
    joints = [ax for ax in figs["joints"].axes if ax.get_visible()]
    assert len(joints) == 4 and all(len(lines(ax)) == 2 for ax in joints)


# ------------------------------------------------------------------ import side effects


@pytest.mark.parametrize("how", ["MPLBACKEND", "matplotlib.use"])
def test_import_keeps_the_backend(how):
    # A fresh interpreter without a display: importing clik.plot neither switches the
    # backend chosen by the user (here "svg") nor imports pyplot.
    env = {k: v for k, v in os.environ.items() if k not in ("MPLBACKEND", "DISPLAY")}
    env.pop("WAYLAND_DISPLAY", None)
    if how == "MPLBACKEND":
        env["MPLBACKEND"] = "svg"
        choose = ""
    else:
        choose = "matplotlib.use('svg'); "
    code = (
        f"import sys, matplotlib; {choose}"
        "import clik.plot; "
        "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["svg", "False"]
