"""``clik reach --scenario``: the map respects a scenario's obstacles and counts what they block."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from clik import solve
from clik.cli import main
from clik.scenarios.scenario import load_scenario
from clik.sweep.reach import grid_points, reach_objects, solve_points
from clik.sweep.reach_data import ReachMap, ReachSpec
from clik.sweep.reach_view import reach_commands
from tests.solving.test_constrained_solve import assert_clear, assert_on_target

pytest.importorskip("distributed", reason="pip install 'dask[distributed]'")

SCENARIO = """
name = "Panda beside a ball"

[robot]
source = "panda"
lock = { panda_finger_joint1 = 0.0, panda_finger_joint2 = 0.0 }

[task]
frame = "panda_hand"
kind = "position"

[trajectory]
kind = "hold"
duration = 0.0

[constraints.obstacles]
enabled = true

[constraints.joint_limits]
enabled = true
"""

BALL = """
[[obstacles]]
name = "ball"
shape = "sphere"
position = [0.45, 0.0, 0.35]
radius = 0.1
threshold = 0.03
"""

BOX = ["0.3", "-0.1", "0.3", "0.5", "0.1", "0.4"]
"""3 x 3 x 2 points 0.1 m apart around the ball."""


def reach(tmp_path: Path, name: str, text: str) -> tuple[int, dict, dict]:
    """Run ``clik reach --scenario`` on ``text``: exit code, reach.json, the table."""
    scenario = tmp_path / f"{name}.toml"
    scenario.write_text(text)
    out = tmp_path / name
    code = main(
        ["reach", "--scenario", str(scenario), "--box", *BOX, "--step", "0.1",
         "--out", str(out), "--workers", "1", "--quiet"]
    )  # fmt: skip
    info = json.loads((out / "reach.json").read_text()) if code == 0 else {}
    table = pq.read_table(out / "reach.parquet").to_pydict() if code == 0 else {}
    return code, info, table


def test_a_ball_blocks_points_that_the_same_grid_reaches_without_it(tmp_path):
    code, with_ball, table = reach(tmp_path, "with", SCENARIO + BALL)
    assert code == 0
    code, without, plain = reach(tmp_path, "without", SCENARIO)
    assert code == 0
    assert with_ball["points"] == without["points"] == 18
    assert with_ball["frame"] == "panda_hand" and with_ball["scenario"].endswith("with.toml")
    assert with_ball["blocked"] > 0 and without["blocked"] == 0
    # The same seeds: what the ball blocks is exactly what it takes from the reachable points.
    assert with_ball["reachable"] + with_ball["blocked"] == without["reachable"]
    assert with_ball["unreachable"] == without["unreachable"]
    blocked = np.array(table["blocked"])
    assert list(table)[-1] == "blocked" and blocked.sum() == with_ball["blocked"]
    assert not np.any(blocked & np.array(table["success"]))
    assert np.all(np.array(plain["success"])[blocked])  # solved without the ball
    points = np.column_stack([table["x"], table["y"], table["z"]])
    assert np.linalg.norm(points[blocked] - [0.45, 0.0, 0.35], axis=1).max() < 0.25
    html = (tmp_path / "with" / "reach.html").read_text()
    assert f"{with_ball['blocked']} blocked by the constraints" in html


def test_the_view_draws_blocked_points_and_the_obstacles(tmp_path, panda):
    scenario = tmp_path / "with.toml"
    scenario.write_text(SCENARIO + BALL)
    spec = ReachSpec(
        "panda", "panda_hand", (0.45, 0.0, 0.35, 0.45, 0.0, 0.65), 0.3,
        scenario=str(scenario), scenario_data=load_scenario(scenario).raw,
    )  # fmt: skip
    reach = ReachMap.from_columns(spec, solve_points(spec, grid_points(spec.box, spec.step)))
    np.testing.assert_array_equal(reach.blocked, [True, False])  # in the ball, above it
    assert reach.counts() == {"reachable": 1, "blocked": 1, "unreachable": 0}
    robot, task, constraints = reach_objects(spec)
    assert constraints is not None
    for point in reach.points[reach.success]:  # the pose behind a reachable point is clear
        result = solve(task, point, robot.q_reference, restarts=spec.restarts,
                       constraints=constraints)  # fmt: skip
        assert result.success
        assert_clear(robot, constraints, result.q)
        assert_on_target(task, result.q, point)
    paths = [c.get("path") for c in reach_commands(reach, panda, constraints.obstacle_info())]
    assert "/meshcat/obstacles/ball/body" in paths and "/meshcat/obstacles/ball/shell" in paths
    assert "/meshcat/reach/blocked" in paths and "/meshcat/reach/unreachable" not in paths


def test_bad_scenarios_name_the_flag(tmp_path, capsys):
    base = ["reach", "--box", *BOX, "--step", "0.1", "--out", str(tmp_path / "o")]
    assert main([*base, "--scenario", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err
    assert "--scenario: expected a scenario file" in err and "no such scenario file" in err
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('[base]\nname = "x"\n')
    assert main([*base, "--scenario", str(sweep)]) == 2
    assert "--scenario: expected a scenario file" in capsys.readouterr().err
    garbage = tmp_path / "garbage.toml"
    garbage.write_bytes(b"\x00\xff not toml")
    assert main([*base, "--scenario", str(garbage)]) == 2
    assert "--scenario: expected a scenario file" in capsys.readouterr().err
    good = tmp_path / "good.toml"
    good.write_text(SCENARIO)
    assert main([*base[:1], "panda", *base[1:], "--scenario", str(good)]) == 2
    assert "--scenario: expected no ROBOT argument with it" in capsys.readouterr().err
    assert main(base) == 2
    assert "ROBOT: expected a robot name or URDF path" in capsys.readouterr().err
    assert main([*base[:1], "panda", *base[1:]]) == 2
    assert "--frame: expected the frame to place" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
