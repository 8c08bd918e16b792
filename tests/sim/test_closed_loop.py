"""clik.sim.closed_loop: the controller driving MuJoCo, the simulated joints fed back."""

from __future__ import annotations

import numpy as np
import pytest

from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.sim.closed_loop import drive, main


@pytest.fixture(scope="module")
def circle():  # type: ignore[no-untyped-def]
    return build(scenario_path("panda_circle"))


def test_fed_forward_the_loop_tracks_the_circle(circle) -> None:  # type: ignore[no-untyped-def]
    loop = drive(circle, feedforward=True)
    s = loop.summary()
    assert s["verdicts"] == {"ok": len(loop.t)}
    assert s["position_error_m"]["task"]["max"] < 1e-3
    model = circle.robot.model
    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    assert np.all(loop.q_sim >= lower - 1e-9) and np.all(loop.q_sim <= upper + 1e-9)
    speed = np.abs(np.diff(loop.q_sim, axis=0)) / np.diff(loop.t)[:, None]
    assert np.all(speed <= model.velocityLimit + 1e-6)


def test_position_servos_alone_lag(circle) -> None:  # type: ignore[no-untyped-def]
    fed = drive(circle, feedforward=True).summary()["position_error_m"]["task"]
    servo = drive(circle, feedforward=False).summary()["position_error_m"]["task"]
    assert servo["median"] > 5e-3 > 100 * fed["median"]


def test_the_script(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["panda_circle"]) == 0
    out = capsys.readouterr().out
    assert "with feed-forward: task task" in out and "without feed-forward" in out
    assert main([]) == 2
