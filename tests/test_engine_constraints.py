"""The compiled constraint state (src/engine/constraints) against clik's ConstraintRun.

Each case runs the Python tracker with its own :class:`ConstraintRun` (made by
``_Run`` as always) and logs, per sample, what ``update`` was given (``q``, the
task rows, ``exact``, the record slot) and what it produced. The engine's
``constraint_trace`` then replays the same sequence through the C++
``ConstraintRun::update`` and must give the same rows, distances, events and
records, within 1e-9.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import clik
import clik.tracking as tracking
from clik.bench.step_lines import OBSTACLES_ONE_ACTIVE, PANDA_TRANSPOSE_GAIN
from clik.constraints import ConstraintSet, Dexterity, JointLimits, Obstacle
from clik.constraints.constraint_run import ConstraintRun
from clik.runner import build
from clik.scenarios import scenario_path
from clik.trajectory import Hold, Line, PoseTrajectory, Waypoints

engine = pytest.importorskip("clik._engine")

TOL = 1e-9


class _Logged(ConstraintRun):
    """The Python ConstraintRun, logging its inputs and outputs per sample."""

    last: _Logged | None = None

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        _Logged.last = self
        self.log: dict[str, list] = {
            k: []
            for k in (
                "q", "JT", "E", "FF", "exact", "slot", "v", "J", "e", "K", "ff",
                "min_distance", "dist_o", "link_o", "exact_o", "active", "penetrations",
                "manipulability",
            )
        }  # fmt: skip

    def update(self, k, q, ext, law, exact):
        log, m = self.log, self.m
        log["q"].append(np.array(q))
        log["JT"].append(ext.J[:m].copy())
        log["E"].append(ext.e[:m].copy())
        log["FF"].append(ext.ff[:m].copy())
        log["exact"].append(bool(exact))
        log["slot"].append(-1)
        v = super().update(k, q, ext, law, exact)
        log["v"].append(v)
        for key, arr in (("J", ext.J), ("e", ext.e), ("K", ext.K), ("ff", ext.ff)):
            log[key].append(arr[m : m + v].copy())
        log["min_distance"].append(self.min_distance)
        log["dist_o"].append(np.array(self.dist_o, dtype=float))
        log["link_o"].append(np.array(self.link_o, dtype=int))
        log["exact_o"].append(np.array(self.exact_o, dtype=bool))
        log["active"].append(self.active_names())
        log["penetrations"].append(list(self.self_penetrations))
        log["manipulability"].append(self.manipulability)
        return v

    def record(self, j):
        self.log["slot"][-1] = j
        super().record(j)


def python_run(monkeypatch, tracker, trajectory, q0=None, record_every=1, settle=0.0):
    monkeypatch.setattr(tracking, "ConstraintRun", _Logged)
    if hasattr(tracker, "engine"):  # the reference is the Python loop, whatever the default
        monkeypatch.setattr(tracker, "engine", "python")
    _Logged.last = None
    result = tracker.run(trajectory, q0, record_every=record_every, settle=settle)
    crun = _Logged.last
    assert crun is not None
    return result, crun


def engine_run(tracker, crun):
    log, m, nv = crun.log, crun.m, tracker.robot.nv
    n = len(log["q"])
    config = engine.ConstraintConfig.from_set(crun.cset)
    return engine.constraint_trace(
        tracker.robot.model,
        config,
        m,
        tracker.law,
        tracker.alpha,
        crun.t,
        crun.rec_dist.shape[0],
        tracker.damping,
        tracker.dt,
        tracker.beta_max,
        np.asarray(tracker.K_task, dtype=float),
        np.array(log["q"]),
        np.concatenate(log["JT"]).reshape(n * m, nv),
        np.array(log["E"]).reshape(n, m),
        np.array(log["FF"]).reshape(n, m),
        log["exact"],
        log["slot"],
        crun.frame_id,
        [int(r) for r in crun.task_rows],
    )


def close(a, b, what):
    np.testing.assert_allclose(a, b, rtol=0.0, atol=TOL, err_msg=what)


def assert_same(result, crun, out):
    """Per sample and per run, the engine's ConstraintRun is the Python one."""
    log = crun.log
    n = len(log["q"])
    assert out["limit"] == crun.limit
    np.testing.assert_array_equal(out["v"], log["v"])
    for k in range(n):
        v = log["v"][k]
        assert out["active_names"][k] == log["active"][k], f"sample {k}"
        close(out["J"][k, :v], log["J"][k], f"J rows, sample {k}")
        for key in ("e", "K", "ff"):
            close(out[key][k, :v], log[key][k], f"{key}, sample {k}")
        pen = out["self_penetrations"][k]
        assert [p[0] for p in pen] == [p[0] for p in log["penetrations"][k]], f"sample {k}"
        close([p[1] for p in pen], [p[1] for p in log["penetrations"][k]], f"sample {k}")
    close(out["min_distance"], log["min_distance"], "min_distance")
    close(out["manipulability"], log["manipulability"], "manipulability")  # NaN: no row
    if crun.cset.obstacles:
        close(out["dist_o"], np.array(log["dist_o"]), "dist_o")
        np.testing.assert_array_equal(out["link_o"], np.array(log["link_o"]))
        np.testing.assert_array_equal(out["exact_o"].astype(bool), np.array(log["exact_o"]))
    rec = out["records"]
    assert rec["events"] == crun.events
    assert rec["events"] == result.events
    assert rec["constraint_names"] == result.info["constraint_names"]
    np.testing.assert_array_equal(rec["active"], crun.rec_active)
    close(rec["witness"], crun.rec_witness, "witness")
    assert rec["skipped"] == crun.skipped_names()
    extra = result.info["summary_extra"]
    if crun.cset.obstacles:
        close(rec["obstacle_distance"], crun.rec_dist, "obstacle_distance")
        np.testing.assert_array_equal(rec["obstacle_link"], crun.rec_link)
        assert rec["obstacle_link"].dtype == np.int16
        close(rec["min_obstacle_distance"], extra["min_obstacle_distance"], "min distance")
        for key in (
            "min_obstacle_distance_by_obstacle",
            "min_obstacle_distance_time_by_obstacle",
        ):
            assert rec[key].keys() == extra[key].keys()
            close(list(rec[key].values()), list(extra[key].values()), key)
        for key in (
            "min_obstacle_distance_link_by_obstacle",
            "min_obstacle_distance_exact_by_obstacle",
        ):
            assert rec[key] == extra[key]
    else:
        assert rec["min_obstacle_distance"] is None


def check(monkeypatch, tracker, trajectory, q0=None, record_every=1, settle=0.0):
    result, crun = python_run(monkeypatch, tracker, trajectory, q0, record_every, settle)
    out = engine_run(tracker, crun)
    assert_same(result, crun, out)
    return result, crun


def actions(events, prefix=""):
    return [e["action"] for e in events if e["constraint"].startswith(prefix)]


# -- the case study --------------------------------------------------------------------


def scenario_case(name, **changes):
    run = build(scenario_path(name))
    cset = run.tracker.constraints
    for key, value in changes.items():
        setattr(cset, key, value)
    return run


@pytest.mark.parametrize("record_every", [1, 7])
@pytest.mark.parametrize("name", ["case_study_both_pinv", "case_study_both"])
def test_case_study(monkeypatch, name, record_every):
    run = scenario_case(name)
    settle = run.scenario.solver["settle"]
    result, crun = check(monkeypatch, run.tracker, run.trajectory, run.q0, record_every, settle)
    assert "activate" in actions(result.events, "obstacle")
    assert "release" in actions(result.events, "joint")
    if record_every > 1:  # the certificates kept some obstacle distances as lower bounds
        assert not all(all(e) for e in crun.log["exact_o"])


@pytest.mark.parametrize("hysteresis", [0.0, 0.05])
def test_case_study_sign_release(monkeypatch, hysteresis):
    run = scenario_case("case_study_both_pinv", release_rule="sign", hysteresis=hysteresis)
    result, _ = check(monkeypatch, run.tracker, run.trajectory, run.q0)
    releases = actions(result.events).count("release")
    if hysteresis == 0.0:
        assert releases > 2  # the sign rule chatters
    else:
        assert releases == 0  # the hysteresis holds the rows at their thresholds


@pytest.mark.parametrize("law", ["pseudoinverse", "transpose"])
def test_case_study_squared_form(monkeypatch, law):
    run = scenario_case("case_study_both_pinv", form="squared")
    tracker = clik.Tracker(
        run.task, law=law, gain=1000.0, dt=1e-3, constraints=run.tracker.constraints
    )
    result, _ = check(monkeypatch, tracker, run.trajectory, run.q0)
    assert "activate" in actions(result.events, "obstacle")


def test_case_study_nonlinear_law_with_gains(monkeypatch):
    run = scenario_case("case_study_both")
    cset = run.tracker.constraints
    cset.gains = {"obstacle": 300.0, "joint": None, "self": None}
    tracker = clik.Tracker(run.task, law="nonlinear", gain=1000.0, dt=1e-3, constraints=cset)
    result, _ = check(monkeypatch, tracker, run.trajectory, run.q0, record_every=3)
    assert "activate" in actions(result.events, "obstacle")


@pytest.mark.parametrize("form", ["normalized", "squared"])
def test_moving_obstacle(monkeypatch, form):
    run = scenario_case("case_study_both_pinv", form=form)
    cset = run.tracker.constraints
    cset.move_obstacle("pin", [0.62, -0.36, 0.0], velocity=[0.03, 0.03, 0.0])
    result, crun = check(monkeypatch, run.tracker, run.trajectory, run.q0, record_every=4)
    assert "activate" in actions(result.events, "obstacle")
    assert crun._obs_step is not None
    active_ff = [ff for ff in crun.log["ff"] if ff.size and np.any(ff != 0.0)]
    assert active_ff  # the moving obstacle's feed-forward (14) reached the rows


@pytest.mark.parametrize("name", ["case_study_both", "case_study_both_pinv"])
def test_row_limit_skips(monkeypatch, name):
    run = scenario_case(name, max_active=1)  # the joint row and the obstacle row compete
    result, crun = check(monkeypatch, run.tracker, run.trajectory, run.q0)
    assert crun.limit == 1 and "skipped" in actions(result.events)


def test_obstacle_pushing_the_arm_releases_inner_rows(monkeypatch):
    run = scenario_case("case_study_both_pinv")
    run.tracker.constraints.move_obstacle("pin", [0.62, -0.36, 0.0], velocity=[-0.3, 0.2, 0.0])
    swaps = []
    swap = tracking.ExtendedTask.swap
    monkeypatch.setattr(
        tracking.ExtendedTask, "swap", lambda ext, a, b: (swaps.append((a, b)), swap(ext, a, b))
    )
    result, _ = check(monkeypatch, run.tracker, run.trajectory, run.q0, record_every=3)
    assert swaps  # the projection rule moved a row that was not last
    assert actions(result.events, "obstacle").count("activate") > 1


@pytest.mark.parametrize("velocity", [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0]])
@pytest.mark.parametrize("form", ["normalized", "squared"])
def test_obstacle_inside_a_link(monkeypatch, form, velocity):
    """Rows in contact and penetration: n along coal's normal, s|s| in the squared form."""
    run = scenario_case("case_study_both_pinv", form=form)
    robot = run.robot
    pin.framesForwardKinematics(robot.model, robot.data, run.q0)
    centre = 0.5 * (robot.data.oMi[3].translation + robot.data.oMi[4].translation)
    cset = run.tracker.constraints
    cset.set_obstacles([Obstacle("blob", "sphere", centre, velocity=velocity, radius=0.01)])
    _, crun = check(monkeypatch, run.tracker, run.trajectory, run.q0, record_every=2)
    assert min(crun.log["min_distance"]) < 0.0
    at_surface = 0.03 if form == "normalized" else 0.5 * 0.03**2  # e_o at distance 0
    assert any(e.size and e.max() > at_surface for e in crun.log["e"])  # a row inside it


# -- the Panda -------------------------------------------------------------------------


def panda_spheres(robot, centres, radius=0.05):
    return [Obstacle(f"sphere{i}", "sphere", c, radius=radius) for i, c in enumerate(centres)]


@pytest.mark.parametrize(
    ("law", "record_every"), [("pseudoinverse", 1), ("pseudoinverse", 10), ("transpose", 5)]
)
def test_panda_three_spheres_and_joint_ranges(monkeypatch, law, record_every):
    run = build(scenario_path("panda_circle"))
    robot = run.robot
    cset = ConstraintSet(
        robot,
        obstacles=panda_spheres(robot, OBSTACLES_ONE_ACTIVE),
        joint_limits=JointLimits(robot, np.radians(5.0)),
    )
    gain = 1000.0 if law == "pseudoinverse" else PANDA_TRANSPOSE_GAIN
    tracker = clik.Tracker(run.task, law=law, gain=gain, dt=1e-3, constraints=cset)
    result, crun = check(monkeypatch, tracker, run.trajectory, run.q0, record_every)
    assert "activate" in actions(result.events, "obstacle")
    assert len(crun.cset.obstacles) == 3


def test_panda_line_through_spheres(monkeypatch, panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    line = Line(p0, p0 + [0.0, 0.35, -0.1], duration=3.0)
    centres = ([0.1, 0.25, 0.65], [0.35, 0.12, 0.5], [0.2, -0.15, 0.45])
    cset = ConstraintSet(
        panda,
        obstacles=panda_spheres(panda, centres),
        obstacle_threshold=0.05,
        joint_limits=JointLimits(panda, np.radians(5.0)),
        max_active=2,
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, _ = check(monkeypatch, tracker, line, record_every=6)
    assert "activate" in actions(result.events, "obstacle")


def test_panda_monitor_only(monkeypatch, panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    line = Line(p0, p0 + [0.0, 0.35, -0.1], duration=1.5)
    ball = Obstacle("ball", "sphere", [0.1, 0.25, 0.65], radius=0.05)
    cset = ConstraintSet(panda, obstacles=[ball], obstacle_rows=False)
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, crun = check(monkeypatch, tracker, line, record_every=9)
    assert result.summary()["min_obstacle_distance"] < 0.0  # a link goes through it
    assert crun.events == []


@pytest.mark.parametrize("release", ["projection", "sign"])
def test_panda_self_collision(monkeypatch, panda, release):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    fold = Line(p0, [0.12, 0.0, 0.40], duration=3.0)  # folds the fingers into links 1-2
    limits = JointLimits(panda, np.radians(2.0))
    cset = ConstraintSet(
        panda, self_collision=True, self_threshold=0.01, joint_limits=limits, release=release
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, _ = check(monkeypatch, tracker, fold, record_every=5)
    assert "activate" in actions(result.events, "self:")


def test_panda_self_collision_monitor(monkeypatch, panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    fold = Line(p0, [0.12, 0.0, 0.40], duration=3.0)
    cset = ConstraintSet(
        panda, self_collision=True, obstacle_rows=False, max_active=0, self_threshold=0.01
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, crun = check(monkeypatch, tracker, fold, record_every=5)
    assert any(crun.log["penetrations"])  # the fingers go into the arm
    assert "skipped" in actions(result.events, "self:")


# -- the dexterity row -----------------------------------------------------------------


@pytest.mark.parametrize("record_every", [1, 5])
def test_dexterity_scenario(monkeypatch, record_every):
    """The case-study arm stretched past its reach, law (9) (case_study_dexterity)."""
    run = scenario_case("case_study_dexterity")
    with pytest.warns(tracking.ReachWarning):
        result, crun = check(monkeypatch, run.tracker, run.trajectory, run.q0, record_every)
    assert actions(result.events, "dexterity") == ["activate", "release"]
    assert np.isfinite(crun.log["manipulability"]).all()


@pytest.mark.parametrize("release", ["projection", "sign"])
def test_dexterity_pseudoinverse_with_joint_ranges(monkeypatch, planar4r, release):
    """Law (10), the tip out near the edge of the reach and back; the row and joint ranges."""
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    turn = [1.195 * np.cos(np.radians(-10.0)), 1.195 * np.sin(np.radians(-10.0)), 0.0]
    trajectory = Waypoints([p0, turn, p0], cruise_speed=0.2, accel_time=0.3)
    cset = ConstraintSet(
        planar4r, dexterity=Dexterity(0.08), joint_limits=JointLimits(planar4r), release=release
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, _ = check(monkeypatch, tracker, trajectory, q0, record_every=3)
    assert "activate" in actions(result.events, "dexterity")


def test_dexterity_panda_pose(monkeypatch, panda):
    """The Panda's pose task near the singularity of joints 1 and 3 aligned (q2 = 0)."""
    task = clik.Task(panda, "panda_hand", "pose")
    q0 = np.array([-0.02, -0.18, 0.97, -1.13, -0.51, 2.78, -1.31])
    M = task.placement(q0)
    line = Line(M.translation, M.translation + [0.1, 0.165, -0.165], 2.0)
    trajectory = PoseTrajectory(line, Hold(rotation=M.rotation, duration=2.0))
    cset = ConstraintSet(panda, dexterity=Dexterity(0.012), dexterity_gain=500.0)
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result, _ = check(monkeypatch, tracker, trajectory, q0, record_every=4)
    assert "activate" in actions(result.events, "dexterity")


# -- set-up pieces ---------------------------------------------------------------------


def test_config_from_set(panda):
    cset = ConstraintSet(
        panda,
        obstacles=panda_spheres(panda, OBSTACLES_ONE_ACTIVE),
        self_collision=True,
        joint_limits=JointLimits(panda),
    )
    config = engine.ConstraintConfig.from_set(cset)
    assert config.n_obstacles == 3
    assert config.n_links == cset.scene.n_links
    assert config.n_self == len(cset.scene.self_pairs)
    assert config.link_labels == cset.link_labels
    np.testing.assert_allclose(config.rho, cset.rho, rtol=1e-14, atol=0.0)  # motion_bounds
    for m in (3, 6):
        for law in ("transpose", "pseudoinverse"):
            assert config.row_limit(m, law) == cset.row_limit(m, law)
    del cset  # the config keeps the scene's GeometryModel alive
    import gc

    gc.collect()
    assert config.n_links > 0


def test_joint_ranges(panda, planar4r):
    for robot, override in ((panda, None), (planar4r, {"joint3": {"upper": np.radians(-80.0)}})):
        jl = JointLimits(robot, np.radians(2.0), override)
        config = engine.ConstraintConfig.from_set(ConstraintSet(robot, joint_limits=jl))
        rng = np.random.default_rng(3)
        for _ in range(20):
            q = rng.uniform(robot.lower - 0.1, robot.upper + 0.1)
            e, excursion, rows = config.joint_limit_rows(q)
            close(e, jl.evaluate(q), "evaluate")
            close(excursion, jl.excursion(q), "excursion")
        expected = np.zeros((2 * jl.n, robot.nv))
        for i in range(2 * jl.n):
            jl.row(i, expected[i])
        np.testing.assert_array_equal(rows, expected)
