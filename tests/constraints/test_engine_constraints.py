"""The compiled constraint core and kinds (src/engine/constraints) against clik's.

Each case runs the same tracking run in both engines (``engine="python"``, whose
:class:`~clik.constraints.constraint_run.ConstraintRun` is the specification, and
``engine="compiled"``) and compares what the constraints did: statuses, reasons,
events, constraint names, the active rows' codes and witness points, the obstacles'
distances and links, the minimum distances, the summaries (manipulability included)
and the joint trajectories, within 1e-9. The typed configs the engine is given
(``_engine.ConstraintSetConfig`` and the kinds') are checked against the set, and
refuse bad sizes.
"""

from __future__ import annotations

import gc
import re
import sys
import warnings

import numpy as np
import pinocchio as pin
import pytest

import clik
from benchmarks.step_lines import OBSTACLES_ONE_ACTIVE, PANDA_TRANSPOSE_GAIN
from clik.constraints import ConstraintSet, Dexterity, JointLimits, Obstacle
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.scenarios.scenario import parse_scenario
from clik.tasks.extended_task import ExtendedTask
from clik.trajectory import Hold, Line, PoseTrajectory, Waypoints

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

engine = pytest.importorskip("clik._engine")

TOL = 1e-9
"""Largest difference between the engines [rad, m, or the quantity's unit]."""

COAL_TOL = 1e-6
"""Largest difference after coal's witness points parted (see :func:`assert_same`)."""

DEADLOCK_WINDOW = 0.1
"""A deadlock is blocked this long [s] before its stop (StopSettings.deadlock_window)."""

DEADLOCK_STEPS = 2
"""Largest difference of a deadlock's stop sample between the engines (as in
test_engine_tracking: the blocked fraction hovers about its threshold)."""


def close(a, b, what, tol=TOL):
    np.testing.assert_allclose(a, b, rtol=0.0, atol=tol, err_msg=what)


def runs(tracker, trajectory, q0=None, record_every=1, settle=0.0):
    """The same run in each engine: (python, compiled)."""
    out = []
    for name in ("python", "compiled"):
        tracker.engine = name
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out.append(tracker.run(trajectory, q0, record_every=record_every, settle=settle))
    return tuple(out)


def same(x, y, what):
    """Equal values: numbers (and lists, arrays of them) within TOL, the rest exactly."""
    if isinstance(x, dict):
        assert isinstance(y, dict) and x.keys() == y.keys(), what
        for key in x:
            same(x[key], y[key], f"{what}.{key}")
    elif isinstance(x, float | np.ndarray) or (
        isinstance(x, list) and x and all(isinstance(v, float) for v in x)
    ):
        close(np.asarray(x, dtype=float), np.asarray(y, dtype=float), what)
    elif isinstance(x, list):
        assert isinstance(y, list) and len(x) == len(y), what
        for i, (u, v) in enumerate(zip(x, y, strict=True)):
            same(u, v, f"{what}[{i}]")
    else:
        assert x == y, what


def assert_same_summary(a, b):
    """Summaries equal but for the wall time and the engine's name."""
    sa, sb = a.summary(), b.summary()
    for summary in (sa, sb):
        summary.pop("info")
        for key in [k for k in summary if k.startswith("wall")]:
            summary.pop(key)
    same(sa, sb, "summary")


def words(reason):
    """A reason without its numbers (a deadlock's error differs in the last digits)."""
    return re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", reason)


def assert_same(a, b, until=None):
    """What the constraints did, and the run they did it in, agree.

    Per recorded sample (trajectories, distances, witness points, active codes) within
    :data:`TOL` up to ``until`` [s] (None: the end). Two things end that agreement, each
    where the engines' rounding (1e-16) meets an amplifier: a deadlock (the law's filtered
    inverse chatters over its window; as in test_engine_tracking, samples before the
    window are compared), and coal, which finds a witness point only to within its GJK
    tolerance, ``sqrt(tol r)``: where a hull's nearest feature changes, the two engines'
    1e-16 apart configurations can take different GJK paths (measured: 2.9e-6 m on the
    Panda's link 3, then 3e-8 rad in ``q``). After ``until``: the same events and status,
    trajectories within :data:`COAL_TOL`.
    """
    assert a.info["engine"] == "python" and b.info["engine"] == "compiled"
    assert a.status == b.status
    n = len(a.t) if until is None else int(np.searchsorted(a.t, until))
    if a.status == "deadlock":
        n = min(n, int(np.searchsorted(a.t, a.t[-1] - DEADLOCK_WINDOW)))
        assert abs(a.steps - b.steps) <= DEADLOCK_STEPS
        assert words(a.reason) == words(b.reason)
    else:
        assert (a.reason, a.steps) == (b.reason, b.steps)
        assert a.events == b.events
    full = n == len(a.t)
    used = int(a.extra["active"][:n].max(initial=-1)) + 1  # the codes of the compared samples
    assert a.info["constraint_names"][:used] == b.info["constraint_names"][:used]
    assert [v["constraint"] for v in a.violations] == [v["constraint"] for v in b.violations]
    for va, vb in zip(a.violations, b.violations, strict=True):
        assert va["t_first"] == vb["t_first"]
        if full:
            assert va["t_last"] == vb["t_last"]
            close(va["worst"], vb["worst"], "violation depth")
    np.testing.assert_array_equal(a.t[:n], b.t[:n])
    np.testing.assert_array_equal(a.extra["active"][:n], b.extra["active"][:n])
    assert b.extra["active"].dtype == np.int32
    close(a.extra["witness"][:n], b.extra["witness"][:n], "witness points")  # NaN: none
    assert ("obstacle_distance" in a.extra) == ("obstacle_distance" in b.extra)
    if "obstacle_distance" in a.extra:
        distance = (a.extra["obstacle_distance"][:n], b.extra["obstacle_distance"][:n])
        close(*distance, "obstacle distances")
        np.testing.assert_array_equal(a.extra["obstacle_link"][:n], b.extra["obstacle_link"][:n])
        assert b.extra["obstacle_link"].dtype == np.int16
    np.testing.assert_array_equal(a.active_count[:n], b.active_count[:n])
    close(a.min_obstacle_distance[:n], b.min_obstacle_distance[:n], "minimum distance")
    dt = float(a.info["dt"])
    close(a.q[:n], b.q[:n], "q")
    close(a.qdot[:n] * dt, b.qdot[:n] * dt, "qdot dt")
    if full:
        assert a.info["constraint_names"] == b.info["constraint_names"]
        assert_same_summary(a, b)
    elif a.status != "deadlock":
        assert a.info["constraint_names"] == b.info["constraint_names"]
        close(a.q, b.q, "q after coal parted", COAL_TOL)


def check(tracker, trajectory, q0=None, record_every=1, settle=0.0, until=None):
    a, b = runs(tracker, trajectory, q0, record_every, settle)
    assert_same(a, b, until)
    return a


def actions(events, prefix=""):
    return [e["action"] for e in events if e["constraint"].startswith(prefix)]


# -- the case study --------------------------------------------------------------------


def scenario_case(name, constraints=None, obstacles=None):
    """A shipped scenario, its ``[constraints]`` and ``[constraints.obstacles]`` changed."""
    path = scenario_path(name)
    data = tomllib.loads(path.read_text())
    data.setdefault("constraints", {}).update(constraints or {})
    if obstacles:
        data["constraints"].setdefault("obstacles", {}).update(obstacles)
    return build(parse_scenario(data, path))


@pytest.mark.parametrize("record_every", [1, 7])
@pytest.mark.parametrize("name", ["case_study_both_pinv", "case_study_both"])
def test_case_study(name, record_every):
    run = scenario_case(name)
    settle = run.scenario.solver["settle"]
    result = check(run.tracker, run.trajectory, run.q0, record_every, settle)
    assert "activate" in actions(result.events, "obstacle")
    assert "release" in actions(result.events, "joint")


@pytest.mark.parametrize("hysteresis", [0.0, 0.05])
def test_case_study_sign_release(hysteresis):
    run = scenario_case(
        "case_study_both_pinv", constraints={"release": "sign", "hysteresis": hysteresis}
    )
    result = check(run.tracker, run.trajectory, run.q0)
    releases = actions(result.events).count("release")
    if hysteresis == 0.0:
        assert releases > 2  # the sign rule chatters
    else:
        assert releases == 0  # the hysteresis holds the rows at their thresholds


@pytest.mark.parametrize("law", ["pseudoinverse", "transpose"])
def test_case_study_squared_form(law):
    run = scenario_case("case_study_both_pinv", obstacles={"form": "squared"})
    tracker = clik.Tracker(
        run.task, law=law, gain=1000.0, dt=1e-3, constraints=run.tracker.constraints
    )
    result = check(tracker, run.trajectory, run.q0)
    assert "activate" in actions(result.events, "obstacle")


def test_case_study_nonlinear_law_with_gains():
    run = scenario_case("case_study_both", obstacles={"gain": 300.0})
    cset = run.tracker.constraints
    tracker = clik.Tracker(run.task, law="nonlinear", gain=1000.0, dt=1e-3, constraints=cset)
    result = check(tracker, run.trajectory, run.q0, record_every=3)
    assert "activate" in actions(result.events, "obstacle")


@pytest.mark.parametrize("form", ["normalized", "squared"])
def test_moving_obstacle(form):
    run = scenario_case("case_study_both_pinv", obstacles={"form": form})
    cset = run.tracker.constraints
    still = check(run.tracker, run.trajectory, run.q0, record_every=4)
    cset.move_obstacle("pin", [0.62, -0.36, 0.0], velocity=[0.03, 0.03, 0.0])
    result = check(run.tracker, run.trajectory, run.q0, record_every=4)
    assert "activate" in actions(result.events, "obstacle")
    assert result.events != still.events  # the obstacle moved, and its rows' feed-forward (14)


@pytest.mark.parametrize("name", ["case_study_both", "case_study_both_pinv"])
def test_row_limit_skips(name):
    run = scenario_case(name, constraints={"max_active": 1})  # joint and obstacle rows compete
    result = check(run.tracker, run.trajectory, run.q0)
    assert "skipped" in actions(result.events)


def test_obstacle_pushing_the_arm_releases_inner_rows(monkeypatch):
    run = scenario_case("case_study_both_pinv")
    run.tracker.constraints.move_obstacle("pin", [0.62, -0.36, 0.0], velocity=[-0.3, 0.2, 0.0])
    swaps = []
    swap = ExtendedTask.swap
    monkeypatch.setattr(
        ExtendedTask, "swap", lambda ext, a, b: (swaps.append((a, b)), swap(ext, a, b))
    )
    result = check(run.tracker, run.trajectory, run.q0, record_every=3)
    assert swaps  # the projection rule moved a row that was not last (the Python run)
    assert actions(result.events, "obstacle").count("activate") > 1


@pytest.mark.parametrize("velocity", [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0]])
@pytest.mark.parametrize("form", ["normalized", "squared"])
def test_obstacle_inside_a_link(form, velocity):
    """Rows in contact and penetration: n along coal's normal, s|s| in the squared form."""
    run = scenario_case("case_study_both_pinv", obstacles={"form": form})
    robot = run.robot
    pin.framesForwardKinematics(robot.model, robot.data, run.q0)
    centre = 0.5 * (robot.data.oMi[3].translation + robot.data.oMi[4].translation)
    cset = run.tracker.constraints
    cset.set_obstacles([Obstacle("blob", "sphere", centre, velocity=velocity, radius=0.01)])
    # From 2.01 s links 2 and 3 are equally near the blob (within 1e-15 m) while the row
    # passes from one to the other: which is "nearest" there is the engines' rounding.
    result = check(run.tracker, run.trajectory, run.q0, record_every=2, until=2.0)
    assert result.summary()["min_obstacle_distance"] < 0.0
    assert any(v["constraint"].startswith("obstacle:blob:") for v in result.violations)


# -- the Panda -------------------------------------------------------------------------


def panda_spheres(centres, radius=0.05):
    return [Obstacle(f"sphere{i}", "sphere", c, radius=radius) for i, c in enumerate(centres)]


@pytest.mark.parametrize(
    ("law", "record_every"), [("pseudoinverse", 1), ("pseudoinverse", 10), ("transpose", 5)]
)
def test_panda_three_spheres_and_joint_ranges(law, record_every):
    run = build(scenario_path("panda_circle"))
    robot = run.robot
    cset = ConstraintSet(
        robot,
        obstacles=panda_spheres(OBSTACLES_ONE_ACTIVE),
        joint_limits=JointLimits(robot, np.radians(5.0)),
    )
    gain = 1000.0 if law == "pseudoinverse" else PANDA_TRANSPOSE_GAIN
    tracker = clik.Tracker(run.task, law=law, gain=gain, dt=1e-3, constraints=cset)
    until = 0.75 if law == "transpose" else None  # coal parts at 0.758 s (assert_same)
    result = check(tracker, run.trajectory, run.q0, record_every, until=until)
    assert "activate" in actions(result.events, "obstacle")
    assert len(result.summary()["min_obstacle_distance_by_obstacle"]) == 3


def panda_line(panda, offset, duration):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    return task, Line(p0, p0 + np.asarray(offset), duration=duration)


def test_panda_line_through_spheres(panda):
    task, line = panda_line(panda, [0.0, 0.35, -0.1], 3.0)
    centres = ([0.1, 0.25, 0.65], [0.35, 0.12, 0.5], [0.2, -0.15, 0.45])
    cset = ConstraintSet(
        panda,
        obstacles=panda_spheres(centres),
        obstacle_threshold=0.05,
        joint_limits=JointLimits(panda, np.radians(5.0)),
        max_active=2,
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result = check(tracker, line, record_every=6)
    assert "activate" in actions(result.events, "obstacle")


def test_panda_monitor_only(panda):
    task, line = panda_line(panda, [0.0, 0.35, -0.1], 1.5)
    ball = Obstacle("ball", "sphere", [0.1, 0.25, 0.65], radius=0.05)
    cset = ConstraintSet(panda, obstacles=[ball], obstacle_rows=False)
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result = check(tracker, line, record_every=9)
    assert result.summary()["min_obstacle_distance"] < 0.0  # a link goes through it
    assert result.events == []


def panda_fold(panda):
    task = clik.Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    return task, Line(p0, [0.12, 0.0, 0.40], duration=3.0)  # folds the fingers into links 1-2


@pytest.mark.parametrize("release", ["projection", "sign"])
def test_panda_self_collision(panda, release):
    task, fold = panda_fold(panda)
    limits = JointLimits(panda, np.radians(2.0))
    cset = ConstraintSet(
        panda, self_collision=True, self_threshold=0.01, joint_limits=limits, release=release
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result = check(tracker, fold, record_every=5)
    assert "activate" in actions(result.events, "self:")


def test_panda_self_collision_monitor(panda):
    task, fold = panda_fold(panda)
    cset = ConstraintSet(
        panda, self_collision=True, obstacle_rows=False, max_active=0, self_threshold=0.01
    )
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result = check(tracker, fold, record_every=5)
    assert any(v["constraint"].startswith("self:") for v in result.violations)  # fingers in
    assert "skipped" in actions(result.events, "self:")


# -- the dexterity row -----------------------------------------------------------------


@pytest.mark.parametrize("record_every", [1, 5])
def test_dexterity_scenario(record_every):
    """The case-study arm stretched past its reach, law (9) (case_study_dexterity)."""
    run = scenario_case("case_study_dexterity")
    result = check(run.tracker, run.trajectory, run.q0, record_every)
    assert actions(result.events, "dexterity") == ["activate", "release"]
    assert np.isfinite(result.summary()["min_manipulability"])


@pytest.mark.parametrize("release", ["projection", "sign"])
def test_dexterity_pseudoinverse_with_joint_ranges(planar4r, release):
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
    result = check(tracker, trajectory, q0, record_every=3)
    assert "activate" in actions(result.events, "dexterity")


def test_dexterity_panda_pose(panda):
    """The Panda's pose task near the singularity of joints 1 and 3 aligned (q2 = 0)."""
    task = clik.Task(panda, "panda_hand", "pose")
    q0 = np.array([-0.02, -0.18, 0.97, -1.13, -0.51, 2.78, -1.31])
    M = task.placement(q0)
    line = Line(M.translation, M.translation + [0.1, 0.165, -0.165], 2.0)
    trajectory = PoseTrajectory(line, Hold(rotation=M.rotation, duration=2.0))
    cset = ConstraintSet(panda, dexterity=Dexterity(0.012), dexterity_gain=500.0)
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset)
    result = check(tracker, trajectory, q0, record_every=4)
    assert "activate" in actions(result.events, "dexterity")


# -- the typed configs -----------------------------------------------------------------


def full_set(panda):
    return ConstraintSet(
        panda,
        obstacles=panda_spheres(OBSTACLES_ONE_ACTIVE),
        self_collision=True,
        joint_limits=JointLimits(panda),
        dexterity=Dexterity(0.01),
        obstacle_gain=200.0,
    )


def test_engine_config_mirrors_the_set(panda):
    cset = full_set(panda)
    config = cset.engine_config()
    kinds = config.kinds
    assert [type(k).__name__ for k in kinds] == [
        "JointRangeConfig", "ObstacleRowsConfig", "LinkPairsConfig", "DexterityConfig",
    ]  # fmt: skip
    joint, obstacles, pairs, dexterity = kinds
    assert joint.names == list(cset.joint_limits.names) and joint.gain is None
    np.testing.assert_array_equal(joint.row_threshold, cset.joint_limits.row_threshold)
    assert [o.name for o in obstacles.obstacles] == [o.name for o in cset.obstacles]
    assert obstacles.gain == 200.0 and obstacles.form == "normalized" and obstacles.rows
    # No geometry index given: the engine takes the one the scene's collision pairs name.
    assert [o.geometry for o in obstacles.obstacles] == [-1] * 3
    assert pairs.threshold == cset.self_threshold and dexterity.threshold == 0.01
    scene = config.scene
    assert scene.n_links == cset.scene.n_links and scene.link_labels == cset.link_labels
    assert scene.self_pairs == [tuple(int(v) for v in p) for p in cset.scene.self_pairs]
    np.testing.assert_array_equal(scene.obstacle_pairs, cset.scene.obstacle_pairs)
    np.testing.assert_allclose(config.rho, cset.scene.motion_bounds(), rtol=1e-14, atol=0.0)
    assert config.release == "projection" and config.max_active is None
    for m in (3, 6):
        for law in ("transpose", "pseudoinverse"):
            assert config.row_limit(m, law) == cset.row_limit(m, law)
    default = [  # without a geometry index: the one the scene's pairs name
        engine.ObstacleConfig(
            name=o.name, position=o.position, rotation=o.rotation, velocity=o.velocity,
            threshold=o.threshold,
        )
        for o in obstacles.obstacles
    ]  # fmt: skip
    assert [o.geometry for o in default] == [-1] * 3
    engine.ConstraintSetConfig(
        model=panda.model, kinds=[engine.ObstacleRowsConfig(obstacles=default, rows=True,
        form="normalized")], scene=scene, release="sign", hysteresis=0.0, max_active=None,
        monitor_margin=0.1,
    )  # fmt: skip
    gmodel = scene.gmodel
    del cset, scene
    gc.collect()
    assert config.scene.gmodel is gmodel  # the config keeps the GeometryModel alive
    assert config.scene.n_links == len(config.scene.link_labels)


def test_kinds_follow_the_set(panda, planar4r):
    plain = ConstraintSet(planar4r).engine_config()
    assert [type(k).__name__ for k in plain.kinds] == ["ObstacleRowsConfig"]
    assert plain.scene is None and plain.rho is None
    with pytest.raises(ValueError, match="redundant task"):
        plain.row_limit(4, "transpose")  # obstacle rows wanted, no free row


def test_configs_refuse_bad_sizes(panda):
    with pytest.raises(ValueError, match="one entry per limited joint"):
        engine.JointRangeConfig(
            q_index=[0, 1], v_index=[0], lower=np.zeros(2), upper=np.ones(2),
            threshold=np.full(2, 0.1), joint_names=["a", "b"], names=["a", "b", "c", "d"],
            row_threshold=np.full(4, 0.1), sign=np.array([1.0, 1.0, -1.0, -1.0]),
        )  # fmt: skip
    with pytest.raises(ValueError, match="'normalized' or 'squared'"):
        engine.ObstacleRowsConfig(obstacles=[], rows=True, form="cubic")
    with pytest.raises(ValueError, match="positive threshold"):
        engine.DexterityConfig(threshold=-1.0)
    cset = full_set(panda)
    good = cset.engine_config()
    scene = cset.scene
    with pytest.raises(ValueError, match="one entry \\(row\\) per link geometry"):
        engine.SceneConfig(
            gmodel=scene.gmodel, n_links=scene.n_links, link_joint=[0],
            local_radius=scene.local_radius, obstacle_pairs=good.scene.obstacle_pairs,
            self_pairs=[], link_labels=cset.link_labels,
        )  # fmt: skip
    with pytest.raises(ValueError, match=r"expected a pin\.GeometryModel"):
        engine.SceneConfig(
            gmodel=object(), n_links=0, link_joint=[], local_radius=np.zeros(0),
            obstacle_pairs=np.zeros((0, 0), dtype=np.int32), self_pairs=[], link_labels=[],
        )  # fmt: skip
    wrong = [
        engine.ObstacleConfig(
            name=o.name, position=o.position, rotation=o.rotation, velocity=o.velocity,
            threshold=o.threshold, geometry=i,  # the obstacle's index, not its geometry's
        )
        for i, o in enumerate(good.kinds[1].obstacles)
    ]  # fmt: skip
    bad_kinds = [*good.kinds]
    bad_kinds[1] = engine.ObstacleRowsConfig(obstacles=wrong, rows=True, form="normalized")
    with pytest.raises(ValueError, match="not in its collision pairs"):
        engine.ConstraintSetConfig(
            model=panda.model, kinds=bad_kinds, scene=good.scene, release="projection",
            hysteresis=0.0, max_active=None, monitor_margin=0.1,
        )  # fmt: skip
    with pytest.raises(ValueError, match="obstacles without link geometry"):
        engine.ConstraintSetConfig(
            model=panda.model, kinds=good.kinds, scene=None, release="projection",
            hysteresis=0.0, max_active=None, monitor_margin=0.1,
        )  # fmt: skip
    with pytest.raises(ValueError, match="release 'projection' or 'sign'"):
        engine.ConstraintSetConfig(
            model=panda.model, kinds=good.kinds, scene=good.scene, release="never",
            hysteresis=0.0, max_active=None, monitor_margin=0.1,
        )  # fmt: skip


def test_record_arrays_are_never_converted():
    """The engine writes the Recorder's arrays in place: a copy would be written instead."""
    n, nq, nv = 3, 2, 2

    def arrays(**changes):
        kwargs = dict(
            N=n, every=1, idx=np.zeros(n, dtype=np.intp), q=np.zeros((n, nq)),
            qdot=np.zeros((n, nv)), qddot=np.zeros((n, nv)), position=np.zeros((n, 3)),
            reference=None, error=np.zeros(n), orientation_error=None, active=None,
            distance=None, joint_min=np.zeros(nq), joint_max=np.zeros(nq),
            qdot_prev=np.zeros(nv),
        )  # fmt: skip
        kwargs.update(changes)
        return engine.RecordArrays(**kwargs)

    assert arrays().capacity == n
    with pytest.raises(TypeError):
        arrays(q=np.zeros((n, nq), dtype=np.float32))
    with pytest.raises(TypeError):
        arrays(q=np.zeros((nq, n)).T)  # not C-contiguous
    with pytest.raises(ValueError, match="RecordArrays"):
        arrays(N=n + 1)  # one sample more than room for
