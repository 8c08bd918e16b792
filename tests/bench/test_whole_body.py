"""Several tasks per tick (issue 42): the bench's dual-arm and humanoid scenes.

The controller stepped tick by tick with a mapping of arrays equals ``clik.track`` on
the same references (1e-12 rad), in both engines; every tick is ``ok``; Pinocchio's
forward kinematics of the commanded joints keeps the feet, the hands and the centre
of mass where the references put them, within the joints' ranges and speeds.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import numpy as np
import pytest

import clik
from benchmarks.whole_body import WholeBody, dual_arm_scene, humanoid_scene

FOOT_TOLERANCE = 1e-5
"""Talos' soles, held [m]."""
HAND_TOLERANCE = {"dual_arm": 1e-5, "humanoid": 1e-4}
"""Baxter's hands on their lines, Talos' hand on its circle [m]."""


@pytest.fixture(scope="module", params=["dual_arm", "humanoid"])
def scene(request: pytest.FixtureRequest) -> Iterator[WholeBody]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ClikWarning)
        yield dual_arm_scene() if request.param == "dual_arm" else humanoid_scene()


def stepped(scene: WholeBody, engine: str) -> tuple[np.ndarray, list[str], clik.TrackingResult]:
    """The controller over the scene's ticks: q_0 .. q_n, each tick's verdict, its result."""
    ctl = scene.controller(engine)
    qs, verdicts = [ctl.q], []
    for k in range(scene.ticks):
        tick = ctl.step(scene.targets[k], scene.velocities[k])
        qs.append(tick.q)
        verdicts.append(tick.verdict)
    return np.array(qs), verdicts, ctl.result()


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_the_controller_equals_track_and_tracks(scene: WholeBody, engine: str) -> None:
    joints, verdicts, result = stepped(scene, engine)
    assert set(verdicts) == {"ok"}
    assert result.status == "completed" and not result.violations
    offline = clik.track(
        tasks=scene.goals, q0=scene.q0, law="pseudoinverse", gain=100.0, dt=scene.t[1],
        constraints=scene.constraints(), engine=engine,
    )  # fmt: skip
    assert offline.status == "completed" and offline.steps == scene.ticks
    np.testing.assert_allclose(joints[:-1], offline.q, rtol=0, atol=1e-12)
    quality = scene.quality(joints)
    tasks = {k.split(".", 1)[1]: v for k, v in quality.items() if k.startswith("max_error_m.")}
    assert set(tasks) == set(scene.poses)
    for name, error in tasks.items():
        bound = FOOT_TOLERANCE if name.endswith("foot") else HAND_TOLERANCE[scene.name]
        assert error <= bound, (name, error)
    assert quality["max_orientation_error_rad"] <= 1e-4
    if scene.com is not None:
        assert quality["com_error_m"] <= 1e-5
    assert quality["max_joint_range_excess"] == 0.0
    assert quality["velocity_ratio"] <= 1.0


def test_the_engines_agree(scene: WholeBody) -> None:
    compiled, _, _ = stepped(scene, "compiled")
    python, _, _ = stepped(scene, "python")
    np.testing.assert_allclose(compiled, python, rtol=0, atol=1e-9)


def test_a_joint_held_at_its_range(scene: WholeBody) -> None:
    """A start near a joint's limit: its range row active from the first tick, the engines
    agree while it holds the joint and after it lets go."""
    q0 = scene.q0.copy()
    model = scene.robot.model
    joint = model.joints[model.njoints - 1]
    q0[joint.idx_q] = model.upperPositionLimit[joint.idx_q] - 1e-3
    runs = []
    for engine in ("compiled", "python"):
        ctl = scene.controller(engine)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", clik.ClikWarning)
            ctl.reset(q0)
        qs = [ctl.q]
        for k in range(200):
            tick = ctl.step(scene.targets[k], scene.velocities[k])
            assert tick.verdict == "ok", tick.reason
            assert tick.active or k > 0, "the joint's range row is active at the start"
            qs.append(tick.q)
        runs.append(np.array(qs))
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-9)
    assert np.all(runs[0][:, joint.idx_q] <= model.upperPositionLimit[joint.idx_q])
