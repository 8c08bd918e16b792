"""What ``clik show`` opens: a scenario file (run it) or an output folder (reload it).

An output folder written by ``clik solve`` or ``clik demo`` holds
``trajectory.npz``, whose ``info`` names the robot but not always how it was
loaded (package folders, locked joints). The robot is rebuilt from, in order:

1. ``info["scenario_file"]``, when it names an existing scenario file;
2. the shipped scenario whose ``name`` equals ``info["scenario"]`` (the case study);
3. ``info["robot_source"]`` (or ``info["robot"]``) with ``info["robot_lock"]``,
   ``info["package_dirs"]``, ``info["robot_xacro_args"]`` and ``info["robot_base"]``
   (with ``info["robot_base_speed"]``) when present, if its configuration size
   matches the run's.

Otherwise :class:`~clik.errors.InputError` says what is missing.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from clik.errors import ClikError, InputError
from clik.model.robot import Robot
from clik.outputs.result import TrackingResult

TRAJECTORY_FILE = "trajectory.npz"
"""The result file of an output folder."""


def load_target(target: str | Path) -> TrackingResult:
    """A result with its robot, from a scenario file (run now) or an output folder.

    Args:
        target: A scenario ``.toml`` file, or a folder holding ``trajectory.npz``.

    Returns:
        The result, ``result.robot`` set.

    Raises:
        InputError: ``target`` is neither, or the robot cannot be rebuilt.
        ScenarioError: The scenario file is invalid.
    """
    path = Path(target)
    if path.is_file() and path.suffix == ".toml":
        from clik.scenarios.runner import build

        run = build(path)
        result = run.execute()
        result.robot = run.robot
        return result
    npz = path / TRAJECTORY_FILE if path.is_dir() else path
    if npz.is_file() and npz.suffix == ".npz":
        result = TrackingResult.load(npz)
        result.robot = rebuild_robot(result, npz)
        return result
    raise InputError(
        "target",
        f"a scenario .toml file or an output folder holding {TRAJECTORY_FILE}",
        got=str(target),
    )


def rebuild_robot(result: TrackingResult, source: Path) -> Robot:
    """The robot a saved result was computed with (see the module docstring).

    Args:
        result: The loaded result.
        source: The file it was read from (named in errors).

    Raises:
        InputError: Nothing in ``info`` rebuilds a robot with the run's configuration size.
    """
    info = result.info
    nq = result.q.shape[1] if result.q.ndim == 2 else -1
    tried: list[str] = []
    spec = _scenario_robot(info)
    if spec is not None:
        robot = _load(spec, tried)
        if robot is not None and robot.nq == nq:
            return robot
    name = info.get("robot_source") or info.get("robot")
    if name:
        spec = {
            "source": name,
            "package_dirs": info.get("package_dirs") or [],
            "lock": info.get("robot_lock") or info.get("lock") or {},
            "xacro_args": info.get("robot_xacro_args") or {},
            "base": info.get("robot_base") or "fixed",
            "base_speed": info.get("robot_base_speed"),
        }
        robot = _load(spec, tried)
        if robot is not None and robot.nq == nq:
            return robot
        if robot is not None:
            tried.append(
                f"robot {name!r} has nq={robot.nq}, the run has {nq} (locked joints not recorded)"
            )
    detail = "; ".join(tried) or "no robot name"
    raise InputError(
        f"{source}: info",
        "'scenario_file', or 'robot_source' with 'robot_lock', to rebuild the robot "
        f"({detail}); open the scenario file instead: clik show SCENARIO.toml",
    )


def _scenario_robot(info: dict[str, Any]) -> dict[str, Any] | None:
    """The ``[robot]`` table of the run's scenario, when it can be found."""
    from clik.scenarios.scenario import load_scenario

    file = info.get("scenario_file")
    if file and Path(file).is_file():
        try:
            return load_scenario(file).robot
        except ClikError:
            return None
    name = info.get("scenario")
    if not name:
        return None
    for entry in resources.files("clik.scenarios").iterdir():
        if not entry.name.endswith(".toml"):
            continue
        try:
            scenario = load_scenario(Path(str(entry)))
        except ClikError:
            continue
        if scenario.name == name:
            return scenario.robot
    return None


def _load(spec: dict[str, Any], tried: list[str]) -> Robot | None:
    try:
        return Robot.load(
            spec["source"],
            package_dirs=spec.get("package_dirs") or None,
            lock=spec.get("lock") or None,
            xacro_args=spec.get("xacro_args") or None,
            base=spec.get("base") or "fixed",
            base_speed=spec.get("base_speed"),
        )
    except ClikError as exc:
        tried.append(str(exc))
        return None
