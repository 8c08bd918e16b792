"""Cloud rows on the Panda, both engines: clouds sampled from analytic shapes (issue 45).

The clearance the rows hold is checked on the written joints against the shapes
themselves (coal, the links' convex geometry as the rows use it), not against the
cloud: at least the threshold minus the voxel size (docs/method.md (C2)). Without
rows the same run goes through the shapes.
"""

from __future__ import annotations

import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.clouds import CloudObstacle, EmptyCloudWarning
from clik.constraints import ConstraintSet
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.collision_scene import CollisionScene
from clik.trajectory import Line
from clik.viz.live_demo import box_skin
from tests.limits_check import assert_within_limits

THRESHOLD = 0.05
VOXEL = 0.01
BOX_HALF = np.array([0.06, 0.06, 0.12])
BALL = 0.05


def ball_skin(radius: float, n: int) -> np.ndarray:
    """``n`` points spread on a sphere (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    polar, azimuth = np.arccos(1.0 - 2.0 * k / n), np.pi * (1.0 + 5**0.5) * k
    return radius * np.column_stack(
        [np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)]
    )


@pytest.fixture(scope="module")
def scene(panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation.copy()
    box_at = p0 + np.array([0.0, 0.28, -0.02])
    ball_at = p0 + np.array([0.08, -0.2, 0.12])
    shapes = [(coal.Box(*(2.0 * BOX_HALF)), box_at), (coal.Sphere(BALL), ball_at)]
    points = np.vstack([box_skin(BOX_HALF, 0.005) + box_at, ball_skin(BALL, 1500) + ball_at])
    line = Line(p0, p0 + np.array([0.0, 0.45, 0.0]), duration=1.2)
    return task, p0, shapes, points, line


def clearance(robot, qs: np.ndarray, shapes, every: int = 5) -> float:
    """The smallest distance of any link's convex geometry to the shapes [m] (coal)."""
    geometry = CollisionScene(robot)
    data, gdata = robot.model.createData(), pin.GeometryData(geometry.gmodel)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    request.enable_signed_distance = True
    worst = np.inf
    for q in qs[::every]:
        pin.updateGeometryPlacements(robot.model, data, geometry.gmodel, gdata, q)
        for i in range(geometry.n_links):
            M = gdata.oMg[i]
            placed = coal.Transform3s(M.rotation, M.translation)
            for shape, at in shapes:
                result.clear()
                link = geometry.gmodel.geometryObjects[i].geometry
                coal.distance(link, placed, shape, coal.Transform3s(np.eye(3), at), request, result)
                worst = min(worst, result.min_distance)
    return float(worst)


def run(task, line, points, engine: str, rows: bool = True):
    cloud = CloudObstacle("scan", points, voxel=VOXEL)
    cset = ConstraintSet(task.robot, kinds=[CloudAvoidance([cloud], rows, THRESHOLD)])
    tracker = clik.Tracker(task, law="pseudoinverse", gain=100.0, constraints=cset, engine=engine)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tracker.run(line)


def test_without_rows_the_line_goes_through_the_box(panda, scene):
    task, _, shapes, points, line = scene
    result = run(task, line, points, "compiled", rows=False)
    assert result.status == "violated", result.reason
    assert "cloud:scan:" in result.reason
    assert clearance(panda, result.q, shapes) < 0.0
    assert result.summary()["min_cloud_distance"] < 0.0


def test_the_rows_keep_the_shapes_beyond_threshold_minus_voxel_in_both_engines(panda, scene):
    task, _, shapes, points, line = scene
    results = [run(task, line, points, engine) for engine in ("python", "compiled")]
    for result in results:
        assert result.status in ("completed", "deadlock"), result.reason
        assert any(e["constraint"].startswith("cloud:scan:") for e in result.events)
        assert clearance(panda, result.q, shapes) >= THRESHOLD - VOXEL
        lower, upper = panda.model.lowerPositionLimit, panda.model.upperPositionLimit
        assert np.all(result.q >= lower - 1e-9) and np.all(result.q <= upper + 1e-9)
        summary = result.summary()
        assert summary["min_cloud_distance"] >= THRESHOLD - 0.01
        assert summary["max_velocity_ratio"] <= 1.0 + 1e-9
    python, compiled = results
    assert python.status == compiled.status and python.reason == compiled.reason
    assert python.q.shape == compiled.q.shape
    np.testing.assert_allclose(python.q, compiled.q, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(
        python.extra["cloud_distance"], compiled.extra["cloud_distance"], rtol=0.0, atol=1e-9
    )
    assert python.events == compiled.events


def test_a_box_sliding_toward_the_arm_tick_by_tick(panda, scene):
    task, p0, _, _, _ = scene
    local = box_skin(BOX_HALF, 0.005)
    start = p0 + np.array([0.0, 0.4, 0.0])

    def centre(k: int) -> np.ndarray:
        return start + np.array([0.0, -0.18 * min(k, 600) / 600, 0.0])  # stops 16 cm short

    outcome = {}
    for engine in ("python", "compiled"):
        cloud = CloudObstacle("scan", local + centre(0), voxel=VOXEL)
        cset = ConstraintSet(panda, kinds=[CloudAvoidance([cloud], threshold=THRESHOLD)])
        ctl = clik.Controller(task, constraints=cset, engine=engine, q0=panda.q_reference)
        qs, verdicts, worst = [], set(), np.inf
        for k in range(900):
            tick = ctl.step(p0, obstacles={"scan": local + centre(k)})
            qs.append(tick.q)
            verdicts.add(tick.verdict)
            box = [(coal.Box(*(2.0 * BOX_HALF)), centre(k))]
            if k % 15 == 0:
                worst = min(worst, clearance(panda, np.array([tick.q]), box, every=1))
        result = ctl.result()
        outcome[engine] = np.array(qs)
        assert verdicts == {"ok"}, result.reason
        assert_within_limits(result, panda)  # joints in range, no limit crossed
        assert result.summary()["max_velocity_ratio"] <= 1.0 + 1e-9
        assert worst >= THRESHOLD - VOXEL
        assert any(e["constraint"].startswith("cloud:scan:") for e in result.events)
        hand = task.placement(qs[-1]).translation
        assert np.linalg.norm(hand - p0) < 1e-3  # the arm moved aside, the hand held
    np.testing.assert_allclose(outcome["python"], outcome["compiled"], rtol=0.0, atol=1e-9)


def test_an_empty_cloud_warns_and_adds_no_row(panda, scene):
    task, _, _, _, line = scene
    with pytest.warns(EmptyCloudWarning, match="'scan' has no points \\(2 dropped"):
        cloud = CloudObstacle("scan", np.full((2, 3), np.nan))
    assert cloud.dropped == 2
    cset = ConstraintSet(panda, kinds=[CloudAvoidance([cloud])])
    result = clik.Tracker(task, constraints=cset).run(line)
    assert result.status == "completed" and not result.events
    assert_within_limits(result, panda)
    assert result.summary()["max_velocity_ratio"] <= 1.0 + 1e-9


def test_a_cloud_that_is_not_a_name_of_the_set_is_refused(panda, scene):
    task, p0, _, points, _ = scene
    cset = ConstraintSet(panda, kinds=[CloudAvoidance([CloudObstacle("scan", points)])])
    ctl = clik.Controller(task, constraints=cset, q0=panda.q_reference)
    with pytest.raises(clik.InputError, match="one of \\['scan'\\]"):
        ctl.update_cloud("lidar", points)
    with pytest.raises(clik.InputError, match=r"obstacles\.scan\.points"):
        ctl.step(p0, obstacles={"scan": np.zeros((4, 2))})


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_an_update_that_sees_the_arm_leaves_the_arm_out_with_a_padding(panda, scene, engine):
    from tests.clouds.test_self_filter import link_points

    task, p0, _, points, _ = scene
    cset = ConstraintSet(panda, kinds=[CloudAvoidance([CloudObstacle("scan", points)])])
    seen = np.vstack([points, link_points(panda, panda.q_reference)])  # the camera sees the arm
    ctl = clik.Controller(task, constraints=cset, engine=engine, q0=panda.q_reference)
    ctl.update_cloud("scan", seen, robot_padding=0.01)
    tick = ctl.step(p0)
    assert tick.verdict == "ok" and not tick.active
    ctl.update_cloud("scan", seen)  # kept: the arm is inside its own cloud
    tick = ctl.step(p0)
    assert tick.verdict == "violated" and tick.active
    assert all(name.startswith("cloud:scan:panda_") for name in tick.active)
