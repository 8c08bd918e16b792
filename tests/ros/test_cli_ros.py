"""``clik ros``'s refusals, which need no ROS graph: no rclpy, a bad ``[ros]`` table."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from clik.cli import main
from clik.scenarios import runner

CIRCLE = Path(runner.__file__).with_name("panda_circle.toml")


def test_without_rclpy_it_says_how_to_get_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "rclpy", None)  # import rclpy fails
    assert main(["ros", str(CIRCLE), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "pip install 'clik[ros]'" in err and "ROS 2 install" in err


@pytest.mark.parametrize(
    ("table", "key"),
    [('output = "torque"', "ros.output"), ("timeout = -1.0", "ros.timeout"),
     ('prefix = "clik"', "ros.prefix"), ("topic = 1", "ros"),
     ("measured_jump = 0.0", "ros.measured_jump")],
)  # fmt: skip
def test_a_bad_ros_table_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], table: str, key: str
) -> None:
    pytest.importorskip("rclpy", reason="rclpy is not installed: pip install 'clik[ros]'")
    scenario = tmp_path / "s.toml"
    scenario.write_text(CIRCLE.read_text() + f"\n[ros]\n{table}\n")
    assert main(["ros", str(scenario), "--duration", "0.1"]) == 2
    assert key in capsys.readouterr().err


def test_the_node_s_measured_jump_is_read_from_the_ros_table() -> None:
    """The node's (M3) bound: 10 by default (late ticks), the table's when it gives one."""
    from clik.control.from_scenario import controller_of
    from clik.scenarios.ros_table import MEASURED_JUMP, RosSettings
    from clik.scenarios.runner import build

    assert RosSettings().measured_jump == MEASURED_JUMP == 10.0
    run = build(CIRCLE)
    assert controller_of(run).measured.factor == 3.0  # the Controller's own default
    assert controller_of(run, 7.5).measured.factor == 7.5
