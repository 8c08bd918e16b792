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
a :class:`~clik.robot.JointValues` (the values as written and their unit) that
:meth:`Robot.check_configuration <clik.robot.Robot.check_configuration>`
converts per joint, and ``[constraints.joint_limits]`` keeps its overrides as written
beside their conversion to radians, for :func:`~clik.constraints.build.build_constraints`
to pick per joint.

A scenario is data only: TOML has no code, no includes and no variables, and
no key here names a file to read but ``robot.source``, ``robot.package_dirs``
and an obstacle's mesh ``file``: paths the user chose (absolute, or relative
to the scenario's folder; URLs are refused, nothing is fetched). A xacro
``robot.source`` (``.xacro``) takes ``robot.xacro_args``, a table of strings.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from clik.bounds import MAX_STEPS
from clik.engine import ENGINES
from clik.errors import ClikError, ScenarioError
from clik.robot import JointValues
from clik.schema import Table
from clik.speed_limits import MAX_PASSES, MAX_SCALE
from clik.xacro_expand import is_xacro

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TRAJECTORY_KINDS = ("line", "circle", "waypoints", "hold")

SHAPES = ("sphere", "box", "capsule", "cylinder", "mesh")
UNITS = ("rad", "deg")


PRISMATIC_THRESHOLD = 0.005
"""Default ``[constraints.joint_limits] prismatic_threshold`` [m]."""


def _angle_scale(table: Table) -> float:
    return math.pi / 180.0 if table.string("unit", "rad", UNITS) == "deg" else 1.0


@dataclass
class Scenario:
    """A validated scenario. Angles are in radians, lengths in metres, times in seconds.

    Joint values are the exception (see the module's docstring): ``initial_q`` is
    a :class:`~clik.robot.JointValues` (the values as written and their ``unit``)
    or None for the reference configuration, and
    ``constraints["joint_limits"]`` has ``override`` (scaled as angles [rad]),
    ``override_as_written`` (in ``unit`` for revolute joints, metres for
    prismatic ones), ``unit``, ``threshold`` [rad] (revolute joints) and
    ``prismatic_threshold`` [m].
    """

    file: Path
    name: str
    robot: dict[str, Any]
    initial_q: JointValues | None
    task: dict[str, Any]
    trajectory: dict[str, Any]
    solver: dict[str, Any]
    obstacles: list[dict[str, Any]] = field(default_factory=list)
    constraints: dict[str, Any] = field(default_factory=dict)
    velocity_limits: dict[str, Any] = field(default_factory=dict)
    """The ``[constraints.velocity_limits]`` table (:func:`_velocity_limits`), kept apart from
    ``constraints`` because it adds no constraint row: it re-times the reference."""
    raw: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def folder(self) -> Path:
        """Folder that relative paths resolve against."""
        return self.file.parent


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(path, "", "no such scenario file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
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
    initial_q = None if q_raw == "reference" else JointValues(ini.vector("q"), unit)
    ini.done()

    tsk = top.table("task", required=True)
    task = {
        "frame": tsk.string("frame"),
        "kind": tsk.string("kind", "pose", ("position", "orientation", "pose")),
        "axes": _strings(tsk, "axes") or None,
    }
    if tsk.has("axes") and task["axes"] is None:
        raise tsk.error("axes", "a non-empty list of axis names (omit it for every axis)", [])
    tsk.done()
    has_orientation = task["kind"] != "position" and (
        task["axes"] is None or any(a.startswith("r") for a in task["axes"])
    )

    trajectory = _trajectory(top.table("trajectory", required=True), folder, has_orientation)

    slv = top.table("solver")
    gain = slv.raw("gain", 1000.0)
    if isinstance(gain, list):
        gain = slv.vector("gain")
        if any(g <= 0 for g in gain):
            raise slv.error("gain", "positive numbers [1/s]", gain)
    else:
        gain = slv.number("gain", 1000.0, minimum=0.0, strict=True, unit="[1/s]")
    solver = {
        "law": slv.string("law", "transpose", ("transpose", "nonlinear", "pseudoinverse")),
        "gain": gain,
        "dt": slv.number("dt", 1e-3, minimum=0.0, strict=True, unit="[s]"),
        "damping": slv.number("damping", 0.0, minimum=0.0),
        "record_every": slv.number("record_every", 1, minimum=1, integer=True),
        "settle": slv.number("settle", 0.0, minimum=0.0, unit="[s]"),
        "engine": slv.string("engine", "compiled", ENGINES),
    }
    if trajectory["duration"] is not None:
        steps = (trajectory["duration"] + solver["settle"]) / solver["dt"] + 1
        if steps > MAX_STEPS:
            total = trajectory["duration"] + solver["settle"]
            raise slv.error(
                "dt",
                f"a step giving at most {MAX_STEPS:.0e} steps over trajectory.duration + "
                f"solver.settle = {total:g} s (this one gives {steps:.3g})",
                solver["dt"],
            )
    slv.done()

    obstacles = [_obstacle(t, folder) for t in top.tables("obstacles")]
    names = [o["name"] for o in obstacles]
    if len(set(names)) != len(names):
        raise ScenarioError(file, "obstacles", f"expected distinct obstacle names, got {names}")
    constraints = _constraints(top.table("constraints"))
    velocity_limits = constraints.pop("velocity_limits")
    top.done()
    return Scenario(
        file, name, robot, initial_q, task, trajectory, solver, obstacles, constraints,
        velocity_limits=velocity_limits, raw=data,
    )  # fmt: skip


def _robot(rob: Table, folder: Path) -> dict[str, Any]:
    """The ``[robot]`` table: ``source``, ``package_dirs``, ``lock``, ``xacro_args``."""
    source = rob.string("source")
    if "://" in source:
        raise rob.error("source", "a robot name or a URDF path (URLs are not fetched)", source)
    looks_like_path = source.endswith((".urdf", ".xacro")) or "/" in source or "\\" in source
    robot = {
        "source": _resolve(folder, source) if looks_like_path else source,
        "package_dirs": [_resolve(folder, p) for p in _strings(rob, "package_dirs")],
        "lock": rob.mapping("lock", lambda t, k: float(t.number(k))),
        "xacro_args": rob.mapping("xacro_args", lambda t, k: t.string(k)),
    }
    if robot["xacro_args"] and not is_xacro(source):
        raise rob.error(
            "xacro_args", "no xacro_args: robot.source is not a xacro file (name ending .xacro)"
        )
    rob.done()
    return robot


def _strings(table: Table, name: str) -> list[str]:
    value = table.raw(name, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise table.error(name, "a list of strings", value)
    return value


def _trajectory(tr: Table, folder: Path, has_orientation: bool = True) -> dict[str, Any]:
    kind = tr.string("kind", choices=TRAJECTORY_KINDS)
    scale = _angle_scale(tr)
    out: dict[str, Any] = {"kind": kind}
    out["start"] = tr.vector("start", 3, None, "[m]")
    if kind in ("line", "hold"):
        out["goal"] = tr.vector("goal", 3, None if kind == "hold" else ..., "[m]")
        if out["goal"] is ...:
            raise tr.error("goal", "a list of 3 numbers [m]")
    if kind == "circle":
        out["center"] = tr.vector("center", 3, unit="[m]")
        out["normal"] = tr.vector("normal", 3, [0.0, 0.0, 1.0])
        if np.linalg.norm(out["normal"]) == 0.0:
            raise tr.error("normal", "a non-zero vector", out["normal"])
        angle = tr.number("angle", None)
        out["angle"] = 2.0 * math.pi if angle is None else angle * scale
        if out["angle"] == 0.0:
            raise tr.error("angle", "a non-zero angle", angle)
    if kind == "waypoints":
        out["points"] = tr.matrix("points", 3, unit="[m]")
        out["blend_radius"] = tr.number("blend_radius", 0.0, minimum=0.0, unit="[m]")
    out["duration"] = tr.number("duration", None, minimum=0.0, strict=kind != "hold", unit="[s]")
    if kind != "hold":
        out["cruise_speed"] = tr.number("cruise_speed", None, minimum=0.0, strict=True)
    if kind == "hold" and out["duration"] is None:
        raise tr.error("duration", "a number >= 0 [s]")
    if kind != "hold" and out["duration"] is None and out.get("cruise_speed") is None:
        raise tr.error("duration", "a duration [s] or a cruise_speed")
    rpy = tr.vector("goal_rpy", 3, None)
    if rpy is not None and not has_orientation:
        raise tr.error("goal_rpy", "no goal_rpy: the task has no orientation rows", rpy)
    out["goal_rpy"] = None if rpy is None else [v * scale for v in rpy]
    tr.done()
    return out


def _obstacle(ob: Table, folder: Path) -> dict[str, Any]:
    shape = ob.string("shape", choices=SHAPES)
    out: dict[str, Any] = {
        "name": ob.string("name"),
        "shape": shape,
        "position": ob.vector("position", 3, unit="[m]"),
    }
    scale = _angle_scale(ob)
    rpy = ob.vector("rpy", 3, [0.0, 0.0, 0.0])
    out["rpy"] = [v * scale for v in rpy]
    out["velocity"] = ob.vector("velocity", 3, [0.0, 0.0, 0.0], "[m/s]")
    out["threshold"] = ob.number("threshold", None, minimum=0.0, strict=True, unit="[m]")
    if shape == "sphere":
        out["radius"] = ob.number("radius", minimum=0.0, unit="[m]")
    elif shape == "box":
        size = ob.vector("size", 3, unit="[m]")
        if any(s <= 0 for s in size):
            raise ob.error("size", "three positive side lengths [m]", size)
        out["size"] = size
    elif shape in ("capsule", "cylinder"):
        out["radius"] = ob.number("radius", minimum=0.0, strict=shape == "cylinder", unit="[m]")
        out["length"] = ob.number("length", minimum=0.0, strict=shape == "cylinder", unit="[m]")
    else:
        file = ob.string("file")
        out["file"] = _resolve(Path(ob.file).parent, file)
        out["scale"] = ob.vector("scale", 3, [1.0, 1.0, 1.0])
    ob.done()
    return out


def _constraints(ct: Table) -> dict[str, Any]:
    out: dict[str, Any] = {}
    obs = ct.table("obstacles")
    out["obstacles"] = {
        "enabled": obs.boolean("enabled", False),
        "threshold": obs.number("threshold", 0.03, minimum=0.0, strict=True, unit="[m]"),
        "gain": obs.number("gain", None, minimum=0.0, strict=True, unit="[1/s]"),
        "form": obs.string("form", "normalized", ("normalized", "squared")),
        "release": obs.string("release", None, ("projection", "sign")),
        "links": _strings(obs, "links") or None,
    }
    obs.done()
    jl = ct.table("joint_limits")
    unit = jl.string("unit", "rad", UNITS)
    scale = _angle_scale(jl)
    written: dict[str, dict[str, float]] = {}
    ov = jl.table("override")
    for joint in list(ov.data):
        sub = ov.table(joint)
        lim = {k: sub.number(k, None) for k in ("lower", "upper")}
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
        )
        * scale,
        "prismatic_threshold": float(
            jl.number(
                "prismatic_threshold",
                PRISMATIC_THRESHOLD,
                minimum=0.0,
                strict=True,
                unit="[m] (prismatic joints)",
            )
        ),
        "gain": jl.number("gain", None, minimum=0.0, strict=True, unit="[1/s]"),
        "override": {j: {k: v * scale for k, v in lim.items()} for j, lim in written.items()},
        "override_as_written": written,
        "unit": unit,
    }
    jl.done()
    sc = ct.table("self_collision")
    out["self_collision"] = {
        "enabled": sc.boolean("enabled", False),
        "threshold": sc.number("threshold", 0.01, minimum=0.0, strict=True, unit="[m]"),
        "gain": sc.number("gain", None, minimum=0.0, strict=True, unit="[1/s]"),
    }
    sc.done()
    out["dexterity"] = _dexterity(ct.table("dexterity"))
    out["velocity_limits"] = _velocity_limits(ct.table("velocity_limits"))
    out["release"] = ct.string("release", "projection", ("projection", "sign"))
    out["hysteresis"] = ct.number("hysteresis", 0.0, minimum=0.0)
    out["max_active"] = ct.number("max_active", None, minimum=0, integer=True)
    ct.done()
    return out


def _dexterity(dx: Table) -> dict[str, Any]:
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
        "gain": dx.number("gain", None, minimum=0.0, strict=True, unit="[1/s]"),
    }
    dx.done()
    return out


def _velocity_limits(vl: Table) -> dict[str, Any]:
    """``[constraints.velocity_limits]``: respect the URDF joint speed limits (time scaling).

    Keys: ``enabled`` (default false), ``scale`` (fraction of the URDF velocity limit,
    ``0 < scale <= 10``, default 1), ``acceleration`` (one limit for every joint or a
    table joint -> limit [rad/s^2 or m/s^2]; default none), ``margin`` (in [0, 1],
    default 0.05), ``max_passes`` (1..20, default 6), ``window`` ([s], default 0.05).
    Checked whether enabled or not.
    """
    accel_unit = "[rad/s^2 or m/s^2]"
    scale = vl.number("scale", 1.0, minimum=0.0, strict=True)
    if scale > MAX_SCALE:
        raise vl.error("scale", f"a number > 0 and <= {MAX_SCALE:g} (of the URDF limit)", scale)
    acceleration = vl.raw("acceleration", None)
    if isinstance(acceleration, dict):
        acceleration = vl.mapping(
            "acceleration",
            lambda t, k: float(t.number(k, minimum=0.0, strict=True, unit=accel_unit)),
        )
    elif acceleration is not None:
        acceleration = float(vl.number("acceleration", minimum=0.0, strict=True, unit=accel_unit))
    margin = vl.number("margin", 0.05, minimum=0.0)
    if margin > 1.0:
        raise vl.error("margin", "a number in [0, 1]", margin)
    passes = vl.number("max_passes", 6, minimum=1, integer=True)
    if passes > MAX_PASSES:
        raise vl.error("max_passes", f"an integer in 1..{MAX_PASSES}", passes)
    out = {
        "enabled": vl.boolean("enabled", False),
        "scale": float(scale),
        "acceleration": acceleration,
        "margin": float(margin),
        "max_passes": int(passes),
        "window": float(vl.number("window", 0.05, minimum=0.0, strict=True, unit="[s]")),
    }
    vl.done()
    return out


def scenario_error_context(exc: ClikError, file: Path) -> ClikError:
    """Attach the scenario file to an error raised while building its objects."""
    if isinstance(exc, ScenarioError):
        return exc
    return ScenarioError(file, getattr(exc, "field", ""), str(exc))
