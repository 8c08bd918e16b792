"""Scenario files and the command line: contracts of `clik solve`, `clik demo`, `clik robots`."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import clik
from clik import ScenarioError
from clik.cli import main
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario
from tests.limits_check import assert_summary_within_limits, assert_within_limits

CASE = scenario_path("case_study_unconstrained").read_text()


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_solve_writes_summary_matching_the_api(tmp_path):
    scenario = scenario_path("panda_circle")
    out = tmp_path / "out"
    assert main(["solve", str(scenario), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    api = build(scenario).execute()
    assert summary["status"] == api.status == "completed"
    assert_summary_within_limits(summary, api.robot)
    assert_within_limits(api, api.robot)
    assert summary["steps"] == api.steps == 3001
    assert summary["max_task_error"] == pytest.approx(api.max_task_error, rel=1e-9)
    assert summary["final_task_error"] == pytest.approx(api.final_task_error, rel=1e-9)
    np.testing.assert_allclose(summary["joint_min"], api.joint_min)
    np.testing.assert_allclose(summary["joint_max"], api.joint_max)
    assert summary["events"] == []
    assert summary["max_task_error"] < 1e-3
    with np.load(out / "trajectory.npz") as npz:
        for key in ("t", "q", "qdot", "qddot", "task_error_norm"):
            assert key in npz.files
        np.testing.assert_allclose(npz["q"], api.q)


def test_existing_output_needs_force(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    scenario = write(tmp_path, CASE)
    assert main(["solve", str(scenario), "--out", str(out), "--quiet"]) == 2
    assert "exists already; pass --force" in capsys.readouterr().err
    assert not (out / "summary.json").exists()
    assert main(["solve", str(scenario), "--out", str(out), "--quiet", "--force"]) == 0
    # --force replaces the folder whole: no file of the earlier contents stays
    assert (out / "summary.json").exists() and not (out / "keep.txt").exists()


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("duration = 3.0", "duration = -3.0", "trajectory.duration", "expected a number > 0 [s]"),
        ("duration = 3.0", 'duration = "3"', "trajectory.duration", "expected a number > 0 [s]"),
        ('kind = "line"', 'kind = "spiral"', "trajectory.kind", "expected one of 'line'"),
        ("dt = 0.001", "dt = 0.001\nsubsteps = 3", "solver.substeps", "unknown key; valid keys"),
        ('frame = "tip"\n', "", "task.frame", "required key is missing"),
        (
            "goal = [0.8, -0.2, 0.0]",
            "goal = [0.8, -0.2]",
            "trajectory.goal",
            "expected a list of 3 numbers [m]",
        ),
        ('law = "transpose"', 'law = "jacobian"', "solver.law", "expected one of 'transpose'"),
        ("gain = 1000.0", "gain = 0", "solver.gain", "expected a number > 0 [1/s]"),
        ('unit = "deg"', 'unit = "grad"', "initial.unit", "expected one of 'rad', 'deg'"),
        ("radius = 0.0", "radius = -1.0", "obstacles[0].radius", "expected a number >= 0 [m]"),
        (
            "threshold = 0.03",
            "threshold = 0.0",
            "constraints.obstacles.threshold",
            "expected a number > 0 [m]",
        ),
        (
            "enabled = false\nthreshold = 2.0",
            "enabled = 1\nthreshold = 2.0",
            "constraints.joint_limits.enabled",
            "expected true or false",
        ),
    ],
)
def test_scenario_errors_name_file_and_key(tmp_path, old, new, key, expected):
    assert old in CASE
    path = write(tmp_path, CASE.replace(old, new, 1))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    message = str(info.value)
    assert str(path) in message and f": {key}: " in message and expected in message


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ('frame = "tip"', 'frame = "hand"', "task.frame", "available frames: "),
        ('source = "planar4r"', 'source = "planar5r"', "robot.source", "available robot names"),
        (
            "upper = -80.0",
            "upper = -80.0\n[constraints.joint_limits.override.joint9]\nlower = 0",
            "constraints.joint_limits.override",
            "joint 'joint9' not found",
        ),
        ("cruise_speed = 0.12", "cruise_speed = 0.01", "trajectory.cruise_speed", "expected"),
        (
            "q = [180, -30, -90, -30]",
            "q = [180, -30, -90]",
            "initial.q",
            "expected an array of 4 finite joint values",
        ),
    ],
)
def test_build_errors_name_file_and_key(tmp_path, old, new, key, expected):
    assert old in CASE
    path = write(tmp_path, CASE.replace(old, new, 1))
    with pytest.raises(ScenarioError) as info:
        build(path)
    message = str(info.value)
    assert str(path) in message and f": {key}: " in message and expected in message


def test_relative_urdf_path_resolves_against_scenario_folder(tmp_path):
    from clik.model.planar_arm import write_planar_arm

    (tmp_path / "models").mkdir()
    write_planar_arm(tmp_path / "models" / "arm.urdf", [0.3, 0.3, 0.3, 0.3])
    text = CASE.replace('source = "planar4r"', 'source = "models/arm.urdf"')
    run = build(write(tmp_path, text))
    assert run.robot.nq == 4 and run.robot.source_path == tmp_path / "models" / "arm.urdf"


def test_robots_lists_ours_and_example_robot_data(capsys):
    assert main(["robots"]) == 0
    listing = capsys.readouterr().out
    assert "planar4r" in listing and "panda" in listing and "ur5" in listing


def test_cli_prints_errors_without_traceback(tmp_path):
    path = write(tmp_path, CASE.replace("dt = 0.001", "dt = -1"))
    proc = subprocess.run(
        [sys.executable, "-m", "clik.cli", "solve", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert "solver.dt: expected a number > 0 [s]" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_demo_runs_the_case_study(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "case_study_unconstrained" in table and "max err [m]" in table
    for name in ("case_study_unconstrained", "case_study_both_pinv"):
        summary = json.loads((out / name / "summary.json").read_text())
        assert summary["status"] == "completed"
        assert_summary_within_limits(summary, clik.Robot.load("planar4r"))
        assert (out / name / "trajectory.npz").is_file()
    unconstrained = json.loads((out / "case_study_unconstrained" / "summary.json").read_text())
    assert unconstrained["max_task_error"] < 1e-3
    assert len(list(out.glob("case_study_*.html"))) == 8
    for law in ("law9", "law10"):
        for fig in ("fig3_tracking_error", "fig4_obstacle_distance", "fig5_q3"):
            assert (out / f"{fig}_{law}.png").stat().st_size > 10_000


def test_demo_no_html_no_plots_writes_neither(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--no-html", "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert "HTML scenes" not in printed and "wrote figures" not in printed
    summaries = sorted(p.parent.name for p in out.glob("*/summary.json"))
    assert len(summaries) == 8 and "case_study_both_pinv" in summaries
    assert list(out.rglob("*.html")) == []
    assert list(out.rglob("*.png")) == []
    assert (out / "table.txt").is_file()


def test_demo_plots_and_no_plots_exclude_each_other(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["demo", "--out", str(tmp_path / "demo"), "--plots", "--no-plots"])
    assert info.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err
    assert not (tmp_path / "demo").exists()


def test_solve_html_and_plots(tmp_path):
    out = tmp_path / "o"
    scenario = str(scenario_path("case_study_both"))
    assert main(["solve", scenario, "--out", str(out), "--html", "--plots", "--quiet"]) == 0
    html = (out / "scene.html").read_text()
    assert html.startswith("<!DOCTYPE html>") and len(html) < 5_000_000
    assert (out / "tracking_error.png").is_file() and (out / "obstacle_distance.png").is_file()


def test_show_serves_on_loopback(capsys):
    from clik.viz import stop_server

    try:
        assert main(["show", str(scenario_path("case_study_both")), "--no-block"]) == 0
        assert "http://127.0.0.1:" in capsys.readouterr().out
    finally:
        stop_server()
