"""Every kind of constraint row, through one generic test (clik/constraints/registry.py).

For each registered kind a case (a robot, a task, a set, a configuration where the
kind's error is positive) drives:

- its rows against central differences of its errors (``edot = f - j qdot``, so
  ``j = -de/dq``), to 1e-6 of the row's size;
- both engines on a short run that activates it: the same status, events and joint
  trajectory (1e-9 rad);
- solve mode: the pose returned satisfies the kind (checked here from the geometry,
  not by clik's own check), or the failure names it;
- bad input: the field named.

A kind without a case here fails :func:`test_every_kind_has_a_case`: registering a kind
is how it gets tested.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.clouds import CloudObstacle
from clik.constraints import (
    ConstraintRun,
    ConstraintSet,
    Dexterity,
    JointLimits,
    LinkPairs,
    Obstacle,
    ObstacleAvoidance,
)
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.cone import Cone
from clik.constraints.kind import Sample
from clik.constraints.registry import KINDS
from clik.constraints.workspace import Workspace
from clik.errors import InputError, ScenarioError
from clik.trajectory import Line

ROBOT = Path(__file__).parents[1] / "data" / "spheres5r.urdf"
SPHERE = 0.05
"""Radius of every link's collision sphere [m], its centre 0.15 m along the link's z."""
STEP = 1e-5
"""Central-difference step [rad]."""
ROW_TOLERANCE = 1e-6
"""Largest ``|j - j_fd| / |j|``."""
PARITY = 1e-9
"""Largest joint difference between the engines [rad]."""
CHECK = 1e-7
"""Slack of the independent checks of a solved pose [m or rad]."""


@dataclass
class Case:
    """A kind in a set, and a configuration where its error is positive."""

    cset: ConstraintSet
    task: clik.Task
    q: np.ndarray
    delta: np.ndarray
    """The reference's displacement in the parity run [m] (it drives into the kind)."""
    label: str
    """What a solve blocked by the kind says (``blocked_by``)."""
    satisfied: Callable[[np.ndarray], bool]
    """Whether a configuration satisfies the kind, from the geometry alone."""
    kwargs: dict = field(default_factory=dict)


def robot() -> clik.Robot:
    return clik.Robot.load(ROBOT)


def tip_task(r: clik.Robot) -> clik.Task:
    return clik.Task(r, "tip", "position")


def placement(r: clik.Robot, q: np.ndarray, frame: str) -> pin.SE3:
    data = r.model.createData()
    pin.framesForwardKinematics(r.model, data, q)
    return data.oMf[r.model.getFrameId(frame)]


def sphere_centres(r: clik.Robot, q: np.ndarray) -> list[np.ndarray]:
    """World centres of the links' collision spheres l1..l5."""
    return [placement(r, q, f"l{i}").act(np.array([0.0, 0.0, 0.15])) for i in range(1, 6)]


Q = np.array([0.3, 0.9, -1.2, 0.4, 0.8])


def joint_case() -> Case:
    r = robot()
    q = Q.copy()
    q[1] = 2.45  # 0.15 rad from its upper limit 2.6
    jl = JointLimits(r, 0.3)

    def satisfied(x: np.ndarray) -> bool:
        return bool(np.all(x - (-2.6 + 0.3) >= -CHECK) and np.all(2.6 - 0.3 - x >= -CHECK))

    cset = ConstraintSet(r, joint_limits=jl)
    return Case(cset, tip_task(r), q, np.array([0.0, 0.0, 0.1]), "joint range", satisfied)


def obstacle_case() -> Case:
    r = robot()
    centre = sphere_centres(r, Q)[2]
    position = centre + np.array([0.0, 0.14, 0.0])  # 0.04 m between the spheres
    ob = Obstacle("ball", "sphere", position, radius=SPHERE, threshold=0.08)

    def satisfied(x: np.ndarray) -> bool:
        return all(
            np.linalg.norm(c - position) - 2 * SPHERE >= 0.08 - CHECK for c in sphere_centres(r, x)
        )

    cset = ConstraintSet(r, obstacles=[ob])
    return Case(cset, tip_task(r), Q.copy(), np.array([0.0, 0.15, 0.0]), "obstacle", satisfied)


def link_pair_case() -> Case:
    r = robot()
    q = np.array([-0.57, -2.4, -2.09, -1.42, -0.43])  # l1 and l3 0.018 m apart
    cset = ConstraintSet(r, self_collision=True, self_threshold=0.1, obstacle_rows=False)
    assert cset.scene is not None
    pairs = [(a, b) for _, a, b in cset.scene.self_pairs]

    def satisfied(x: np.ndarray) -> bool:
        c = sphere_centres(r, x)
        return all(np.linalg.norm(c[a] - c[b]) - 2 * SPHERE >= 0.1 - CHECK for a, b in pairs)

    return Case(cset, tip_task(r), q, np.array([-0.1, 0.0, -0.05]), "link pair", satisfied)


def dexterity_case() -> Case:
    r = robot()
    task = tip_task(r)
    J = task.jacobian(Q)
    w = math.sqrt(np.linalg.det(J @ J.T))
    threshold = 1.2 * w

    def satisfied(x: np.ndarray) -> bool:
        Jx = task.jacobian(x)
        return math.sqrt(max(np.linalg.det(Jx @ Jx.T), 0.0)) >= threshold - CHECK

    cset = ConstraintSet(r, dexterity=Dexterity(threshold))
    return Case(cset, task, Q.copy(), np.array([0.1, 0.1, 0.0]), "dexterity", satisfied)


def workspace_case() -> Case:
    r = robot()
    p = placement(r, Q, "tip").translation
    lower, upper = p - np.array([0.05, 1.0, 1.0]), p + np.array([1.0, 1.0, 1.0])
    box = Workspace(r, "tip", lower, upper, threshold=0.1, name="cell")

    def satisfied(x: np.ndarray) -> bool:
        y = placement(r, x, "tip").translation
        return bool(np.all(y - lower >= 0.1 - CHECK) and np.all(upper - y >= 0.1 - CHECK))

    cset = ConstraintSet(r, kinds=[box])
    return Case(cset, tip_task(r), Q.copy(), np.array([-0.1, 0.0, 0.0]), "workspace", satisfied)


def cone_case() -> Case:
    r = robot()
    a = placement(r, Q, "tip").rotation[:, 2]
    side = np.cross(a, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    u = math.cos(0.5) * a + math.sin(0.5) * np.cross(side, a)  # 0.5 rad from the axis
    cone = Cone(r, "tip", [0, 0, 1], u, angle=0.55, threshold=0.1, name="upright")

    def satisfied(x: np.ndarray) -> bool:
        ax = placement(r, x, "tip").rotation[:, 2]
        theta = math.atan2(np.linalg.norm(np.cross(ax, u)), float(ax @ u))
        return theta <= 0.55 - 0.1 + CHECK

    cset = ConstraintSet(r, kinds=[cone])
    return Case(cset, tip_task(r), Q.copy(), np.array([0.1, -0.1, 0.0]), "cone", satisfied)


def cloud_case() -> Case:
    r = robot()
    centre = sphere_centres(r, Q)[2] + np.array([0.0, 0.14, 0.0])
    rng = np.random.default_rng(4)
    points = rng.normal(size=(300, 3))
    points = centre + SPHERE * points / np.linalg.norm(points, axis=1)[:, None]  # a ball's skin
    cloud = CloudObstacle("scan", points, voxel=0.0)

    def satisfied(x: np.ndarray) -> bool:
        gaps = [np.linalg.norm(points - c, axis=1).min() - SPHERE for c in sphere_centres(r, x)]
        return min(gaps) >= 0.08 - CHECK

    cset = ConstraintSet(r, kinds=[CloudAvoidance([cloud], threshold=0.08)])
    return Case(cset, tip_task(r), Q.copy(), np.array([0.0, 0.15, 0.0]), "cloud", satisfied)


CASES: dict[type, Callable[[], Case]] = {
    JointLimits: joint_case,
    ObstacleAvoidance: obstacle_case,
    LinkPairs: link_pair_case,
    Dexterity: dexterity_case,
    Workspace: workspace_case,
    Cone: cone_case,
    CloudAvoidance: cloud_case,
}

KIND_IDS = [k.__name__ for k in KINDS]


def test_every_kind_has_a_case():
    assert set(KINDS) == set(CASES), (
        "a registered kind needs a case in tests/constraints/test_kinds.py"
    )
    assert len(KINDS) == 7


def kind_run(case: Case, kind_type: type, q: np.ndarray):
    """The kind's candidates at ``q`` with their rows: {key: (error, row)}."""
    r, task = case.cset.robot, case.task
    J_task = task.jacobian(q)
    pin.computeJointJacobians(r.model, r.data, q)
    pin.updateFramePlacements(r.model, r.data)
    crun = ConstraintRun(
        case.cset, task.m, "pseudoinverse", 1.0, np.array([0.0, 1e-3]), 1, task.frame_id,
        task.rows,
    )  # fmt: skip
    sample = Sample(0.0, q, None, r, J_task, True, [], crun.scene)
    out = []
    for run in crun.runs:
        if type(run.kind) is kind_type:
            run.evaluate(sample, out)
    rows = {}
    for c in out:
        row = np.zeros(r.nv)
        c.run.row(sample, c, row)
        rows[c.key] = (c.error, row)
    return rows


@pytest.mark.parametrize("kind_type", KINDS, ids=KIND_IDS)
def test_rows_are_the_errors_derivatives(kind_type):
    case = CASES[kind_type]()
    r = case.cset.robot
    here = kind_run(case, kind_type, case.q)
    assert here, f"{kind_type.__name__}: no candidate at the case's configuration"
    for key, (error, row) in here.items():
        assert error > 0.0, key
        fd = np.zeros(r.nv)
        for k in range(r.nv):
            dq = np.zeros(r.nv)
            dq[k] = STEP
            plus = kind_run(case, kind_type, pin.integrate(r.model, case.q, dq))[key][0]
            minus = kind_run(case, kind_type, pin.integrate(r.model, case.q, -dq))[key][0]
            fd[k] = -(plus - minus) / (2 * STEP)
        assert np.linalg.norm(row) > 1e-3, key
        assert np.linalg.norm(row - fd) <= ROW_TOLERANCE * np.linalg.norm(row), (key, row, fd)


@pytest.mark.parametrize("kind_type", KINDS, ids=KIND_IDS)
def test_engines_agree(kind_type):
    case = CASES[kind_type]()
    p0 = case.task.placement(case.q).translation
    line = Line(p0, p0 + case.delta, 0.4)
    results = []
    for engine in ("python", "compiled"):
        tracker = clik.Tracker(
            case.task, law="transpose", gain=500.0, dt=1e-3, constraints=case.cset, engine=engine
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results.append(tracker.run(line, case.q))
    a, b = results
    assert any(e["action"] == "activate" for e in a.events), "the run never activated the kind"
    assert (a.status, a.events) == (b.status, b.events)
    assert [{**v, "worst": None} for v in a.violations] == [
        {**v, "worst": None} for v in b.violations
    ]
    for va, vb in zip(a.violations, b.violations, strict=True):
        assert va["worst"] == pytest.approx(vb["worst"], abs=PARITY)
    assert a.info["constraint_names"] == b.info["constraint_names"]
    np.testing.assert_allclose(a.q, b.q, atol=PARITY, rtol=0)
    sa, sb = a.summary(), b.summary()
    for key in sa:
        if key.endswith("_used") or key.startswith("min_obstacle"):
            assert sa[key] == sb[key], key


@pytest.mark.parametrize("kind_type", KINDS, ids=KIND_IDS)
def test_solve_mode_honours_the_kind(kind_type):
    """The target is the tip at a configuration inside the kind's threshold, and the
    solve starts there: the unconstrained pose violates the kind; the constrained solve
    moves off it (the arm is redundant) or names the kind."""
    case = CASES[kind_type]()
    target = case.task.placement(case.q).translation
    free = clik.solve(case.task, target, case.q)
    assert free.success and not case.satisfied(free.q)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = clik.solve(case.task, target, case.q, constraints=case.cset)
    if res.success:
        assert case.satisfied(res.q), res.reason
        assert np.linalg.norm(case.task.placement(res.q).translation - target) <= 1e-4
    else:
        assert res.blocked_by is not None and case.label in res.blocked_by, res.reason


def test_dexterity_blocks_a_stretched_planar_arm():
    """The issue's case: planar4r toward x = 1.19 m, w >= 0.1: no pose at w < 0.1."""
    arm = clik.Robot.load("planar4r")
    task = clik.Task(arm, "tip", "position", axes=["x", "y"])
    target = [1.19, 0.0, 0.0]
    cset = ConstraintSet(arm, dexterity=Dexterity(0.1))
    free = clik.solve(task, target)
    J = task.jacobian(free.q)
    assert free.success and math.sqrt(np.linalg.det(J @ J.T)) < 0.1
    res = clik.solve(task, target, constraints=cset)
    if res.success:
        J = task.jacobian(res.q)
        assert math.sqrt(np.linalg.det(J @ J.T)) >= 0.1 - CHECK
    else:
        assert res.blocked_by is not None and "dexterity" in res.blocked_by


BAD_INPUT = [
    (JointLimits, lambda r: JointLimits(r, -1.0), "constraints.joint_limits.threshold"),
    (JointLimits, lambda r: ConstraintSet(r, joint_limits=0.1), "constraints.joint_limits"),
    (ObstacleAvoidance, lambda r: ConstraintSet(r, form="cubic"), "constraints.obstacles.form"),
    (
        ObstacleAvoidance,
        lambda r: ConstraintSet(r, obstacle_threshold=-0.1),
        "constraints.obstacle_threshold",
    ),
    (
        LinkPairs,
        lambda r: ConstraintSet(r, self_collision=True, self_threshold=0.0),
        "constraints.self_threshold",
    ),
    (Dexterity, lambda r: Dexterity(float("nan")), "constraints.dexterity.threshold"),
    (Dexterity, lambda r: ConstraintSet(r, dexterity=0.1), "constraints.dexterity"),
    (
        Workspace,
        lambda r: Workspace(r, "tip", [0, 0, 0], [1, -1, 1]),
        "constraints.workspace.upper",
    ),
    (
        Workspace,
        lambda r: Workspace(r, "tip", [0, 0, 0], [1, 1, 0.1], threshold=0.05),
        "constraints.workspace.threshold",
    ),
    (Workspace, lambda r: Workspace(r, "tip", [0, 0], [1, 1, 1]), "constraints.workspace.lower"),
    (Cone, lambda r: Cone(r, "tip", [0, 0, 0], [0, 0, 1], 0.5), "constraints.cone.axis"),
    (Cone, lambda r: Cone(r, "tip", [0, 0, 1], [0, 0, 1], 0.0), "constraints.cone.angle"),
    (CloudAvoidance, lambda r: CloudAvoidance([np.zeros((3, 3))]), "clouds[0]"),
    (CloudAvoidance, lambda r: CloudObstacle("scan", np.zeros((4, 2))), "obstacles.scan.points"),
    (CloudAvoidance, lambda r: CloudObstacle("s", np.zeros((4, 3)), -0.1), "obstacles.s.voxel"),
    (
        Cone,
        lambda r: Cone(r, "tip", [0, 0, 1], [0, 0, 1], 0.2, threshold=0.2),
        "constraints.cone.threshold",
    ),
    (Cone, lambda r: Cone(r, "tip", [0, 0, 1], [0, 0, 1], 0.5, gain=-1.0), "constraints.cone.gain"),
]


def test_every_kind_has_bad_input():
    assert {k for k, _, _ in BAD_INPUT} == set(KINDS)


@pytest.mark.parametrize(("kind_type", "make", "field"), BAD_INPUT)
def test_bad_input_names_the_field(kind_type, make, field):
    with pytest.raises(InputError) as info:
        make(robot())
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: expected ")


def test_an_unknown_frame_is_named():
    with pytest.raises(clik.FrameNotFound):
        Workspace(robot(), "wrist", [0, 0, 0], [1, 1, 1])


SCENARIO = """
name = "kinds"
[robot]
source = "{robot}"
[initial]
q = [0.3, 0.9, -1.2, 0.4, 0.8]
[task]
frame = "tip"
kind = "position"
[trajectory]
kind = "hold"
duration = 0.1
[solver]
dt = 0.001
{table}
"""


@pytest.mark.parametrize(
    ("table", "field"),
    [
        (
            '[[constraints.workspace]]\nframe = "tip"\nlower = [0, 0]\nupper = [1, 1, 1]',
            "constraints.workspace[0].lower",
        ),
        (
            '[[constraints.workspace]]\nframe = "tip"\nlower = [0, 0, 0]\nupper = [1, 1, 1]\n'
            "threshold = 0.5",
            "constraints.workspace[0].threshold",
        ),
        (
            '[[constraints.workspace]]\nframe = "hand"\nlower = [0, 0, 0]\nupper = [1, 1, 1]',
            "constraints.workspace[0].frame",
        ),
        (
            '[[constraints.cone]]\nframe = "tip"\naxis = [0, 0, 1]\ndirection = [0, 0, 1]\n'
            'angle = 200\nunit = "deg"',
            "constraints.cone[0].angle",
        ),
        (
            '[[constraints.cone]]\nframe = "tip"\naxis = [0, 0, 1]\ndirection = [0, 0, 1]\n'
            "angle = 0.5\ncolour = 1",
            "constraints.cone[0].colour",
        ),
    ],
)
def test_scenario_tables_name_the_key(tmp_path, table, field):
    from clik.scenarios.runner import build

    path = tmp_path / "kinds.toml"
    path.write_text(SCENARIO.format(robot=ROBOT, table=table))
    with pytest.raises(ScenarioError) as info:
        build(path)
    assert f": {field}: " in str(info.value) or str(info.value).startswith(f"{path}: {field}")


def test_scenario_tables_build_the_kinds(tmp_path):
    from clik.scenarios.runner import build

    table = (
        '[[constraints.workspace]]\nname = "cell"\nframe = "tip"\nlower = [-1, -1, 0]\n'
        'upper = [1, 1, 1.5]\nthreshold = 0.05\n[[constraints.cone]]\nframe = "tip"\n'
        'axis = [0, 0, 1]\ndirection = [0, 0, 1]\nangle = 90\nthreshold = 10\nunit = "deg"'
    )
    path = tmp_path / "kinds.toml"
    path.write_text(SCENARIO.format(robot=ROBOT, table=table))
    run = build(path)
    kinds = run.tracker.constraints.kinds
    box, cone = kinds[-2], kinds[-1]
    assert isinstance(box, Workspace) and box.label == "cell" and box.threshold == 0.05
    assert isinstance(cone, Cone) and cone.key == "cone:tip"
    assert cone.angle == pytest.approx(math.pi / 2) and cone.threshold == pytest.approx(
        math.radians(10)
    )
    result = run.execute()
    assert result.status == "completed", result.reason
    assert result.summary()["workspace_used"][0]["name"] == "cell"
    assert result.summary()["cone_used"][0]["angle"] == pytest.approx(math.pi / 2)
