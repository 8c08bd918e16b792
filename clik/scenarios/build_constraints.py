"""Build a :class:`ConstraintSet` from a scenario's ``[[obstacles]]`` and ``[constraints]``.

Shape obstacles become :class:`Obstacle` objects; ``shape = "cloud"`` ones
(:mod:`clik.scenarios.cloud_table`) :class:`~clik.clouds.cloud_obstacle.CloudObstacle` objects,
read now, in one :class:`~clik.constraints.cloud_avoidance.CloudAvoidance` kind with the
obstacles' threshold, rows and gain.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from clik.clouds.cloud_obstacle import CloudObstacle
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits, convert_override
from clik.constraints.joint_thresholds import (
    LOOKS_LIKE_DEGREES,
    MAX_ANGLE_THRESHOLD,
    degrees_hint,
)
from clik.constraints.kind import ConstraintKind
from clik.constraints.obstacle import Obstacle
from clik.constraints.registry import TABLE_KINDS
from clik.errors import (
    ClikError,
    FrameNotFound,
    GeometryError,
    InputError,
    JointNotFound,
    ScenarioError,
)
from clik.model.joints import REVOLUTE

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.scenarios.scenario import Scenario
    from clik.tasks.task import Task


def build_constraints(scenario: Scenario, robot: Robot, task: Task) -> ConstraintSet:
    """The scenario's obstacles (always monitored) and enabled constraint rows.

    Joint-range rows (:class:`JointLimits`): ``threshold`` [rad] is the revolute
    joints' ``d_q`` and ``prismatic_threshold`` [m] the prismatic joints' (each
    capped at a quarter of the joint's range, with a warning); an override is read in the
    table's ``unit`` for a revolute joint and in metres for a prismatic one. A
    ``threshold`` in radians (no ``unit = "deg"``) that looks like degrees and is wider
    than a revolute joint's whole range is refused, naming the joint (:func:`_check_radians`).
    The dexterity row (:class:`Dexterity`) keeps the task's manipulability above
    ``[constraints.dexterity] threshold``. The clouds (:func:`_clouds`) are read now.
    """
    obstacles = []
    for i, spec in enumerate(scenario.obstacles):
        if spec["shape"] == "cloud":
            continue
        kwargs = {k: spec[k] for k in ("radius", "size", "length", "file", "scale") if k in spec}
        try:
            obstacles.append(
                Obstacle(
                    spec["name"],
                    spec["shape"],
                    spec["position"],
                    spec["rpy"],
                    spec["velocity"],
                    spec["threshold"],
                    **kwargs,
                )
            )
        except (InputError, GeometryError) as exc:
            raise ScenarioError(scenario.file, f"obstacles[{i}]", str(exc)) from None
    c = scenario.constraints
    obs, jl_spec, sc = c["obstacles"], c["joint_limits"], c["self_collision"]
    joint_limits = _joint_limits(scenario, robot, jl_spec)
    dx_spec = c.get("dexterity") or {"enabled": False, "gain": None}
    kinds = _table_kinds(scenario, robot)
    clouds = _clouds(scenario, robot)
    if clouds:
        kinds.insert(0, CloudAvoidance(clouds, obs["enabled"], obs["threshold"], obs["gain"]))
    release = obs["release"] or c["release"]
    try:
        return ConstraintSet(
            robot,
            obstacles=obstacles,
            obstacle_rows=obs["enabled"],
            obstacle_threshold=obs["threshold"],
            obstacle_gain=obs["gain"],
            form=obs["form"],
            links=obs["links"],
            joint_limits=joint_limits,
            joint_gain=jl_spec["gain"],
            self_collision=sc["enabled"],
            self_threshold=sc["threshold"],
            self_gain=sc["gain"],
            dexterity=_dexterity(scenario, dx_spec),
            dexterity_gain=dx_spec["gain"],
            kinds=kinds,
            release=release,
            hysteresis=c["hysteresis"],
            max_active=c["max_active"],
        )
    except ClikError as exc:
        raise ScenarioError(scenario.file, "constraints", str(exc)) from None


def _clouds(scenario: Scenario, robot: Robot) -> list[CloudObstacle]:
    """The ``shape = "cloud"`` obstacles, read from their files.

    With ``self_filter``, the points within ``self_padding`` of the robot at the start
    configuration (``initial.q``) are left out.

    Raises:
        ScenarioError: A file that cannot be read (``obstacles[i].file``), bad settings.
    """
    clouds = []
    for i, spec in enumerate(scenario.obstacles):
        if spec["shape"] != "cloud":
            continue
        where = f"obstacles[{i}]"
        settings = {k: spec[k] for k in ("voxel", "position", "rpy", "threshold")}
        try:
            cloud = CloudObstacle.from_file(spec["name"], spec["file"], **settings)
        except InputError as exc:
            key = f"{where}.file" if exc.field == str(spec["file"]) else where
            raise ScenarioError(scenario.file, key, str(exc)) from None
        if spec["self_filter"]:
            q0 = robot.q_reference if scenario.initial_q is None else scenario.initial_q
            try:
                q0 = robot.check_configuration(q0, "initial.q")
            except InputError as exc:
                raise ScenarioError(scenario.file, "initial.q", str(exc)) from None
            cloud = cloud.without_robot(robot, q0, spec["self_padding"])
        clouds.append(cloud)
    return clouds


def _joint_limits(scenario: Scenario, robot: Robot, jl_spec: dict[str, Any]) -> JointLimits | None:
    """The ``[constraints.joint_limits]`` rows, or None when not enabled.

    A bad override is an error even when the rows are off.
    """
    if not (jl_spec["enabled"] or jl_spec["override"]):
        return None
    try:
        override = jl_spec["override"]
        if "override_as_written" in jl_spec:  # parse_scenario's; older dicts: radians
            override = convert_override(
                robot, jl_spec["override_as_written"], jl_spec.get("unit", "rad")
            )
        if jl_spec.get("unit", "rad") == "rad":
            _check_radians(jl_spec["threshold"], robot, override)
        elif jl_spec["threshold"] > MAX_ANGLE_THRESHOLD:  # written in degrees: no hint
            raise InputError(
                "constraints.joint_limits.threshold",
                "an angle of at most 360 deg, smaller than a revolute joint's range",
                f"{math.degrees(jl_spec['threshold']):g} deg",
            )
        joint_limits = JointLimits(
            robot,
            jl_spec["threshold"],
            override,
            prismatic_threshold=jl_spec.get("prismatic_threshold"),
        )
    except JointNotFound as exc:
        raise ScenarioError(scenario.file, "constraints.joint_limits.override", str(exc)) from None
    except InputError as exc:
        message = str(exc).removeprefix(f"{exc.field}: ")  # the key is said once
        raise ScenarioError(scenario.file, exc.field, message) from None
    return joint_limits if jl_spec["enabled"] else None


def _check_radians(threshold: float, robot: Robot, override: Any) -> None:
    """Refuse a threshold [rad] wider than a revolute joint's range (degrees read as radians).

    Such a threshold could only be capped (a quarter of the range), which leaves the rows
    active over half the joint's range: ``threshold = 5.0`` meant as 5 deg is 286 deg.
    Only one that looks like degrees (from :data:`LOOKS_LIKE_DEGREES` = 1 rad) is refused;
    a smaller one is capped with a warning.

    Raises:
        InputError: ``constraints.joint_limits.threshold``, naming the joint.
    """
    if threshold < LOOKS_LIKE_DEGREES:
        return
    limits = JointLimits(robot, override=override, warn_cap=False)
    for name, kind, lo, hi in zip(
        limits.joint_names, limits.kinds, limits.lower, limits.upper, strict=True
    ):
        if kind == REVOLUTE and threshold > hi - lo:
            raise InputError(
                "constraints.joint_limits.threshold",
                f"an angle [rad] smaller than {name}'s range ({hi - lo:.4g} rad)"
                + degrees_hint(threshold),
                threshold,
            )


def _dexterity(scenario: Scenario, spec: dict[str, Any]) -> Dexterity | None:
    """The ``[constraints.dexterity]`` row (:class:`Dexterity`), or None when not enabled."""
    if not spec["enabled"]:
        return None
    try:
        return Dexterity(spec["threshold"])
    except InputError as exc:
        raise ScenarioError(scenario.file, exc.field, str(exc)) from None


def _table_kinds(scenario: Scenario, robot: Robot) -> list[ConstraintKind]:
    """The ``[[constraints.<table>]]`` kinds (:data:`~clik.constraints.registry.TABLE_KINDS`)."""
    out: list[ConstraintKind] = []
    tables = scenario.constraints.get("kinds", {})
    for kind in TABLE_KINDS:
        for i, spec in enumerate(tables.get(kind.table, [])):
            where = f"constraints.{kind.table}[{i}]"
            try:
                out.append(kind.from_spec(robot, spec))
            except FrameNotFound as exc:
                raise ScenarioError(scenario.file, f"{where}.frame", str(exc)) from None
            except InputError as exc:
                field = exc.field.replace(f"constraints.{kind.table}", where, 1)
                message = str(exc).removeprefix(f"{exc.field}: ")
                raise ScenarioError(scenario.file, field, message) from None
    return out
