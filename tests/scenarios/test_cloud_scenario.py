"""``[[obstacles]]`` with ``shape = "cloud"``: read, built, run by both engines and the CLI.

The Panda's hand follows a line above a crate given as points (a box's surface); the
crate's rows hold the fingers at the threshold.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.cli import main
from clik.clouds.cloud_obstacle import CloudObstacle
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.errors import ScenarioError
from clik.model.robot import PANDA_FINGERS
from clik.outputs.result import TrackingResult
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario
from tests.clouds.test_self_filter import link_points

CRATE_CENTRE = (0.307, 0.15, 0.40)
"""Where the crate's frame is [m]: below the middle of the hand's line."""
CRATE_SIZE = 0.1
"""The crate's side [m]."""
THRESHOLD = 0.03
"""The obstacles' ``d_o`` [m]."""
SAME = 1e-9
"""How close both engines' distances are [m]."""

SCENARIO = """\
name = "Panda past a scanned crate"

[robot]
source = "panda"
lock = {{ panda_finger_joint1 = 0.0, panda_finger_joint2 = 0.0 }}

[task]
frame = "panda_hand"
kind = "position"

[trajectory]
kind = "line"
goal = [0.307, 0.3, 0.59]
duration = 1.0

[solver]
law = "pseudoinverse"
gain = 100.0
engine = "{engine}"

[[obstacles]]
name = "crate"
shape = "cloud"
file = "{file}"
position = [0.307, 0.15, 0.40]
{extra}
[constraints.obstacles]
enabled = true
threshold = 0.03
"""


def box_surface(n: int, size: float = CRATE_SIZE, seed: int = 0) -> np.ndarray:
    """``n`` points on the faces of a cube of side ``size`` centred at the origin [m]."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-0.5 * size, 0.5 * size, (n, 3))
    axis = rng.integers(0, 3, n)
    points[np.arange(n), axis] = 0.5 * size * rng.choice([-1.0, 1.0], n)
    return points


def write_ply(path: Path, points: np.ndarray) -> Path:
    """An ASCII PLY file of ``points`` (its ``vertex`` element's x, y, z)."""
    head = f"ply\nformat ascii 1.0\nelement vertex {len(points)}\n"
    head += "property double x\nproperty double y\nproperty double z\nend_header\n"
    path.write_text(head + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points.tolist()))
    return path


def write_scenario(folder: Path, file: str, engine: str = "compiled", extra: str = "") -> Path:
    """The crate scenario in ``folder`` (``file`` relative to it), with ``extra`` cloud keys."""
    path = folder / f"crate_{engine}.toml"
    path.write_text(SCENARIO.format(engine=engine, file=file, extra=extra), encoding="utf-8")
    return path


def run(path: Path) -> TrackingResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ClikWarning)  # joint speeds: not what this tests
        return build(path).execute()


def cloud_kind(path: Path) -> CloudAvoidance:
    """The one cloud kind of the scenario's constraint set, built (not run)."""
    cset = build(path).tracker.constraints
    assert cset is not None
    (kind,) = [k for k in cset.kinds if isinstance(k, CloudAvoidance)]
    return kind


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("crate")
    np.save(out / "crate.npy", box_surface(3000))
    return out


@pytest.fixture(scope="module")
def results(folder: Path) -> dict[str, TrackingResult]:
    return {e: run(write_scenario(folder, "crate.npy", e)) for e in ("python", "compiled")}


def test_both_engines_hold_the_fingers_at_the_crate_alike(results):
    python, compiled = results["python"], results["compiled"]
    assert python.status == compiled.status == "completed"
    d_py, d_cc = (r.summary()["min_cloud_distance"] for r in (python, compiled))
    assert THRESHOLD - 1e-3 < d_py < THRESHOLD + 0.01  # the line passes near: held at d_o
    assert abs(d_py - d_cc) <= SAME
    assert any(e["constraint"].startswith("cloud:crate:") for e in python.events)
    assert python.events == compiled.events
    np.testing.assert_allclose(
        python.extra["cloud_distance"], compiled.extra["cloud_distance"], atol=SAME
    )


def test_the_run_lists_the_cloud_read_from_the_file(results, folder):
    (info,) = results["compiled"].info["clouds"]
    assert info["name"] == "crate" and info["shape"] == "cloud"
    assert info["points"] == 3000 and info["removed"] == 0  # nothing of the crate is on the arm
    assert info["source"] == str(folder / "crate.npy")
    np.testing.assert_allclose(info["position"], CRATE_CENTRE)
    assert info["threshold"] == THRESHOLD and info["voxel"] == 0.01


def test_a_ply_file_gives_the_cloud_an_npy_file_gives(folder):
    points = box_surface(3000)
    write_ply(folder / "crate.ply", points)
    kinds = [cloud_kind(write_scenario(folder, name)) for name in ("crate.npy", "crate.ply")]
    np.testing.assert_allclose(kinds[0].clouds[0].world, kinds[1].clouds[0].world, atol=1e-12)
    assert kinds[1].threshold == THRESHOLD and kinds[1].rows


def test_clik_solve_writes_and_prints_the_cloud(folder, tmp_path, capsys):
    scenario = write_scenario(folder, "crate.npy")
    assert main(["solve", str(scenario), "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    nearest = summary["min_cloud_distance"]
    assert summary["min_cloud_distance_by_cloud"] == {"crate": nearest}
    assert summary["min_obstacle_distance_by_obstacle"]["crate"] == nearest
    assert summary["info"]["clouds"][0]["spheres"] > 0
    assert f"min link-obstacle distance {nearest:.4f} m (clouds: crate {nearest:.4f} m)" in printed


def test_a_cloud_out_of_reach_is_said_to_be_farther(folder, tmp_path, capsys):
    scenario = write_scenario(folder, "crate.npy")
    text = scenario.read_text().replace("[0.307, 0.15, 0.40]", "[0.307, 0.15, -0.5]")
    scenario.write_text(text)
    assert main(["solve", str(scenario), "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["min_cloud_distance"] is None  # no link within reach: no exact distance
    assert "min link-obstacle distance > 0.0500 m (clouds: crate > 0.0500 m)" in (
        capsys.readouterr().out
    )


@pytest.mark.parametrize(
    ("extra", "key", "words"),
    [
        ("voxl = 0.02", "obstacles[0].voxl", "did you mean `voxel`"),
        ("voxel = -0.01", "obstacles[0].voxel", "a number >= 0 [m]"),
        ("self_filter = 1", "obstacles[0].self_filter", "true or false"),
        ("self_padding = -1.0", "obstacles[0].self_padding", "a number >= 0 [m]"),
        ("self_filter = false\nself_padding = 0.02", "obstacles[0].self_padding", "no self_pad"),
        ("velocity = [0.1, 0.0, 0.0]", "obstacles[0].velocity", "no velocity for a cloud"),
        ("threshold = 0.0", "obstacles[0].threshold", "a number > 0 [m]"),
        ("rpy = [0.0, 0.0]", "obstacles[0].rpy", "a list of 3 numbers"),
    ],
)
def test_a_bad_cloud_key_is_named(folder, extra, key, words):
    with pytest.raises(ScenarioError) as caught:
        load_scenario(write_scenario(folder, "crate.npy", extra=extra))
    assert caught.value.key == key
    assert words in str(caught.value)


@pytest.mark.parametrize("file", ["crate.stl", "https://example.org/crate.npy", "crate"])
def test_a_file_that_is_no_cloud_is_refused_before_reading(folder, file):
    with pytest.raises(ScenarioError, match=r"expected a point cloud file ending \.npy") as caught:
        load_scenario(write_scenario(folder, file))
    assert caught.value.key == "obstacles[0].file"


def test_a_missing_cloud_file_names_the_key_and_the_file(folder):
    scenario = load_scenario(write_scenario(folder, "scans/missing.npy"))  # read: not yet
    assert scenario.obstacles[0]["file"] == str(folder / "scans" / "missing.npy")
    with pytest.raises(ScenarioError) as caught:
        build(scenario)
    assert caught.value.key == "obstacles[0].file"
    assert str(folder / "scans" / "missing.npy") in str(caught.value)
    assert "an existing point cloud file" in str(caught.value)


@pytest.mark.parametrize("self_filter", [True, False])
def test_the_self_filter_removes_the_arms_points(folder, self_filter):
    robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
    on_arm = (
        link_points(robot, robot.q_reference, per_shape=20) - CRATE_CENTRE
    )  # in the crate's frame
    crate = box_surface(500)
    np.save(folder / "seen.npy", np.vstack([crate, on_arm]))
    extra = "" if self_filter else "self_filter = false"
    (cloud,) = cloud_kind(write_scenario(folder, "seen.npy", extra=extra)).clouds
    assert isinstance(cloud, CloudObstacle) and len(on_arm) > 50
    if self_filter:
        assert cloud.removed == len(on_arm)
        np.testing.assert_allclose(cloud.local, crate, atol=1e-12)
    else:
        assert cloud.removed == 0 and len(cloud.local) == len(crate) + len(on_arm)
