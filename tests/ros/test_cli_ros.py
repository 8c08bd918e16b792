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
     ('prefix = "clik"', "ros.prefix"), ("topic = 1", "ros")],
)  # fmt: skip
def test_a_bad_ros_table_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], table: str, key: str
) -> None:
    pytest.importorskip("rclpy", reason="rclpy is not installed: pip install 'clik[ros]'")
    scenario = tmp_path / "s.toml"
    scenario.write_text(CIRCLE.read_text() + f"\n[ros]\n{table}\n")
    assert main(["ros", str(scenario), "--duration", "0.1"]) == 2
    assert key in capsys.readouterr().err
