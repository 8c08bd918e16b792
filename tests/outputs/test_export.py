"""``clik solve --export csv json``: trajectories a controller can play, read back and checked.

The files are compared with ``trajectory.npz``; the accelerations with central
differences of the recorded velocities (one-sided at the ends) computed here.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.cli import main
from clik.errors import ExportError, InputError
from clik.outputs.export import check_exportable
from clik.outputs.result import TrackingResult
from clik.scenarios import scenario_path
from tests.limits_check import assert_summary_within_limits
from tests.model.test_joint_kinds import CONTINUOUS_BODY
from tests.urdf_snippets import urdf_text

PANDA = scenario_path("panda_circle")
EXACT = 1e-12
"""Tolerance on times, positions and velocities read back (they are written in full) [SI]."""


def solve(out: Path, *options: str, scenario: Path = PANDA) -> int:
    return main(["solve", str(scenario), "--out", str(out), "--quiet", *options])


def recorded(out: Path) -> dict[str, np.ndarray]:
    with np.load(out / "trajectory.npz") as npz:
        return {k: npz[k] for k in ("t", "q", "qdot")}


def differences(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Central differences inside, one-sided at the ends (a uniform grid or not)."""
    a = np.empty_like(v)
    a[0] = (v[1] - v[0]) / (t[1] - t[0])
    a[-1] = (v[-1] - v[-2]) / (t[-1] - t[-2])
    for k in range(1, len(t) - 1):
        h0, h1 = t[k] - t[k - 1], t[k + 1] - t[k]
        a[k] = (h0**2 * v[k + 1] - h1**2 * v[k - 1] + (h1**2 - h0**2) * v[k]) / (
            h0 * h1 * (h0 + h1)
        )
    return a


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(x) for x in row] for row in rows[1:]])


def read_json(path: Path) -> tuple[list[str], np.ndarray, dict[str, np.ndarray]]:
    data = json.loads(path.read_text())
    points = data["points"]
    times = np.array(
        [p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"] for p in points]
    )
    for p in points:
        assert isinstance(p["time_from_start"]["sec"], int)
        assert 0 <= p["time_from_start"]["nanosec"] < 10**9
    fields = {k: np.array([p[k] for p in points]) for k in ("positions", "velocities")}
    fields["accelerations"] = np.array([p["accelerations"] for p in points])
    return data["joint_names"], times, fields


def columns(table: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """time, positions, velocities, accelerations from CSV rows (3 columns per joint)."""
    body = table[:, 1:].reshape(len(table), n, 3)
    return table[:, 0], body[:, :, 0], body[:, :, 1], body[:, :, 2]


@pytest.fixture(scope="module")
def panda_export(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("export") / "out"
    assert solve(out, "--export", "csv", "json") == 0
    return out


def test_csv_matches_the_npz(panda_export, panda):
    summary = json.loads((panda_export / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert_summary_within_limits(summary, panda)
    rec = recorded(panda_export)
    header, table = read_csv(panda_export / "trajectory.csv")
    names = panda.joint_names
    expected = ["time"] + [
        f"{n}.{k}" for n in names for k in ("position", "velocity", "acceleration")
    ]
    assert header == expected
    t, q, v, a = columns(table, len(names))
    assert len(t) == len(rec["t"]) == 3001
    np.testing.assert_allclose(t, rec["t"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(q, rec["q"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(v, rec["qdot"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(a, differences(rec["t"], rec["qdot"]), rtol=1e-9, atol=1e-9)


def test_json_is_a_joint_trajectory_matching_the_npz(panda_export, panda):
    rec = recorded(panda_export)
    data = json.loads((panda_export / "trajectory.json").read_text())
    assert data["header"]["frame_id"] == ""
    names, times, fields = read_json(panda_export / "trajectory.json")
    assert names == panda.joint_names
    np.testing.assert_allclose(times, rec["t"] - rec["t"][0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fields["positions"], rec["q"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(fields["velocities"], rec["qdot"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(
        fields["accelerations"], differences(rec["t"], rec["qdot"]), rtol=1e-9, atol=1e-9
    )
    assert data["points"][-1]["time_from_start"] == {"sec": 3, "nanosec": 0}


@pytest.mark.parametrize(("every", "count"), [(3, 1001), (7, 430)])
def test_decimation_keeps_every_kth_and_the_last(tmp_path, every, count):
    out = tmp_path / "out"
    assert solve(out, "--export", "csv", "json", "--export-every", str(every)) == 0
    rec = recorded(out)
    keep = list(range(0, len(rec["t"]), every))
    if keep[-1] != len(rec["t"]) - 1:
        keep.append(len(rec["t"]) - 1)  # 3000 = 7 * 428 + 4: the last sample is added
    assert len(keep) == count
    _, table = read_csv(out / "trajectory.csv")
    t, q, v, a = columns(table, rec["qdot"].shape[1])
    np.testing.assert_allclose(t, rec["t"][keep], rtol=0, atol=EXACT)
    np.testing.assert_allclose(q, rec["q"][keep], rtol=0, atol=EXACT)
    np.testing.assert_allclose(v, rec["qdot"][keep], rtol=0, atol=EXACT)
    full = differences(rec["t"], rec["qdot"])  # taken before decimation
    np.testing.assert_allclose(a, full[keep], rtol=1e-9, atol=1e-9)
    _, times, fields = read_json(out / "trajectory.json")
    assert len(times) == count and times[-1] == pytest.approx(3.0, abs=1e-9)
    np.testing.assert_allclose(fields["positions"], rec["q"][keep], rtol=0, atol=EXACT)


WHEEL_SCENARIO = """
name = "wheel arm past 180 degrees"
[robot]
source = "wheel_arm.urdf"
[initial]
q = [175.0, 0.0, 0.05]
unit = "deg"
[task]
frame = "tip"
kind = "position"
axes = ["x", "y"]
[trajectory]
kind = "line"
goal = [{gx}, {gy}, 0.1]
duration = 1.0
[solver]
law = "pseudoinverse"
gain = 100.0
dt = 0.001
"""


def test_a_continuous_joint_is_exported_as_its_unwrapped_angle(tmp_path):
    """j1 (continuous) turns from 175 to about 183 deg: atan2 jumps to -pi, the file does not."""
    (tmp_path / "wheel_arm.urdf").write_text(urdf_text(CONTINUOUS_BODY))
    radius, goal = 0.65, math.radians(185.0)  # the tip: 0.3 + 0.3 + 0.05 m from j1's axis
    scenario = tmp_path / "wheel.toml"
    scenario.write_text(
        WHEEL_SCENARIO.format(gx=radius * math.cos(goal), gy=radius * math.sin(goal))
    )
    out = tmp_path / "out"
    assert solve(out, "--export", "csv", "json", scenario=scenario) == 0
    summary = json.loads((out / "summary.json").read_text())
    robot = clik.Robot.load(tmp_path / "wheel_arm.urdf")
    assert summary["status"] == "completed"
    assert_summary_within_limits(summary, robot)
    rec = recorded(out)
    header, table = read_csv(out / "trajectory.csv")
    assert header[1:4] == ["j1.position", "j1.velocity", "j1.acceleration"]
    t, q, v, a = columns(table, 3)
    wrapped = np.arctan2(rec["q"][:, 1], rec["q"][:, 0])
    assert wrapped.min() < -3.0 and wrapped.max() > 3.0  # atan2 alone would jump
    angle = q[:, 0]
    assert angle[0] == pytest.approx(math.radians(175.0), abs=1e-12)
    assert angle.max() > math.pi and np.abs(np.diff(angle)).max() < 0.01
    np.testing.assert_allclose(np.cos(angle), rec["q"][:, 0], atol=EXACT)
    np.testing.assert_allclose(np.sin(angle), rec["q"][:, 1], atol=EXACT)
    np.testing.assert_allclose(q[:, 1:], rec["q"][:, 2:], rtol=0, atol=EXACT)
    np.testing.assert_allclose(t, rec["t"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(v, rec["qdot"], rtol=0, atol=EXACT)
    np.testing.assert_allclose(a, differences(rec["t"], rec["qdot"]), rtol=1e-9, atol=1e-9)
    names, _, fields = read_json(out / "trajectory.json")
    assert names == ["j1", "j2", "j3"]
    np.testing.assert_allclose(fields["positions"], q, rtol=0, atol=EXACT)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--export", "csv", "--export-every", "0"], "--export-every: expected an integer >= 1"),
        (["--export", "csv", "--export-every", "-2"], "--export-every: expected an integer >= 1"),
        (["--export", "csv", "--export-every", "1.5"], "--export-every: expected an integer"),
        (["--export", "csv", "--export-every", "x"], "--export-every: expected an integer"),
        (["--export", "xml"], "--export: invalid choice: 'xml'"),
        (["--export"], "--export: expected at least one argument"),
    ],
)
def test_bad_export_options_are_refused_before_anything_is_written(
    tmp_path, capsys, options, message
):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as info:
        solve(out, *options)
    assert info.value.code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_export_every_without_export_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert solve(out, "--force", "--export-every", "2") == 2
    assert "clik: error: --export-every: expected to be given with --export" in (
        capsys.readouterr().err
    )
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


def test_a_joint_with_several_velocities_is_refused():
    model = pin.Model()
    model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "base")
    with pytest.raises(ExportError, match=r"joint 'base' \(JointModelFreeFlyer, nq 7, nv 6\)"):
        check_exportable(model)


def test_python_api_export(tmp_path, panda_export, panda):
    loaded = TrackingResult.load(panda_export / "trajectory.npz")
    with pytest.raises(InputError, match="robot: expected the run's robot"):
        loaded.export(tmp_path / "a")
    written = loaded.export(tmp_path / "a", formats="csv", every=1000, robot=panda)
    assert list(written) == ["csv"] and written["csv"] == tmp_path / "a" / "trajectory.csv"
    _, table = read_csv(written["csv"])
    np.testing.assert_allclose(table[:, 0], [0.0, 1.0, 2.0, 3.0], atol=EXACT)
    same = (panda_export / "trajectory.csv").read_text().splitlines()
    assert written["csv"].read_text().splitlines() == [same[i] for i in (0, 1, 1001, 2001, 3001)]
    for bad in (0, -1, 1.5, True):
        with pytest.raises(InputError, match="every: expected an integer >= 1"):
            loaded.export(tmp_path / "b", every=bad, robot=panda)
    with pytest.raises(InputError, match="formats: expected one or more of 'csv', 'json'"):
        loaded.export(tmp_path / "b", formats=("xml",), robot=panda)
    assert not (tmp_path / "b").exists()
