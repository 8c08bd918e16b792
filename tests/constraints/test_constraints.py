"""Constraint rows (13)-(19), activation and release, the case study, the Panda, deadlock."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.constraints import CollisionScene, ConstraintSet, JointLimits, Obstacle, obstacle_row
from clik.constraints.obstacle_rows import point_jacobian
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.trajectory import Line
from tests.limits_check import assert_completed, assert_within_limits

FD = 1e-6
PANDA_FINGER_STL = str(
    next(
        iter(
            sorted(
                clik.Robot.load("panda").source_path.parent.parent.glob(
                    "meshes/collision/finger.stl"
                )
            )
        )
    )
)


def pair_error_and_row(robot, scene, q, link, o, form, thr, t=0.0):
    """Error and row of the (link geometry, obstacle) pair at q."""
    pin.computeJointJacobians(robot.model, robot.data, q)
    scene.update(robot.data, t)
    pair = int(scene.obstacle_pairs[link, o])
    dist, p_link, p_obs, normal = scene.distance(pair)
    Jp = point_jacobian(robot.model, robot.data, int(scene.link_joint[link]), p_link)
    row = np.zeros(robot.nv)
    e, ff = obstacle_row(
        form, thr, dist, p_link, p_obs, normal, Jp, scene.obstacles[o].velocity, row
    )
    return e, row, ff, dist


def write_octahedron_obj(folder):
    """A small convex mesh file (an octahedron of 2 cm half-size), as a user would give."""
    folder.mkdir(parents=True, exist_ok=True)
    v = 0.02 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    faces = [(1, 3, 5), (3, 2, 5), (2, 4, 5), (4, 1, 5), (3, 1, 6), (2, 3, 6), (4, 2, 6), (1, 4, 6)]
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    text += "".join(f"f {a} {b} {c}\n" for a, b, c in faces)
    path = folder / "octahedron.obj"
    path.write_text(text)
    return path


def obstacles_near(robot, q, link_index, mesh_dir, scene_links=None):
    """Four shapes placed about 5 cm from a link's geometry at q."""
    probe = CollisionScene(
        robot, [Obstacle("probe", "sphere", [9.0, 9.0, 9.0], radius=0.0)], scene_links
    )
    pin.framesForwardKinematics(robot.model, robot.data, q)
    probe.update(robot.data, 0.0)
    M = probe.gdata.oMg[link_index]
    away = M.translation + M.rotation @ np.array([0.15, 0.12, 0.05])
    mesh = str(write_octahedron_obj(mesh_dir))
    return [
        Obstacle("sphere", "sphere", away, radius=0.01),
        Obstacle("box", "box", away, rpy=[0.3, 0.2, 0.1], size=[0.02, 0.03, 0.04]),
        Obstacle("capsule", "capsule", away, rpy=[0.5, 0.0, 0.0], radius=0.01, length=0.03),
        Obstacle("mesh", "mesh", away + [0.03, 0.03, 0.0], rpy=[0.2, 0.4, 0.0], file=mesh),
        # a real collision mesh (its convex hull) against the link's hull: GJK on both sides
        Obstacle(
            "link_mesh",
            "mesh",
            away + [0.1, 0.1, 0.0],
            file=PANDA_FINGER_STL,
            scale=[0.3, 0.3, 0.3],
        ),
    ]


@pytest.mark.parametrize("form", ["normalized", "squared"])
@pytest.mark.parametrize(("robot_name", "q_seed"), [("planar4r", 1), ("panda", 2)])
def test_obstacle_rows_are_the_derivative_of_their_error(
    request, robot_name, q_seed, form, tmp_path
):
    robot = request.getfixturevalue(robot_name)
    rng = np.random.default_rng(q_seed)
    q = (
        robot.random_configuration(rng)
        if robot_name == "panda"
        else np.radians([180, -30, -90, -30])
    )
    link = robot.nv - 1 if robot_name == "planar4r" else 5
    obstacles = obstacles_near(robot, q, link, tmp_path)
    scene = CollisionScene(robot, obstacles)
    for o in range(len(obstacles)):
        _, row, _, dist = pair_error_and_row(robot, scene, q, link, o, form, 0.3)
        assert dist > 0.0
        for _ in range(3):
            dq = rng.normal(size=robot.nv)
            e_plus = pair_error_and_row(robot, scene, q + FD * dq, link, o, form, 0.3)[0]
            e_minus = pair_error_and_row(robot, scene, q - FD * dq, link, o, form, 0.3)[0]
            # edot = ff - j qdot  =>  de/dq dq = -j dq
            assert (e_plus - e_minus) / (2 * FD) == pytest.approx(-row @ dq, rel=1e-4, abs=1e-7)


def test_point_segment_and_sphere_capsule_closed_forms(planar4r):
    q = np.radians([180, -30, -90, -30])
    pin.framesForwardKinematics(planar4r.model, planar4r.data, q)
    joints = [planar4r.data.oMi[j].translation.copy() for j in range(1, 5)]
    tip = planar4r.data.oMf[planar4r.frame_id("tip")].translation.copy()
    a, b = joints[3], tip  # link 4 is the segment from joint 4 to the tip
    c = np.array([0.7, -0.28, 0.0])
    s = np.clip((c - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    closed = float(np.linalg.norm(a + s * (b - a) - c))
    for radius in (0.0, 0.01):
        scene = CollisionScene(planar4r, [Obstacle("pin", "sphere", c, radius=radius)])
        scene.update(planar4r.data, 0.0)
        dist, p_link, p_obs, _ = scene.distance(int(scene.obstacle_pairs[3, 0]))
        assert dist == pytest.approx(closed - radius, abs=1e-9)
        np.testing.assert_allclose(p_link, a + s * (b - a), atol=1e-9)
        assert np.linalg.norm(p_obs - c) == pytest.approx(radius, abs=1e-9)


def test_joint_limit_rows(planar4r):
    jl = JointLimits(planar4r, np.radians(2.0), {"joint3": {"upper": np.radians(-80.0)}})
    q = np.radians([180, -30, -81, -30])
    e = jl.evaluate(q)
    i_up = jl.names.index("joint:joint3:upper")
    assert e[i_up] == pytest.approx(np.radians(2.0) - np.radians(1.0))  # e_q = d_q - d (17)
    row = np.zeros(4)
    jl.row(i_up, row)
    np.testing.assert_array_equal(row, [0, 0, -1, 0])  # u_q = -(0 0 1 0) for an upper limit
    # the row is minus the derivative of the error: edot = -u qdot
    dq = np.array([0.1, 0.2, 0.3, 0.4])
    assert (jl.evaluate(q + FD * dq)[i_up] - jl.evaluate(q - FD * dq)[i_up]) / (2 * FD) == (
        pytest.approx(-row @ dq)
    )
    jl.row(jl.names.index("joint:joint2:lower"), row)
    np.testing.assert_array_equal(row, [0, 1, 0, 0])


def test_moving_obstacle_feed_forward(planar4r):
    q = np.radians([180, -30, -90, -30])
    v = np.array([0.02, -0.05, 0.0])
    scene = CollisionScene(
        planar4r, [Obstacle("pin", "sphere", [0.7, -0.28, 0.0], velocity=v, radius=0.0)]
    )
    for form in ("normalized", "squared"):
        e0, _, ff, _ = pair_error_and_row(planar4r, scene, q, 3, 0, form, 0.03, t=0.0)
        e1 = pair_error_and_row(planar4r, scene, q, 3, 0, form, 0.03, t=FD)[0]
        assert (e1 - e0) / FD == pytest.approx(ff, rel=1e-4)  # edot = ff with qdot = 0


def case_study(name: str) -> clik.TrackingResult:
    return build(scenario_path(name)).execute()


def actions(result, prefix):
    return [e["action"] for e in result.events if e["constraint"].startswith(prefix)]


Q3_LIMIT = -80.0


@pytest.fixture(scope="module", params=["", "_pinv"], ids=["law9", "law10"])
def runs(request):
    names = ("unconstrained", "obstacle", "joint_limit", "both")
    return request.param, {n: case_study(f"case_study_{n}{request.param}") for n in names}


def test_case_study_claims(runs):
    suffix, r = runs
    q3max = {n: math.degrees(res.joint_max[2]) for n, res in r.items()}
    dist = {n: res.summary()["min_obstacle_distance"] for n, res in r.items()}
    for res in r.values():
        assert_completed(res)  # the URDF's limits; the -80 deg one below
    # 1: link 4 hits the obstacle, q3 passes -80 deg
    assert dist["unconstrained"] < 1e-4 and q3max["unconstrained"] > Q3_LIMIT
    # 2: no collision, q3 still passes -80 deg
    assert dist["obstacle"] > 0.005 and q3max["obstacle"] > Q3_LIMIT
    # 3: q3 stays below -80 deg
    assert q3max["joint_limit"] < Q3_LIMIT
    # 4: no collision, q3 below -80 deg, the joint-limit constraint released before the end
    assert dist["both"] > 0.005 and q3max["both"] < Q3_LIMIT
    releases = [
        e
        for e in r["both"].events
        if e["constraint"] == "joint:joint3:upper" and e["action"] == "release"
    ]
    assert releases and releases[0]["t"] < 3.0
    if suffix == "_pinv":  # law (10): tight tracking and constraints held almost exactly
        for name, res in r.items():
            assert res.max_task_error < 1e-4, name
        for name in ("obstacle", "both"):
            assert dist[name] >= 0.03 - 1e-3
        for name in ("joint_limit", "both"):
            assert q3max[name] <= -82.0 + 0.1
        for res in r.values():
            for prefix in ("obstacle", "joint"):
                acts = actions(res, prefix)
                assert acts.count("activate") <= 1 and acts.count("release") <= 1


def test_sign_release_rule_chatters_where_projection_does_not(planar4r):
    run = build(scenario_path("case_study_both_pinv"))
    run.tracker.constraints.release_rule = "sign"
    sign = run.execute()
    assert (
        actions(sign, "joint").count("activate") > 1
        or actions(sign, "obstacle").count("activate") > 1
    )


@pytest.fixture(scope="module")
def panda_line(panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    return task, Line(p0, p0 + [0.0, 0.35, -0.1], duration=3.0)


BALL = Obstacle("ball", "sphere", [0.1, 0.25, 0.65], radius=0.05)


def test_panda_sphere_avoided(panda, panda_line):
    task, line = panda_line
    free = clik.Tracker(
        task,
        law="pseudoinverse",
        constraints=ConstraintSet(panda, obstacles=[BALL], obstacle_rows=False),
    )
    assert free.run(line).summary()["min_obstacle_distance"] < 0.0  # a link goes through it
    for jl in (None, JointLimits(panda, np.radians(5.0))):
        cs = ConstraintSet(panda, obstacles=[BALL], obstacle_threshold=0.05, joint_limits=jl)
        result = clik.Tracker(task, law="pseudoinverse", constraints=cs).run(line)
        assert result.status == "completed"
        assert_within_limits(result, panda, obstacle_floor=0.05 - 0.002)
        assert result.summary()["min_obstacle_distance"] >= 0.05 - 0.002
        assert result.max_task_error < 5e-3
        assert np.all(result.joint_min >= panda.lower) and np.all(result.joint_max <= panda.upper)
        assert result.extra["obstacle_distance"].shape == (3001, 1)


def test_panda_self_collision(panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    fold = Line(p0, [0.12, 0.0, 0.40], duration=3.0)  # folds the fingers into links 1-2
    monitor = ConstraintSet(
        panda, self_collision=True, obstacle_rows=False, max_active=0, self_threshold=0.01
    )
    assert monitor.scene is not None and len(monitor.scene.self_pairs) > 5
    free = clik.Tracker(task, law="pseudoinverse", constraints=monitor).run(fold)
    # The joint ranges too: without them the guarded fold passes joint 4's URDF limit.
    limits = JointLimits(panda, np.radians(2.0))
    rows = ConstraintSet(panda, self_collision=True, self_threshold=0.01, joint_limits=limits)
    guarded = clik.Tracker(task, law="pseudoinverse", constraints=rows).run(fold)
    free_min = self_min_distance(panda, rows.scene, free.q)
    guarded_min = self_min_distance(panda, rows.scene, guarded.q)
    assert free_min < 0.0  # unconstrained, the fingers go into the arm
    assert free.status == "violated"
    assert {v["constraint"].split(":")[0] for v in free.violations} == {"self"}
    assert guarded.status == "completed" and guarded.max_task_error < 1e-4
    assert guarded.violations == []
    assert np.all(guarded.q >= panda.lower - 1e-9) and np.all(guarded.q <= panda.upper + 1e-9)
    assert guarded_min >= 0.01 - 0.002
    assert any(e["constraint"].startswith("self:") for e in guarded.events)


def self_min_distance(robot, scene, qs):
    best = math.inf
    for q in qs[::10]:
        pin.framesForwardKinematics(robot.model, robot.data, q)
        scene.update(robot.data, 0.0)
        for pair, _, _ in scene.self_pairs:
            best = min(best, scene.distance(pair)[0])
    return best


def test_deadlock_is_detected_and_reported(tmp_path):
    from clik.cli import main

    scenario = __import__("pathlib").Path(__file__).parents[1] / "data" / "deadlock.toml"
    assert main(["solve", str(scenario), "--out", str(tmp_path / "o"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["status"] == "deadlock"
    assert "obstacle:pin:link4" in summary["reason"]
    assert summary["steps"] < 6501  # stopped before the end of the settle time


def test_summary_contract_for_obstacles(tmp_path):
    from clik.cli import main

    out = tmp_path / "o"
    assert main(["solve", str(scenario_path("case_study_both")), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["min_obstacle_distance"] == pytest.approx(
        summary["min_obstacle_distance_by_obstacle"]["pin"]
    )
    assert {e["action"] for e in summary["events"]} <= {"activate", "release", "skipped"}
    assert all(set(e) >= {"t", "constraint", "action"} for e in summary["events"])
    with np.load(out / "trajectory.npz") as npz:
        assert npz["min_obstacle_distance"].shape == (3001,)
        assert npz["min_obstacle_distance"].min() == pytest.approx(summary["min_obstacle_distance"])


@pytest.mark.parametrize("form", ["normalized", "squared"])
def test_penetration_still_pushes_out(planar4r, form):
    q = np.radians([180, -30, -90, -30])
    pin.framesForwardKinematics(planar4r.model, planar4r.data, q)
    a = planar4r.data.oMi[4].translation.copy()
    tip = planar4r.data.oMf[planar4r.frame_id("tip")].translation.copy()
    center = 0.5 * (a + tip) + np.array([0.004, 0.0, 0.0])  # 4 mm off link 4's axis
    scene = CollisionScene(planar4r, [Obstacle("ball", "sphere", center, radius=0.01)])
    e, row, _, dist = pair_error_and_row(planar4r, scene, q, 3, 0, form, 0.03)
    assert dist < 0.0  # the link is inside the ball
    # following the row (qdot = K j^T e, e > 0) lowers the error: the link moves out
    step = 1e-4 * row / np.linalg.norm(row)
    assert pair_error_and_row(planar4r, scene, q + step, 3, 0, form, 0.03)[0] < e
    rng = np.random.default_rng(3)
    for _ in range(3):
        dq = rng.normal(size=4)
        e_plus = pair_error_and_row(planar4r, scene, q + FD * dq, 3, 0, form, 0.03)[0]
        e_minus = pair_error_and_row(planar4r, scene, q - FD * dq, 3, 0, form, 0.03)[0]
        assert (e_plus - e_minus) / (2 * FD) == pytest.approx(-row @ dq, rel=1e-4, abs=1e-7)


def test_more_candidates_than_rows_are_skipped_and_logged(tmp_path):
    text = scenario_path("case_study_both_pinv").read_text()
    text = text.replace(
        "[constraints.obstacles]", "[constraints]\nmax_active = 1\n\n[constraints.obstacles]"
    )
    path = tmp_path / "one_row.toml"
    path.write_text(text)
    result = build(path).execute()  # one row only: the obstacle must wait for joint 3
    skipped = [e for e in result.events if e["action"] == "skipped"]
    assert skipped and skipped[0]["constraint"] == "obstacle:pin:link4"
    assert result.extra["active"].shape[1] == 1


def test_sign_rule_hysteresis_reduces_switching():
    counts = []
    for hysteresis in (0.0, 0.2):
        run = build(scenario_path("case_study_both_pinv"))
        run.tracker.constraints.release_rule = "sign"
        run.tracker.constraints.hysteresis = hysteresis
        counts.append(len(run.execute().events))
    assert counts[1] < counts[0]


def test_obstacles_move_and_change_between_runs(planar4r):
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180, -30, -90, -30])
    line = Line(task.placement(q0).translation, [0.8, -0.2, 0.0], duration=3.0, cruise_speed=0.12)
    cs = ConstraintSet(planar4r, obstacles=[Obstacle("pin", "sphere", [0.7, -0.28, 0], radius=0)])
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cs)
    near = tracker.run(line, q0).summary()["min_obstacle_distance"]
    cs.move_obstacle("pin", [0.7, -0.5, 0.0])
    far = tracker.run(line, q0).summary()["min_obstacle_distance"]
    assert far > near + 0.1
    cs.move_obstacle("pin", [0.7, -0.5, 0.0], velocity=[0.0, 0.07, 0.0])  # comes back in 3 s
    coming = tracker.run(line, q0).summary()["min_obstacle_distance"]
    assert coming < far - 0.1
    cs.move_obstacle("pin", [0.7, -0.5, 0.0], velocity=[0.0, 0.0, 0.0])
    assert tracker.run(line, q0).summary()["min_obstacle_distance"] == pytest.approx(far)
    cs.set_obstacles(
        [
            Obstacle("a", "sphere", [0.7, -0.28, 0], radius=0),
            Obstacle("b", "box", [0.3, 0.5, 0.0], size=[0.1, 0.1, 0.1]),
        ]
    )
    both = tracker.run(line, q0).summary()
    assert set(both["min_obstacle_distance_by_obstacle"]) == {"a", "b"}
    assert both["min_obstacle_distance_by_obstacle"]["a"] == pytest.approx(near, abs=1e-4)
