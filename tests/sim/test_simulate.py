"""``clik simulate``: a run replayed in MuJoCo (clik.sim, docs/guides/simulate.md)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from clik.cli import main
from clik.errors import InputError
from clik.model.robot import PANDA_FINGERS, Robot
from clik.model.srdf import SrdfWarning
from clik.scenarios import runner
from clik.sim import SIMULATION_FILE, SIMULATION_PLOT, simulate
from clik.sim.mujoco_model import robot_spec
from clik.viz.target import load_target

SCENARIOS = Path(runner.__file__).parent
BALL = """
[[obstacles]]
name = "ball"
shape = "sphere"
position = {position}
radius = {radius}

[constraints.obstacles]
enabled = {enabled}
"""


def _solved(tmp_path: Path, name: str, extra: str = "") -> Path:
    """An output folder of ``clik solve`` on the shipped Panda circle (plus ``extra``)."""
    scenario = tmp_path / f"{name}.toml"
    scenario.write_text((SCENARIOS / "panda_circle.toml").read_text() + extra)
    out = tmp_path / name
    assert main(["solve", str(scenario), "--out", str(out)]) in (0, 3)
    return out


@pytest.fixture(scope="module")
def circle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _solved(tmp_path_factory.mktemp("circle"), "circle")


def test_feedforward_closes_the_servo_lag(circle: Path, tmp_path: Path) -> None:
    result = load_target(circle)
    with_ff = simulate(result, feedforward=True)
    without = simulate(result, feedforward=False)
    run = with_ff.summary()["run_position_error_m"]["task"]
    ff = with_ff.summary()["position_error_m"]["task"]
    servo = without.summary()["position_error_m"]["task"]
    assert run["max"] < 1e-5  # the run itself tracks the circle
    assert ff["max"] < 1e-3  # fed forward: under a millimetre
    assert servo["median"] > 5e-3  # a position servo alone lags by millimetres
    assert servo["median"] > 20 * ff["median"]
    # the lag is that of eq. (P1) without feed-forward: kv / kp seconds of motion
    speed = np.linalg.norm(np.diff(result.position, axis=0), axis=1) / np.diff(result.t)
    assert servo["max"] == pytest.approx(200.0 / 4000.0 * speed.max(), rel=0.25)
    assert with_ff.summary()["min_clearance_m"] is None
    assert with_ff.summary()["saturated_joints"] == []


def test_the_command_writes_and_keeps(circle: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", str(circle)]) == 0
    printed = capsys.readouterr().out
    assert "with velocity feed-forward" in printed and "off its reference" in printed
    summary = json.loads((circle / SIMULATION_FILE).read_text())
    assert set(summary) >= {"position_error_m", "min_clearance_m", "saturated_joints"}
    assert summary["position_error_m"]["task"]["max"] < 1e-3
    assert (circle / SIMULATION_PLOT).stat().st_size > 1000
    before = (circle / SIMULATION_FILE).read_text()
    assert main(["simulate", str(circle), "--no-feedforward"]) == 2  # exists: not replaced
    assert "--force" in capsys.readouterr().err
    assert (circle / SIMULATION_FILE).read_text() == before
    assert main(["simulate", str(circle), "--no-feedforward", "--force"]) == 0
    assert json.loads((circle / SIMULATION_FILE).read_text())["feedforward"] is False


def test_clearance_matches_clik_and_finds_a_collision(tmp_path: Path) -> None:
    near = _solved(
        tmp_path, "near", BALL.format(position=[0.45, 0.1, 0.75], radius=0.05, enabled="true")
    )
    result = load_target(near)
    clearance = simulate(result).summary()["min_clearance_m"]
    assert result.min_obstacle_distance is not None
    assert clearance == pytest.approx(float(result.min_obstacle_distance.min()), abs=2e-3)
    assert clearance > 0.0
    hit = _solved(
        tmp_path, "hit", BALL.format(position=[0.307, 0.1, 0.59], radius=0.08, enabled="false")
    )
    assert main(["simulate", str(hit)]) == 3  # the replayed hand passes through the ball
    assert json.loads((hit / SIMULATION_FILE).read_text())["min_clearance_m"] < -0.05


def test_saturation_is_reported(circle: Path) -> None:
    result = load_target(circle)
    assert result.robot is not None
    model = result.robot.model
    kept = model.effortLimit.copy()
    try:
        model.effortLimit = np.full_like(kept, 0.05)  # [N m]: too weak to follow
        sim = simulate(result)
    finally:
        model.effortLimit = kept
    saturated = sim.summary()["saturated_joints"]
    assert saturated and all(0.0 < s["fraction"] <= 1.0 for s in saturated)
    assert sim.summary()["position_error_m"]["task"]["max"] > 1e-2
    assert "force limit" in sim.words()


def test_every_task_of_a_stack_is_measured(tmp_path: Path) -> None:
    out = tmp_path / "two"
    assert main(["solve", str(SCENARIOS / "baxter_two_hands.toml"), "--out", str(out)]) == 0
    with pytest.warns(SrdfWarning):  # example-robot-data's SRDF names baxter/... joints
        result = load_target(out)
    summary = simulate(result).summary()
    hands = {"left_hand", "right_hand"}
    assert hands <= set(summary["position_error_m"])
    for name in hands:
        assert summary["position_error_m"][name]["max"] < 2e-3
        assert summary["run_position_error_m"][name]["max"] < 1e-5
    assert summary["dropped_meshes"]  # Baxter's Collada meshes: MuJoCo does not read them


def test_robots_a_replay_cannot_drive(planar4r: Robot) -> None:
    import mujoco

    with pytest.raises(InputError, match=r"robot\.inertial.*joint1"):
        robot_spec(mujoco, planar4r)
    floating = Robot.load("panda", base="floating", lock=PANDA_FINGERS)
    with pytest.raises(InputError, match=r"robot\.base.*fixed-base robot"):
        robot_spec(mujoco, floating)


def test_bad_settings_are_named(circle: Path) -> None:
    result = load_target(circle)
    for kw, field in ((dict(kp=-1.0), "kp"), (dict(kv=float("nan")), "kv"),
                      (dict(timestep=0.0), "timestep")):  # fmt: skip
        with pytest.raises(InputError, match=f"simulate.{field}"):
            simulate(result, **kw)  # type: ignore[arg-type]
    assert main(["simulate", str(circle / "nothing")]) == 2


def test_the_replay_moves_the_joints_mujoco_reports(circle: Path) -> None:
    """The joints the report gives are MuJoCo's, mapped back to clik's frames right."""
    result = load_target(circle)
    sim = simulate(result)
    assert result.robot is not None
    model, data = result.robot.model, result.robot.model.createData()
    k = len(result.t) // 2
    q = result.q[k].copy()
    q[: sim.q_sim.shape[1]] = sim.q_sim[k]
    pin.framesForwardKinematics(model, data, q)
    hand = data.oMf[model.getFrameId("panda_hand")].translation
    gap = np.linalg.norm(hand - result.reference_position[k])
    assert gap == pytest.approx(sim.errors["task"][k], abs=1e-12)
