"""Scenario files: one TOML file names everything a run needs.

The keys are a contract (see the README). Relative paths resolve against the
scenario file's folder. A scenario is validated completely before anything
is computed: an unknown key, a wrong type, a missing required field or an
out-of-range value raises :class:`~clik.errors.ScenarioError` naming the file,
the key path (e.g. ``trajectory.duration``) and what was expected.

Angles are given in the table's ``unit`` (``"rad"`` by default, or
``"deg"``) and converted once, here, except joint values: ``unit`` applies to
revolute (and continuous) joints only, prismatic joints' values are metres, and
which joint is which is known only with the robot. So ``initial.q`` is kept as
a :class:`~clik.model.joints.JointValues` (the values as written and their unit) that
:meth:`Robot.check_configuration <clik.model.robot.Robot.check_configuration>`
converts per joint, and ``[constraints.joint_limits]`` keeps its overrides as written
beside their conversion to radians, for :func:`~clik.scenarios.build_constraints.build_constraints`
to pick per joint.

One task is ``[task]`` and ``[trajectory]``; several are ``[[tasks]]``, each with its
``[tasks.trajectory]``, and ``[[objectives]]`` add eq. (5)'s null-space terms
(:mod:`clik.scenarios.task_tables`). ``[task]`` and ``[[tasks]]`` together are refused.

A scenario is data only: TOML has no code, no includes and no variables, and
no key here names a file to read but ``robot.source``, ``robot.package_dirs``,
``robot.srdf`` and an obstacle's mesh or cloud ``file``: paths the user chose (absolute, or relative
to the scenario's folder; URLs are refused, nothing is fetched). A xacro
``robot.source`` (``.xacro``) takes ``robot.xacro_args``, a table of strings, which
also expand an SRDF with xacro markup (``robot.srdf = "arm.srdf.xacro"``).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clik.bounds import MAX_STEPS, SCALE_RANGE
from clik.constraints.registry import TABLE_KINDS
from clik.engine import ENGINES
from clik.errors import ScenarioError
from clik.model.base import BASES, FIXED, check_base_speed
from clik.model.joints import JointValues
from clik.model.xacro_expand import is_xacro
from clik.scenarios.cloud_table import cloud_keys
from clik.scenarios.fields import gain_value
from clik.scenarios.ros_table import ros_table
from clik.scenarios.speed_tables import joint_speed_table, velocity_limits_table
from clik.scenarios.task_tables import finish_tasks, primary, read_objectives, read_tasks
from clik.scenarios.tolerance import read_tolerance
from clik.schema import (
    MAX_ANGLE,
    MAX_JOINT_VALUE,
    MAX_LENGTH,
    MAX_SPEED,
    MIN_SAMPLES,
    Table,
)
from clik.tasks.task import frame_table, has_orientation_rows
from clik.trajectory.tables import UNITS, angle_scale, strings, trajectory_table

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SHAPES = ("sphere", "box", "capsule", "cylinder", "mesh", "cloud")


PRISMATIC_THRESHOLD = 0.005
"""Default ``[constraints.joint_limits] prismatic_threshold`` [m]."""


@dataclass
class Scenario:
    """A validated scenario. Angles are in radians, lengths in metres, times in seconds.

    Joint values are the exception (see the module's docstring): ``initial_q`` is
    a :class:`~clik.model.joints.JointValues` (the values as written and their ``unit``),
    a string ``"srdf:NAME"`` (the SRDF group state ``NAME``, converted by
    :meth:`Robot.check_configuration <clik.model.robot.Robot.check_configuration>`)
    or None for the reference configuration, and
    ``constraints["joint_limits"]`` has ``override`` (scaled as angles [rad]),
    ``override_as_written`` (in ``unit`` for revolute joints, metres for
    prismatic ones), ``unit``, ``threshold`` [rad] (revolute joints) and
    ``prismatic_threshold`` [m].
    """

    file: Path
    name: str
    robot: dict[str, Any]
    initial_q: JointValues | str | None
    task: dict[str, Any]
    trajectory: dict[str, Any]
    solver: dict[str, Any]
    obstacles: list[dict[str, Any]] = field(default_factory=list)
    constraints: dict[str, Any] = field(default_factory=dict)
    velocity_limits: dict[str, Any] = field(default_factory=dict)
    """The ``[constraints.velocity_limits]`` table (:func:`_velocity_limits`), kept apart from
    ``constraints`` because it adds no constraint row: it re-times the reference."""
    joint_speed: dict[str, Any] = field(default_factory=lambda: {"enabled": True})
    """The ``[constraints.joint_speed]`` table
    (:func:`~clik.scenarios.speed_tables.joint_speed_table`): the joint speed limits the
    law keeps (on by default)."""
    tasks: list[dict[str, Any]] = field(default_factory=list)
    """The ``[[tasks]]`` tables (:mod:`clik.scenarios.task_tables`); empty with ``[task]``.
    With ``[[tasks]]``, ``task`` and ``trajectory`` are the primary task's."""
    objectives: list[dict[str, Any]] = field(default_factory=list)
    """The ``[[objectives]]`` tables (eq. (5), law (10))."""
    ros: dict[str, Any] = field(default_factory=dict)
    """The ``[ros]`` table (:func:`clik.scenarios.ros_table.ros_table`): read by ``clik ros``."""
    raw: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def folder(self) -> Path:
        """Folder that relative paths resolve against."""
        return self.file.parent

    @property
    def has_constraints(self) -> bool:
        """Whether the run needs a constraint set: obstacles, an enabled table, or a kind's."""
        tables = self.constraints.values()
        return bool(
            self.obstacles
            or any(c.get("enabled") for c in tables if isinstance(c, dict))
            or any(self.constraints.get("kinds", {}).values())
        )


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(path, "", "no such scenario file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8").removeprefix("\ufeff"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(path, "", f"not valid TOML ({exc})") from None
    except RecursionError:  # tomllib recurses on nested arrays and inline tables
        raise ScenarioError(
            path, "", "not valid TOML (arrays or tables nested too deeply)"
        ) from None
    return parse_scenario(data, path)


def _resolve(folder: Path, value: str) -> str:
    p = Path(value).expanduser()
    return str(p if p.is_absolute() else (folder / p))


def parse_scenario(data: dict[str, Any], file: str | Path) -> Scenario:
    """Validate a scenario given as a dict (as read from TOML)."""
    file = Path(file)
    folder = file.parent
    top = Table(data, file)
    name = top.string("name", file.stem)

    robot = _robot(top.table("robot", required=True), folder)

    ini = top.table("initial")
    unit = ini.string("unit", "rad", UNITS)
    q_raw = ini.raw("q", "reference")
    q_bound = MAX_JOINT_VALUE / angle_scale(ini)
    initial_q: JointValues | str | None = None
    if isinstance(q_raw, str):
        if q_raw != "reference" and not _group_state_name(q_raw):
            raise ini.error(
                "q", "'reference', 'srdf:NAME' (a group state) or a list of joint values", q_raw
            )
        initial_q = None if q_raw == "reference" else q_raw
    else:
        initial_q = JointValues(ini.vector("q", bound=q_bound), unit)
    ini.done()

    if top.has("tasks"):
        tasks, task, trajectory, solver = _several_tasks(top, folder)
    else:
        tasks, (task, trajectory) = [], _single_task(top, folder)
        solver = _solver(top.table("solver"), trajectory["duration"])
    objectives = read_objectives(top.tables("objectives"), solver["law"])

    obstacles = [_obstacle(t, folder) for t in top.tables("obstacles")]
    names = [o["name"] for o in obstacles]
    if len(set(names)) != len(names):
        raise ScenarioError(file, "obstacles", f"expected distinct obstacle names, got {names}")
    constraints = _constraints(top.table("constraints"), solver["dt"])
    velocity_limits = constraints.pop("velocity_limits")
    joint_speed = constraints.pop("joint_speed")
    if tasks and velocity_limits["enabled"]:
        raise ScenarioError(
            file, "constraints.velocity_limits.enabled", "false with [[tasks]] (re-timing "
            "slows one trajectory; several tasks have several)",
        )  # fmt: skip
    ros = ros_table(top.table("ros"))
    top.done()
    return Scenario(
        file, name, robot, initial_q, task, trajectory, solver, obstacles, constraints,
        velocity_limits=velocity_limits, joint_speed=joint_speed, tasks=tasks,
        objectives=objectives, ros=ros, raw=data,
    )  # fmt: skip


def _single_task(top: Table, folder: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """``[task]`` and ``[trajectory]``: one frame task and its trajectory."""
    tsk = top.table("task", required=True)
    task = frame_table(tsk)
    tsk.done()
    has_orientation = has_orientation_rows(task["kind"], task["axes"])
    return task, trajectory_table(top.table("trajectory", required=True), folder, has_orientation)


def _several_tasks(top: Table, folder: Path) -> tuple[Any, ...]:
    """``[[tasks]]`` (:mod:`clik.scenarios.task_tables`) and ``[solver]``.

    Returns:
        The tasks, the primary's ``task`` and ``trajectory`` tables (what ``[task]`` and
        ``[trajectory]`` hold for one task), and the solver.
    """
    for key, expected in (
        ("task", "either [task] (one task) or [[tasks]] (several), not both"),
        ("trajectory", "no [trajectory] with [[tasks]] (each has its [tasks.trajectory])"),
    ):
        if top.has(key):
            raise ScenarioError(top.file, key, f"expected {expected}; this file has both")
    tables = top.tables("tasks")
    if not tables:
        raise top.error("tasks", "at least one [[tasks]] table", [])
    tasks = read_tasks(tables, folder)
    durations = [t["trajectory"]["duration"] for t in tasks]
    known = [d for d in durations if d is not None]
    solver = _solver(top.table("solver"), max(known) if known else None)
    finish_tasks(tables, tasks, solver)
    main = primary(tasks)
    task = {key: main[key] for key in ("frame", "kind", "axes")}
    return tasks, task, main["trajectory"], solver


def _solver(slv: Table, duration: float | None) -> dict[str, Any]:
    """The ``[solver]`` table; ``duration`` [s] (None: from ``cruise_speed``) bounds ``dt``."""
    dt = slv.number("dt", 1e-3, minimum=0.0, strict=True, unit="[s]")
    if duration is not None:
        check_dt(slv, dt, duration)
    solver = {
        "law": slv.string("law", "transpose", ("transpose", "nonlinear", "pseudoinverse")),
        "gain": gain_value(slv, "gain", dt, 1000.0),
        "dt": dt,
        "damping": slv.number("damping", 0.0, minimum=0.0, bound=MAX_LENGTH),
        "record_every": slv.number("record_every", 1, minimum=1, integer=True),
        "settle": slv.number("settle", 0.0, minimum=0.0, unit="[s]"),
        "engine": slv.string("engine", "compiled", ENGINES),
        **read_tolerance(slv),
    }
    if duration is not None:
        steps = (duration + solver["settle"]) / dt + 1
        if steps > MAX_STEPS:
            total = duration + solver["settle"]
            raise slv.error(
                "dt",
                f"a step giving at most {MAX_STEPS:.0e} steps over trajectory.duration + "
                f"solver.settle = {total:g} s (this one gives {steps:.3g})",
                dt,
            )
    slv.done()
    return solver


def check_dt(slv: Table, dt: float, duration: float) -> None:
    """Refuse a ``solver.dt`` that leaves fewer than ``MIN_SAMPLES`` samples in ``duration``."""
    if duration > 0.0 and dt * MIN_SAMPLES > duration * (1.0 + 1e-12):
        raise slv.error(
            "dt",
            f"a step of at most trajectory.duration / {MIN_SAMPLES} = "
            f"{duration / MIN_SAMPLES:g} s (at least {MIN_SAMPLES} samples to track)",
            dt,
        )


def _group_state_name(value: str) -> str:
    """``NAME`` of an ``initial.q = "srdf:NAME"``, or ``""`` for another string."""
    prefix, _, name = value.partition(":")
    return name if prefix == "srdf" and name.strip() == name else ""


def _srdf(rob: Table, folder: Path) -> str | bool | None:
    """``robot.srdf``: a path (resolved like ``source``), false (none) or None (the robot's own)."""
    value = rob.raw("srdf", None)
    if value is None or value is False:
        return value
    expected = "an SRDF file path, or false (not even the robot's own SRDF)"
    if not isinstance(value, str) or not value.strip() or "://" in value:
        raise rob.error("srdf", expected + " (URLs are not fetched)", value)
    return _resolve(folder, value)


def _base_speed(rob: Table) -> list[float] | None:
    """``robot.base_speed``: ``[linear m/s, angular rad/s]``, or None (the defaults)."""
    value = rob.vector("base_speed", 2, None, "[m/s, rad/s]", MAX_SPEED)
    if value is not None and not all(v > 0.0 for v in value):
        raise rob.error("base_speed", "two positive speeds [m/s, rad/s]", value)
    return None if value is None else list(check_base_speed(value, "robot.base_speed"))


def _robot(rob: Table, folder: Path) -> dict[str, Any]:
    """The ``[robot]`` table: the robot, its files, locked joints and base.

    Keys ``source``, ``package_dirs``, ``lock``, ``xacro_args``, ``srdf``, ``base``
    (``"fixed"``, ``"planar"``, ``"floating"``) and ``base_speed`` ([m/s, rad/s]).
    """
    source = rob.string("source")
    if "://" in source:
        raise rob.error("source", "a robot name or a URDF path (URLs are not fetched)", source)
    suffixes = (".urdf", ".xacro", ".xml")  # .xml: an MJCF model (or a URDF)
    looks_like_path = source.endswith(suffixes) or "/" in source or "\\" in source
    robot = {
        "source": _resolve(folder, source) if looks_like_path else source,
        "package_dirs": [_resolve(folder, p) for p in strings(rob, "package_dirs")],
        "lock": rob.mapping("lock", lambda t, k: float(t.number(k, bound=MAX_JOINT_VALUE))),
        "xacro_args": rob.mapping("xacro_args", lambda t, k: t.string(k)),
        "srdf": _srdf(rob, folder),
        "base": rob.string("base", FIXED, BASES),
        "base_speed": _base_speed(rob),
    }
    if robot["base_speed"] is not None and robot["base"] == FIXED:
        raise rob.error("base_speed", "no base_speed: robot.base is 'fixed' (no base to move)")
    srdf = robot["srdf"]
    if robot["xacro_args"] and not is_xacro(source) and not (srdf and is_xacro(str(srdf))):
        raise rob.error(
            "xacro_args",
            "no xacro_args: robot.source is not a xacro file (name ending .xacro), nor robot.srdf",
        )
    rob.done()
    return robot


def _obstacle(ob: Table, folder: Path) -> dict[str, Any]:
    shape = ob.string("shape", choices=SHAPES)
    out: dict[str, Any] = {
        "name": ob.string("name"),
        "shape": shape,
        "position": ob.vector("position", 3, unit="[m]", bound=MAX_LENGTH),
    }
    scale = angle_scale(ob)
    rpy = ob.vector("rpy", 3, [0.0, 0.0, 0.0], bound=MAX_ANGLE / scale)
    out["rpy"] = [v * scale for v in rpy]
    out["threshold"] = _length(ob, "threshold", None, strict=True)
    if shape == "cloud":  # at rest, read when the run is built (clik.scenarios.cloud_table)
        out.update(cloud_keys(ob))
        out["file"] = _resolve(folder, out["file"])
        ob.done()
        return out
    out["velocity"] = ob.vector("velocity", 3, [0.0, 0.0, 0.0], "[m/s]", MAX_SPEED)
    if shape == "sphere":
        out["radius"] = _length(ob, "radius")
    elif shape == "box":
        size = ob.vector("size", 3, unit="[m]", bound=MAX_LENGTH)
        if any(s <= 0 for s in size):
            raise ob.error("size", "three positive side lengths [m]", size)
        out["size"] = size
    elif shape in ("capsule", "cylinder"):
        out["radius"] = _length(ob, "radius", strict=shape == "cylinder")
        out["length"] = _length(ob, "length", strict=shape == "cylinder")
    else:
        file = ob.string("file")
        out["file"] = _resolve(Path(ob.file).parent, file)
        out["scale"] = ob.vector("scale", 3, [1.0, 1.0, 1.0])
        low, high = SCALE_RANGE
        if any(not low <= abs(v) <= high for v in out["scale"]):
            raise ob.error("scale", f"three scale factors of magnitude in [{low:g}, {high:g}]",
                           out["scale"])  # fmt: skip
    ob.done()
    return out


def _length(table: Table, name: str, default: Any = ..., strict: bool = False) -> Any:
    """A length [m] in ``[0, MAX_LENGTH]`` (``> 0`` when ``strict``); ``...``: required."""
    if default is ...:
        return table.number(name, minimum=0.0, strict=strict, unit="[m]", bound=MAX_LENGTH)
    return table.number(name, default, minimum=0.0, strict=strict, unit="[m]", bound=MAX_LENGTH)


def _constraints(ct: Table, dt: float) -> dict[str, Any]:
    """The ``[constraints]`` table; ``dt`` [s] bounds the rows' gains (``gain * dt``)."""
    out: dict[str, Any] = {}
    obs = ct.table("obstacles")
    out["obstacles"] = {
        "enabled": obs.boolean("enabled", False),
        "threshold": _length(obs, "threshold", 0.03, strict=True),
        "gain": _scalar_gain(obs, dt),
        "form": obs.string("form", "normalized", ("normalized", "squared")),
        "release": obs.string("release", None, ("projection", "sign")),
        "links": strings(obs, "links") or None,
    }
    obs.done()
    jl = ct.table("joint_limits")
    unit = jl.string("unit", "rad", UNITS)
    scale = angle_scale(jl)
    written: dict[str, dict[str, float]] = {}
    ov = jl.table("override")
    for joint in list(ov.data):
        sub = ov.table(joint)
        lim = {k: sub.number(k, None, bound=MAX_JOINT_VALUE / scale) for k in ("lower", "upper")}
        sub.done()
        written[joint] = {k: float(v) for k, v in lim.items() if v is not None}
    out["joint_limits"] = {
        "enabled": jl.boolean("enabled", False),
        "threshold": jl.number(
            "threshold",
            2.0 if scale != 1.0 else math.radians(2.0),
            minimum=0.0,
            strict=True,
            unit=f"[{unit}] (revolute joints)",
            bound=MAX_ANGLE / scale,
        )
        * scale,
        "prismatic_threshold": float(
            jl.number(
                "prismatic_threshold",
                PRISMATIC_THRESHOLD,
                minimum=0.0,
                strict=True,
                unit="[m] (prismatic joints)",
                bound=MAX_LENGTH,
            )
        ),
        "gain": _scalar_gain(jl, dt),
        "override": {j: {k: v * scale for k, v in lim.items()} for j, lim in written.items()},
        "override_as_written": written,
        "unit": unit,
    }
    jl.done()
    sc = ct.table("self_collision")
    out["self_collision"] = {
        "enabled": sc.boolean("enabled", False),
        "threshold": _length(sc, "threshold", 0.01, strict=True),
        "gain": _scalar_gain(sc, dt),
    }
    sc.done()
    out["dexterity"] = _dexterity(ct.table("dexterity"), dt)
    out["kinds"] = {
        kind.table: [kind.read_table(t, dt) for t in ct.tables(kind.table)]
        for kind in TABLE_KINDS
        if kind.table is not None
    }
    out["velocity_limits"] = velocity_limits_table(ct.table("velocity_limits"))
    out["joint_speed"] = joint_speed_table(ct.table("joint_speed"))
    out["release"] = ct.string("release", "projection", ("projection", "sign"))
    out["hysteresis"] = ct.number("hysteresis", 0.0, minimum=0.0, bound=MAX_LENGTH)
    out["max_active"] = ct.number("max_active", None, minimum=1, integer=True)
    ct.done()
    return out


def _scalar_gain(table: Table, dt: float) -> Any:
    """A constraint row's optional ``gain`` [1/s] (> 0, ``gain * dt <= MAX_GAIN_DT``)."""
    value = table.raw("gain", None)
    if isinstance(value, list):
        raise table.error("gain", "a number > 0 [1/s]", value)
    return gain_value(table, "gain", dt)


def _dexterity(dx: Table, dt: float) -> dict[str, Any]:
    """``[constraints.dexterity]``: keep the task's manipulability ``w >= threshold`` (D1)-(D3).

    Keys: ``enabled`` (default false), ``threshold`` (``w_min`` > 0 [m^p], required when
    enabled), ``gain`` (> 0 [1/s], default: the law's).
    """
    enabled = dx.boolean("enabled", False)
    unit = "[m^p] (the task's manipulability)"
    if enabled:
        threshold = dx.number("threshold", minimum=0.0, strict=True, unit=unit)
    else:
        threshold = dx.number("threshold", None, minimum=0.0, strict=True, unit=unit)
    out = {
        "enabled": enabled,
        "threshold": None if threshold is None else float(threshold),
        "gain": _scalar_gain(dx, dt),
    }
    dx.done()
    return out
