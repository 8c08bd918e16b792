"""Reachability maps: the grid, the solves, manipulability, the table and the HTML view."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pyarrow.parquet as pq
import pytest

from clik import InputError, Task
from clik.cli import main
from clik.sweep.reach import grid_points, manipulability, solve_points
from clik.sweep.reach_data import ReachMap, ReachSpec
from clik.sweep.reach_output import write_reach

pytest.importorskip("distributed", reason="pip install 'dask[distributed]'")

PLANAR_BOX = [-1.6, -1.6, 0.0, 1.6, 1.6, 0.0]
"""5 x 5 x 1 points 0.8 m apart around the planar arm's base; its reach is 4 x 0.3 = 1.2 m."""


def test_grid_points_include_both_bounds_x_fastest():
    points = grid_points([0.0, 0.0, 0.0, 0.2, 0.1, 0.0], 0.1)
    np.testing.assert_allclose(
        points, [[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0, 0.1, 0], [0.1, 0.1, 0], [0.2, 0.1, 0]]
    )
    assert grid_points(PLANAR_BOX, 0.8).shape == (25, 3)


@pytest.mark.parametrize(
    ("box", "step", "field", "expected"),
    [
        ([0, 0, 0, -1, 1, 1], 0.1, "box", "xmin <= xmax"),
        ([0, 0, 0, 1, 1], 0.1, "box", "six finite numbers"),
        ([0, 0, 0, 1, 1, math.nan], 0.1, "box", "six finite numbers"),
        ([0, 0, 0, 1, 1, 1], 0.0, "step", "a positive number [m]"),
        ([0, 0, 0, 10, 10, 10], 0.001, "step", "at most 2000000 points"),
    ],
)
def test_bad_grids(box, step, field, expected):
    with pytest.raises(InputError) as info:
        grid_points(box, step)
    assert info.value.field == field and expected in str(info.value)


def test_manipulability_is_the_product_of_singular_values(planar4r):
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    q = np.radians([10.0, 20.0, 30.0, 40.0])
    singular = np.linalg.svd(task.jacobian(q), compute_uv=False)
    assert manipulability(task, q) == pytest.approx(float(np.prod(singular)), rel=1e-12)
    assert manipulability(task, np.zeros(4)) == pytest.approx(0.0, abs=1e-12)  # stretched out


def test_planar_map_on_a_local_cluster(tmp_path):
    out = tmp_path / "map"
    args = ["reach", "planar4r", "--frame", "tip", "--box", *map(str, PLANAR_BOX)]
    args += ["--step", "0.8", "--axes", "x", "y", "--out", str(out), "--workers", "2", "--quiet"]
    assert main(args) == 0
    table = pq.read_table(out / "reach.parquet").to_pydict()
    assert list(table) == [
        "x", "y", "z", "success", "iterations", "attempts", "position_error",
        "orientation_error", "manipulability",
    ]  # fmt: skip
    points = np.column_stack([table["x"], table["y"], table["z"]])
    np.testing.assert_allclose(points, grid_points(PLANAR_BOX, 0.8))
    radius = np.hypot(points[:, 0], points[:, 1])
    success = np.array(table["success"])
    # Within reach (|p| <= 0.8 * sqrt(2) = 1.13 m < 1.2 m) exactly the inner 3 x 3 points.
    np.testing.assert_array_equal(success, radius < 1.2)
    assert success.sum() == 9
    for i in np.flatnonzero(success):
        assert table["position_error"][i] <= 1e-4
        assert table["manipulability"][i] > 0.0
    for i in np.flatnonzero(~success):
        assert table["manipulability"][i] is None
        assert table["position_error"][i] >= radius[i] - 1.2 - 1e-6  # as close as it gets
        assert table["attempts"][i] == 21  # every restart tried
    info = json.loads((out / "reach.json").read_text())
    assert info["points"] == 25 and info["reachable"] == 9 and info["kind"] == "position"
    html = (out / "reach.html").read_text()
    assert "planar4r tip: 9/25 points reachable" in html and "clikSceneReady" in html
    assert main([*args[:-1], "--quiet"]) == 2  # the folder exists now: --force


def test_panda_pose_map_with_a_fixed_orientation(panda, tmp_path):
    """Points near the hand's reference pose, its orientation fixed: solved; 2 m away: not."""
    task = Task(panda, "panda_hand", "pose")
    reference = task.placement(panda.q_reference)
    rpy = tuple(pin.rpy.matrixToRpy(reference.rotation))
    spec = ReachSpec(
        "panda", "panda_hand", (0, 0, 0, 0, 0, 0), 0.1, orientation_rpy=rpy,
        lock={"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}, restarts=3,
    )  # fmt: skip
    near = reference.translation + np.array([[0.0, 0.0, 0.0], [0.1, 0.0, -0.05], [0.0, 0.1, 0.1]])
    far = reference.translation + np.array([[2.0, 0.0, 0.0]])
    columns = solve_points(spec, np.vstack([near, far]))
    reach = ReachMap.from_columns(spec, columns)
    np.testing.assert_array_equal(reach.success, [True, True, True, False])
    assert reach.iterations[0] == 0  # the start is the target
    assert np.all(reach.orientation_error[:3] <= 1e-3)
    assert np.all(reach.manipulability[:3] > 0) and math.isnan(reach.manipulability[3])
    csv = reach.write_table(tmp_path / "map.parquet", fmt="csv")
    lines = csv.read_text().splitlines()
    assert csv.name == "map.csv" and lines[0].startswith("x,y,z,success")
    assert lines[-1].split(",")[3] == "False" and lines[-1].endswith(",")  # no manipulability
    table = pq.read_table(reach.write_table(tmp_path / "map.parquet")).to_pydict()
    assert table["success"] == [True, True, True, False] and table["manipulability"][3] is None
    # "auto": the suffix decides; an explicit format wins over the suffix.
    assert reach.write_table(tmp_path / "auto.csv").read_text() == csv.read_text()
    forced = reach.write_table(tmp_path / "forced.csv", fmt="parquet")
    assert pq.read_table(forced).to_pydict() == table
    with pytest.raises(InputError, match="format: expected 'auto', 'parquet' or 'csv'"):
        reach.write_table(tmp_path / "map.xlsx", fmt="xlsx")
    written = write_reach(reach, tmp_path / "out", html=False)
    assert sorted(written) == ["json", "table"] and sorted(p.name for p in written.values()) == [
        "reach.json",
        "reach.parquet",
    ]
    assert pq.read_table(written["table"]).to_pydict() == table
    info = json.loads(written["json"].read_text())
    assert info["points"] == 4 and info["reachable"] == 3 and info["table"] == "reach.parquet"


def test_bad_requests_exit_2(tmp_path, capsys):
    base = ["reach", "planar4r", "--box", *map(str, PLANAR_BOX), "--out", str(tmp_path / "o")]
    assert main([*base, "--frame", "hand", "--step", "0.8"]) == 2
    assert "frame 'hand' not found; available frames: 'universe'" in capsys.readouterr().err
    assert main([*base, "--frame", "tip", "--step", "-1"]) == 2
    assert "step: expected a positive number [m]" in capsys.readouterr().err
    assert main([*base, "--frame", "tip", "--step", "0.8", "--lock", "joint9=0"]) == 2
    assert "joint 'joint9' not found" in capsys.readouterr().err
    assert main([*base, "--frame", "tip", "--step", "0.8", "--restarts", "-1"]) == 2
    assert "restarts: expected an integer >= 0" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()  # nothing written before the request is checked
    with pytest.raises(SystemExit):
        main([*base, "--frame", "tip", "--step", "0.8", "--lock", "joint1"])
    assert "expected JOINT=VALUE" in capsys.readouterr().err


CHROMIUM = Path("/usr/bin/chromium")


@pytest.mark.browser
@pytest.mark.skipif(not CHROMIUM.exists(), reason="no /usr/bin/chromium: apt-get install chromium")
def test_the_html_view_loads_in_a_browser(tmp_path, planar4r):
    sync_api = pytest.importorskip("playwright.sync_api", reason="pip install playwright")
    from clik.sweep.reach_view import export_reach_html

    spec = ReachSpec("planar4r", "tip", tuple(PLANAR_BOX), 0.8, axes=("x", "y"))
    reach = ReachMap.from_columns(spec, solve_points(spec, grid_points(PLANAR_BOX, 0.8)))
    path = export_reach_html(reach, tmp_path / "reach.html", robot=planar4r)
    errors: list[str] = []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=str(CHROMIUM), args=["--no-sandbox", "--disable-gpu"]
        )
        try:
            page = browser.new_page(viewport={"width": 800, "height": 600})
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(path.as_uri())
            page.wait_for_function("window.clikSceneReady === true", timeout=30_000)
            counts = page.evaluate(
                """() => ["reachable", "unreachable"].map(
                    (n) => viewer.scene_tree.find(["meshcat", "reach", n]).object
                        .children[0].geometry.attributes.position.count)"""
            )
        finally:
            browser.close()
    assert errors == []
    assert counts == [9, 16]
