"""Build a :class:`ConstraintSet` from a scenario's ``[[obstacles]]`` and ``[constraints]``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits, convert_override
from clik.constraints.obstacle import Obstacle
from clik.errors import ClikError, GeometryError, InputError, JointNotFound, ScenarioError
from clik.robot import PRISMATIC, REVOLUTE

if TYPE_CHECKING:
    from clik.robot import Robot
    from clik.scenario import Scenario
    from clik.task import Task


def build_constraints(scenario: Scenario, robot: Robot, task: Task) -> ConstraintSet:
    """The scenario's obstacles (always monitored) and enabled constraint rows.

    Joint-range rows (:class:`JointLimits`): ``threshold`` [rad] is the revolute
    joints' ``d_q`` and ``prismatic_threshold`` [m] the prismatic joints' (each
    capped at a quarter of the joint's range); an override is read in the
    table's ``unit`` for a revolute joint and in metres for a prismatic one.
    The dexterity row (:class:`Dexterity`) keeps the task's manipulability above
    ``[constraints.dexterity] threshold``.
    """
    obstacles = []
    for i, spec in enumerate(scenario.obstacles):
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
    joint_limits = None
    if jl_spec["enabled"] or jl_spec["override"]:  # a bad override is an error even when off
        _check_thresholds(scenario, robot, jl_spec)
        try:
            override = jl_spec["override"]
            if "override_as_written" in jl_spec:  # parse_scenario's; older dicts: radians
                override = convert_override(
                    robot, jl_spec["override_as_written"], jl_spec.get("unit", "rad")
                )
            joint_limits = JointLimits(
                robot,
                jl_spec["threshold"],
                override,
                prismatic_threshold=jl_spec.get("prismatic_threshold"),
            )
        except JointNotFound as exc:
            raise ScenarioError(
                scenario.file, "constraints.joint_limits.override", str(exc)
            ) from None
        except InputError as exc:
            raise ScenarioError(scenario.file, exc.field, str(exc)) from None
        if not jl_spec["enabled"]:
            joint_limits = None
    dx_spec = c.get("dexterity") or {"enabled": False, "gain": None}
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
            release=release,
            hysteresis=c["hysteresis"],
            max_active=c["max_active"],
        )
    except ClikError as exc:
        raise ScenarioError(scenario.file, "constraints", str(exc)) from None


def _check_thresholds(scenario: Scenario, robot: Robot, spec: dict[str, Any]) -> None:
    """Refuse a joint-range threshold no joint can use: at least every joint's whole range.

    A threshold is capped at a quarter of each joint's range (:class:`JointLimits`), so a
    somewhat large one still works; one as large as the widest range of its kind of joint
    (``1e300``) is a typo, named by its key.
    """
    kinds = robot.joint_kinds
    for kind, key, unit in (
        (REVOLUTE, "threshold", "rad"),
        (PRISMATIC, "prismatic_threshold", "m"),
    ):
        threshold = spec.get(key)
        ranges = [
            robot.upper[j.idx_q] - robot.lower[j.idx_q]
            for name, j in zip(robot.joint_names, robot.model.joints[1:], strict=True)
            if kinds[name] == kind
        ]
        ranges = [h for h in ranges if math.isfinite(h) and h > 0.0]
        if threshold is None or not ranges or threshold < max(ranges):
            continue
        raise ScenarioError(
            scenario.file,
            f"constraints.joint_limits.{key}",
            f"expected a threshold smaller than a {kind} joint's range (the widest range "
            f"of {robot.name} is {max(ranges):.6g} {unit}), got {threshold:.6g} {unit}",
        )


def _dexterity(scenario: Scenario, spec: dict[str, Any]) -> Dexterity | None:
    """The ``[constraints.dexterity]`` row (:class:`Dexterity`), or None when not enabled."""
    if not spec["enabled"]:
        return None
    try:
        return Dexterity(spec["threshold"])
    except InputError as exc:
        raise ScenarioError(scenario.file, exc.field, str(exc)) from None
