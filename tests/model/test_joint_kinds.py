"""Revolute, prismatic, continuous and mimic joints: units, joint-range rows, locking.

The Panda (7 revolute joints, 2 prismatic fingers, finger 2 mimicking finger 1)
and small URDFs written here: one with a continuous joint beside limited ones,
some with mimic joints.
"""

from __future__ import annotations

import math
import sys
import warnings

import numpy as np
import pinocchio as pin
import pytest
from matplotlib.figure import Figure

import clik
from clik import plot
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.joint_limits import JointLimits, limits_by_q
from clik.errors import InfeasibleError, InputError, RobotLoadError, ScenarioError
from clik.model.joints import PRISMATIC, REVOLUTE, JointValues
from clik.model.mimic import MimicJointWarning
from clik.model.robot import Robot
from clik.scenarios.build_constraints import build_constraints
from clik.scenarios.scenario import parse_scenario
from tests.limits_check import assert_within_limits
from tests.urdf_snippets import urdf_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

FINGER = "panda_finger_joint1"
FOLLOWER = "panda_finger_joint2"
FINGER_RANGE = 0.04  # [m], the Panda's finger: [0, 0.04]
READY_DEG = [0.0, -45.0, 0.0, -135.0, 0.0, 90.0, 45.0]  # the ready pose, revolute joints [deg]


def load_panda() -> Robot:
    """The Panda with its fingers free (finger 2 locked as a mimic joint)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MimicJointWarning)
        return Robot.load("panda")


@pytest.fixture(scope="module")
def panda8() -> Robot:
    return load_panda()


def panda_scenario(
    tmp_path, initial: str = "", limits: str = ""
) -> clik.scenarios.scenario.Scenario:
    """A Panda scenario (hold in place) with the given ``[initial]`` and joint-limit lines."""
    text = f"""
[robot]
source = "panda"

[initial]
{initial or 'q = "reference"'}

[task]
frame = "panda_hand"
kind = "position"

[trajectory]
kind = "hold"
duration = 0.05

[constraints.joint_limits]
enabled = true
{limits}
"""
    path = tmp_path / "panda.toml"
    path.write_text(text, encoding="utf-8")
    return parse_scenario(tomllib.loads(text), path)


def joint_limits_of(scenario, robot: Robot) -> JointLimits:
    task = clik.Task(robot, scenario.task["frame"], scenario.task["kind"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        constraints = build_constraints(scenario, robot, task)
    assert constraints.joint_limits is not None
    return constraints.joint_limits


# ------------------------------------------------------------ degrees: revolute only


def test_initial_q_in_degrees_keeps_the_finger_in_metres(tmp_path, panda8):
    q_deg = [*READY_DEG, 0.02]
    scenario = panda_scenario(tmp_path, f'q = {q_deg}\nunit = "deg"')
    q0 = panda8.check_configuration(scenario.initial_q, "initial.q")
    np.testing.assert_allclose(q0[:7], np.radians(READY_DEG), rtol=0, atol=1e-15)
    assert q0[7] == 0.02  # metres, not 0.02 deg = 3.5e-4 m
    assert panda8.q_units == ["rad"] * 7 + ["m"]
    assert panda8.joint_kinds[FINGER] == PRISMATIC
    assert panda8.joint_kinds["panda_joint1"] == REVOLUTE


def test_runner_builds_the_degree_start(tmp_path):
    from clik.scenarios.runner import build

    scenario = panda_scenario(tmp_path, f'q = {[*READY_DEG, 0.02]}\nunit = "deg"')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = build(scenario)
    assert run.q0[7] == 0.02
    assert run.q0[3] == pytest.approx(math.radians(-135.0), abs=1e-15)


def test_degree_threshold_gives_the_fingers_a_metre_threshold(tmp_path, panda8):
    scenario = panda_scenario(tmp_path, limits='threshold = 2.0\nunit = "deg"')
    jl = joint_limits_of(scenario, panda8)
    assert jl.joint_names == panda8.joint_names  # 7 revolute joints and finger 1
    np.testing.assert_allclose(jl.threshold[:7], math.radians(2.0))
    assert jl.threshold[7] == 0.005  # the default prismatic_threshold [m]
    # Fingers half open: no finger row fires (a 2 deg = 0.035 m threshold on a
    # 0.04 m range made both fire).
    q = panda8.configuration([*READY_DEG, 0.02], "deg")
    errors = dict(zip(jl.names, jl.evaluate(q), strict=True))
    assert errors[f"joint:{FINGER}:lower"] == pytest.approx(0.005 - 0.02)
    assert errors[f"joint:{FINGER}:upper"] == pytest.approx(0.005 - 0.02)
    assert max(errors.values()) < 0.0


def test_prismatic_threshold_key_and_the_quarter_range_cap(tmp_path, panda8):
    given = panda_scenario(
        tmp_path, limits='threshold = 2.0\nunit = "deg"\nprismatic_threshold = 0.002'
    )
    assert joint_limits_of(given, panda8).threshold[7] == 0.002
    wide = panda_scenario(tmp_path, limits="prismatic_threshold = 0.03")
    jl = joint_limits_of(wide, panda8)
    assert jl.threshold[7] == pytest.approx(FINGER_RANGE / 4)  # capped: 0.01, not 0.03
    # the cap holds for revolute joints too: joint 4 spans 3.0020 rad
    big = JointLimits(panda8, threshold=2.0)
    span = panda8.upper[3] - panda8.lower[3]
    assert big.threshold[3] == pytest.approx(span / 4)
    assert big.threshold[3] < 2.0


def test_prismatic_threshold_must_be_positive(tmp_path):
    with pytest.raises(ScenarioError, match=r"constraints\.joint_limits\.prismatic_threshold"):
        panda_scenario(tmp_path, limits="prismatic_threshold = 0.0")


def test_degree_override_converts_revolute_joints_only(tmp_path, panda8):
    limits = (
        'unit = "deg"\n'
        f"[constraints.joint_limits.override.{FINGER}]\nupper = 0.03\n"
        "[constraints.joint_limits.override.panda_joint4]\nupper = -100.0\n"
    )
    scenario = panda_scenario(tmp_path, limits=limits)
    jl = joint_limits_of(scenario, panda8)
    upper = dict(zip(jl.joint_names, jl.upper, strict=True))
    assert upper[FINGER] == 0.03  # metres as written
    assert upper["panda_joint4"] == pytest.approx(math.radians(-100.0))


def test_limit_message_shows_a_prismatic_joint_in_metres(panda8):
    q = panda8.q_reference
    q[7] = 0.05
    with pytest.raises(InfeasibleError) as caught:
        panda8.check_within_limits(q)
    assert f"'{FINGER}' = 0.05 not in [0, 0.04] m" in str(caught.value)
    q = panda8.q_reference
    q[3] = 0.5
    with pytest.raises(InfeasibleError, match=r"'panda_joint4' = 0.5 not in .* rad \(28.65 deg"):
        panda8.check_within_limits(q)


def test_joint_values_survive_pickling():
    import pickle

    values = JointValues([90.0, 0.02], "deg")
    back = pickle.loads(pickle.dumps(values))
    assert back == values
    assert (back.written, back.unit) == ((90.0, 0.02), "deg")
    with pytest.raises(InputError, match="unit"):
        JointValues([1.0], "grad")


# ---------------------------------------------------------------- mimic joints


def right_finger_offset(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """Position of the right finger in the hand frame [m]."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    hand = data.oMf[model.getFrameId("panda_hand")]
    return hand.actInv(data.oMf[model.getFrameId("panda_rightfinger")]).translation.copy()


def test_panda_follower_finger_is_locked_with_a_warning():
    with pytest.warns(MimicJointWarning) as caught:
        panda = Robot.load("panda")
    (warning,) = [w for w in caught if issubclass(w.category, MimicJointWarning)]
    assert FOLLOWER in str(warning.message) and FINGER in str(warning.message)
    assert warning.message.joints == {FOLLOWER: (FINGER, 0.02)}
    assert FOLLOWER not in panda.joint_names and FINGER in panda.joint_names
    assert (panda.nq, panda.nv) == (8, 8)
    assert panda.locked == {FOLLOWER: 0.02}  # multiplier 1 x the leader's reference 0.02
    assert panda.mimics[FOLLOWER].leader == FINGER
    # the locked follower sits where the full model puts it for finger2 = 0.02
    full = pin.buildModelFromUrdf(str(panda.source_path))
    q = panda.q_reference
    q[7] = 0.03
    offset = right_finger_offset(panda.model, q)
    np.testing.assert_allclose(offset, right_finger_offset(full, np.r_[q, 0.02]), atol=1e-12)
    assert not np.allclose(offset, right_finger_offset(full, np.r_[q, 0.03]), atol=1e-3)


def test_locking_the_leader_locks_the_follower_at_its_value_silently():
    with warnings.catch_warnings():
        warnings.simplefilter("error", MimicJointWarning)
        panda = Robot.load("panda", lock={FINGER: 0.03})
    assert panda.locked == {FINGER: 0.03, FOLLOWER: 0.03}
    assert panda.nq == 7


def test_follower_stays_put_along_a_tracked_run(panda8):
    task = clik.Task(panda8, "panda_hand", "position")
    q0 = panda8.q_reference
    q0[7] = 0.02
    p0 = task.placement(q0).translation
    line = clik.trajectory.Line(p0, p0 + [0.0, 0.05, -0.03], duration=0.3)
    result = clik.track(task, line, q0=q0, law="pseudoinverse", gain=100.0)
    assert result.status == "completed"
    assert_within_limits(result, panda8)
    assert np.ptp(result.q[:, 3]) > 0.01  # the arm moved
    full = pin.buildModelFromUrdf(str(panda8.source_path))  # finger 2 free, set to 0.02
    for q in result.q[:: max(1, len(result.q) // 10)]:
        expected = right_finger_offset(full, np.r_[q, 0.02])
        np.testing.assert_allclose(right_finger_offset(panda8.model, q), expected, atol=1e-12)


LINKS3 = '<link name="base"/><link name="a"/><link name="b"/><link name="c"/>'


def revolute(name: str, parent: str, child: str, low: float, high: float, extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>'
        f'<limit lower="{low}" upper="{high}" effort="1" velocity="1"/>{extra}</joint>'
    )


def test_mimic_multiplier_offset_and_chain(tmp_path):
    body = (
        LINKS3
        + revolute("ja", "base", "a", -1, 1)
        + revolute("jb", "a", "b", -0.5, 0.5, '<mimic joint="ja" multiplier="2" offset="0.3"/>')
        + revolute("jc", "b", "c", -2, 2, '<mimic joint="jb" multiplier="-1"/>')
    )
    path = tmp_path / "mimic.urdf"
    path.write_text(urdf_text(body), encoding="utf-8")
    with pytest.warns(MimicJointWarning) as caught:
        robot = Robot.load(path)
    assert robot.joint_names == ["ja"]
    # ja's reference 0: jb = 2 x 0 + 0.3, jc = -1 x jb (its leader locked: not in the warning)
    assert robot.locked == {"jb": pytest.approx(0.3), "jc": pytest.approx(-0.3)}
    (warning,) = [w.message for w in caught if issubclass(w.category, MimicJointWarning)]
    assert warning.joints == {"jb": ("ja", pytest.approx(0.3))}
    with pytest.raises(InputError, match="lock: expected at least one joint left free"):
        Robot.load(path, lock={"ja": 0.2})  # locks its followers too: nothing left


def test_mimic_follower_value_is_clipped_into_its_limits(tmp_path):
    body = (
        LINKS3
        + revolute("ja", "base", "a", -1, 1)
        + revolute("jb", "a", "b", -0.5, 0.5, '<mimic joint="ja" multiplier="2" offset="0.3"/>')
        + revolute("jc", "b", "c", -2, 2)
    )
    path = tmp_path / "clip.urdf"
    path.write_text(urdf_text(body), encoding="utf-8")
    robot = Robot.load(path, lock={"ja": 0.2})  # leader locked: no warning
    assert robot.joint_names == ["jc"]
    assert robot.locked == {"ja": 0.2, "jb": 0.5}  # 2 x 0.2 + 0.3 = 0.7, clipped


@pytest.mark.parametrize(
    ("mimics", "message"),
    [
        (('<mimic joint="jc"/>', '<mimic joint="jb"/>'), "mimic joints follow each other"),
        (('<mimic joint="ja" multiplier="two"/>', ""), "multiplier 'two', expected a finite"),
        (('<mimic joint="ja" offset="nan"/>', ""), "offset 'nan', expected a finite"),
        (('<mimic joint="ja" multiplier="1e300"/>', ""), "multiplier '1e300', expected a number"),
        (('<mimic joint="ja" offset="-2e3"/>', ""), "offset '-2e3', expected a number of magni"),
    ],
)
def test_bad_mimic_is_a_load_error(tmp_path, mimics, message):
    body = (
        LINKS3
        + revolute("ja", "base", "a", -1, 1)
        + revolute("jb", "a", "b", -1, 1, mimics[0])
        + revolute("jc", "b", "c", -1, 1, mimics[1])
    )
    path = tmp_path / "bad.urdf"
    path.write_text(urdf_text(body), encoding="utf-8")
    with pytest.raises(RobotLoadError, match=message):
        Robot.load(path)


def test_mimic_of_a_missing_joint_is_ignored(tmp_path):
    body = (
        '<link name="base"/><link name="a"/><link name="b"/>'
        + revolute("ja", "base", "a", -1, 1)
        + revolute("jb", "a", "b", -1, 1, '<mimic joint="nowhere"/>')
    )
    path = tmp_path / "missing.urdf"
    path.write_text(urdf_text(body), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error", MimicJointWarning)
        robot = Robot.load(path)
    assert robot.joint_names == ["ja", "jb"] and robot.locked == {}


# ----------------------------------------------------- continuous beside limited joints

CONTINUOUS_BODY = (
    '<link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="tip"/>'
    '<joint name="j1" type="continuous"><parent link="base"/><child link="l1"/>'
    '<origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
    '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>'
    '<origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    '<joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>'
    '<origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>'
    '<limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>'
    '<joint name="jtip" type="fixed"><parent link="l3"/><child link="tip"/></joint>'
)


@pytest.fixture
def wheel_arm(tmp_path) -> Robot:
    """j1 continuous (q 0-1 as cos, sin; v 0), j2 revolute [-1, 1] (q 2, v 1),
    j3 prismatic [0, 0.1] m (q 3, v 2)."""
    path = tmp_path / "wheel_arm.urdf"
    path.write_text(urdf_text(CONTINUOUS_BODY), encoding="utf-8")
    return Robot.load(path)


def test_continuous_joint_gets_no_rows_the_others_keep_theirs(wheel_arm):
    assert (wheel_arm.nq, wheel_arm.nv) == (4, 3)
    jl = JointLimits(wheel_arm, threshold=0.1, prismatic_threshold=0.01)
    assert jl.names == ["joint:j2:lower", "joint:j3:lower", "joint:j2:upper", "joint:j3:upper"]
    assert jl.joint_names == ["j2", "j3"]
    assert jl.q_index.tolist() == [2, 3] and jl.v_index.tolist() == [1, 2]
    np.testing.assert_array_equal(jl.lower, [-1.0, 0.0])
    np.testing.assert_array_equal(jl.upper, [1.0, 0.1])
    np.testing.assert_array_equal(jl.row_threshold, [0.1, 0.01, 0.1, 0.01])
    assert jl._thr is jl.row_threshold
    a = 2.5  # the continuous joint's angle [rad]: no effect on the rows
    q = np.array([math.cos(a), math.sin(a), 0.95, 0.004])
    # e_q = d_q - d: d = q - lower (lower rows), upper - q (upper rows)
    expected = [0.1 - (0.95 + 1.0), 0.01 - 0.004, 0.1 - (1.0 - 0.95), 0.01 - (0.1 - 0.004)]
    np.testing.assert_allclose(jl.evaluate(q), expected, rtol=0, atol=1e-15)
    assert jl.slack(q) == pytest.approx(-0.05)
    row = np.full(3, 7.0)
    jl.row(1, row)  # j3 lower: +1 at j3's velocity index
    np.testing.assert_array_equal(row, [0.0, 0.0, 1.0])
    jl.row(2, row)  # j2 upper: -1 at j2's velocity index
    np.testing.assert_array_equal(row, [0.0, -1.0, 0.0])
    beyond = np.array([1.0, 0.0, 1.2, -0.003])
    np.testing.assert_allclose(jl.excursion(beyond), [-2.2, 0.003, 0.2, -0.103], atol=1e-15)
    np.testing.assert_allclose(jl.excursion(q), [-1.95, -0.004, -0.05, -0.096], atol=1e-15)


def test_continuous_joint_cannot_take_an_override(wheel_arm):
    with pytest.raises(InputError, match=r"override\.j1: expected a revolute or prismatic"):
        JointLimits(wheel_arm, override={"j1": {"upper": 1.0}})


def test_threshold_cap_on_a_short_range(wheel_arm):
    jl = JointLimits(wheel_arm, threshold=0.8)  # j2 spans 2 rad, j3 0.1 m
    np.testing.assert_allclose(jl.threshold, [0.5, 0.025])


def test_continuous_angle_form_in_degrees(wheel_arm):
    q = wheel_arm.check_configuration(JointValues([90.0, 10.0, 0.05], "deg"))
    np.testing.assert_allclose(q, [0.0, 1.0, math.radians(10.0), 0.05], atol=1e-15)
    same = wheel_arm.configuration([0.0, 1.0, 10.0, 0.05], "deg")  # (cos, sin) kept as is
    np.testing.assert_allclose(same, q, atol=1e-15)
    with pytest.raises(
        InputError, match=r"an array of 4 finite joint values .* \(or 3, a continuous"
    ):
        wheel_arm.configuration([1.0, 2.0], "deg")


def test_limits_by_q_places_the_rows_of_limited_joints(wheel_arm):
    used = {"lower": [-1.0, 0.0], "upper": [1.0, 0.1], "threshold": [0.1, 0.01]}
    lower, upper, thr = limits_by_q(used, wheel_arm, 4)
    np.testing.assert_array_equal(upper[2:], [1.0, 0.1])
    assert np.isnan(upper[:2]).all() and np.isnan(thr[:2]).all()
    assert limits_by_q(used, None, 4) is None  # no robot, no index: cannot place them
    lower, _, _ = limits_by_q({**used, "q_index": [2, 3]}, None, 4)
    np.testing.assert_array_equal(lower[2:], [-1.0, 0.0])


# ----------------------------------------------------------------------- plots


def data_lines(ax) -> list:
    """The plotted runs: lines without a gid, not the event legend entries."""
    events = ("activate", "release", "skipped")
    return [ln for ln in ax.lines if ln.get_gid() is None and ln.get_label() not in events]


def test_joint_plots_show_revolute_in_degrees_and_prismatic_in_metres(panda8):
    task = clik.Task(panda8, "panda_hand", "position")
    q0 = panda8.q_reference
    q0[7] = 0.02
    p0 = task.placement(q0).translation
    line = clik.trajectory.Line(p0, p0 + [0.0, 0.03, 0.0], duration=0.2)
    cs = ConstraintSet(panda8, joint_limits=JointLimits(panda8, prismatic_threshold=0.005))
    result = clik.track(task, line, q0=q0, law="pseudoinverse", gain=100.0, constraints=cs)
    ax = Figure().subplots()
    plot.joint(ax, result, joint_index=7)
    assert ax.get_ylabel() == f"q8 ({FINGER}) [m]"
    (data,) = data_lines(ax)
    np.testing.assert_allclose(data.get_ydata(), result.q[:, 7])
    limits = sorted(float(ln.get_ydata()[0]) for ln in ax.lines if ln.get_gid() == "limit")
    assert limits == pytest.approx([0.0, 0.04])
    thresholds = sorted(float(ln.get_ydata()[0]) for ln in ax.lines if ln.get_gid() == "threshold")
    assert thresholds == pytest.approx([0.005, 0.035])
    ax = Figure().subplots()
    plot.joint(ax, result, joint_index=3)
    assert ax.get_ylabel() == "q4 (panda_joint4) [deg]"
    (data,) = data_lines(ax)
    np.testing.assert_allclose(data.get_ydata(), np.degrees(result.q[:, 3]))
