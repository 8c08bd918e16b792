"""Does clik load an MJCF model as MuJoCo does? Kinematics, geometry and distances compared.

For one MJCF file, :func:`agreement` compiles it with MuJoCo (``mujoco.MjModel``), loads
it with clik (``clik.Robot.load``) and compares, at the ``home`` key (else ``qpos0``) and
at :data:`RANDOM_CONFIGURATIONS` seeded random configurations within the joint ranges:

- **Forward kinematics**: every named body (``data.xpos``, ``data.xmat``) and site
  (``site_xpos``, ``site_xmat``) against clik's frame of the same name; the largest
  position [m] and rotation [rad] differences.
- **Geometry placement**: every MuJoCo collision geom (``contype`` or ``conaffinity``
  nonzero, not a plane or height field) against clik's collision object for it (matched
  by name, else by parent body and order, :func:`match_geoms`). Both shapes are compared
  as convex sets in the world through their support functions on
  :data:`SUPPORT_DIRECTIONS` directions: ``max_d |h_mujoco(d) - h_clik(d)|`` is the
  Hausdorff distance of the two convex hulls (sampled). It holds position, orientation
  and size at once, and is blind to the frame a mesh is written in: MuJoCo re-centres a
  mesh at its inertial frame (the offset goes into the geom's pose, ``mesh_pos``,
  ``mesh_quat``), clik builds its shapes from MuJoCo's compiled ones; the world vertex sets agree.
- **Probe distances**: small spheres (:data:`PROBE_RADIUS`) a few centimetres off each
  collision geom (along seeded random directions); MuJoCo's ``mj_geomDistance`` (the
  probe a mocap sphere added through ``MjSpec``) against coal's distance to clik's
  geometry (a mesh as its convex hull, which MuJoCo's collision uses too, and clik's
  collision scene).

Configurations: clik's ``q`` is MuJoCo's ``qpos`` joint by joint (matched by name, else
by order), but for the root body's free joint: with a fixed base clik welds the root body
at its ``qpos0`` pose (the free joint's values are not in ``q``), with a floating base
clik's free flyer holds ``x y z qx qy qz qw`` where MuJoCo holds ``x y z qw qx qy qz``.

Run::

    python benchmarks/mjcf_agreement.py PATH... [--json OUT.json] [--table OUT.md]
    python benchmarks/mjcf_agreement.py --menagerie /path/to/mujoco_menagerie --table OUT.md

With several models, each runs in its own process (a crash or a hang in one loader
costs that row only, :data:`MODEL_TIMEOUT`).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.mjcf_shapes import (
    clik_support,
    fibonacci_sphere,
    match_geoms,
    mujoco_support,
    probe,
    pruned_spec,
)
from benchmarks.mjcf_table import MENAGERIE_MODELS, table

RANDOM_CONFIGURATIONS = 5
"""Random configurations compared after the reference one."""
SEED = 0
"""Seed of the random configurations and probe directions."""
SUPPORT_DIRECTIONS = 256
"""Directions (a Fibonacci sphere) on which the support functions are compared."""
UNLIMITED_SLIDE = 0.1
"""Half-range of an unlimited slide joint's random values [m]."""
BASE_SPREAD = 0.5
"""Half-range of a floating base's random position offset [m]."""
MODEL_TIMEOUT = 600.0
"""Seconds one model may take in its own process."""


def agreement(path: str | Path, base: str | None = None) -> dict[str, Any]:
    """Compare clik's loading of an MJCF file with MuJoCo's.

    Args:
        path: The MJCF file.
        base: clik's base, ``"fixed"`` or ``"floating"``; default ``"floating"`` when the
            root body has a free joint, else ``"fixed"``.

    Returns:
        ``model`` (the path), ``mujoco`` ("ok" or MuJoCo's error), ``clik`` ("ok" or the
        error's class and message), ``base``, ``configurations`` (compared),
        ``fk_position_m``, ``fk_rotation_rad``, ``frames_compared``, ``geoms_compared``,
        ``geom_placement_m``, ``probe_distance_m``, ``probes`` (compared) and ``notes``;
        a measure is None when it could not be taken.
    """
    import mujoco

    path = Path(path)
    result = _empty_result(path, "ok", "not tried")
    notes: list[str] = result["notes"]
    m = None
    try:
        m = mujoco.MjModel.from_xml_path(str(path))
    except Exception as error:  # MuJoCo raises ValueError; any refusal is recorded
        result["mujoco"] = f"mujoco refuses: {_one_line(error)}"
        absent = _absent_file(path, str(error))
        if absent:
            notes.append(f"absent file: {absent}")
            m = _without_absent_visuals(path, notes)
            if m is not None:
                result["mujoco"] = "ok (absent visual-only meshes left out)"
    if base is None:
        base = "floating" if m is not None and _root_free_joint(m) is not None else "fixed"
    result["base"] = base
    robot = _load_clik(path, base, result)
    if m is None or robot is None:
        return result
    try:
        _compare(mujoco, m, robot, path, base, result)
    except Exception as error:  # a comparison step failing is a finding, not a crash
        notes.append(f"comparison stopped: {type(error).__name__}: {_one_line(error)}")
    return result


def _empty_result(path: Path, mujoco: str, clik: str) -> dict[str, Any]:
    """A result without measures (:func:`agreement`'s keys)."""
    return {
        "model": str(path),
        "mujoco": mujoco,
        "clik": clik,
        "base": None,
        "configurations": 0,
        "fk_position_m": None,
        "fk_rotation_rad": None,
        "frames_compared": 0,
        "geoms_compared": 0,
        "geom_placement_m": None,
        "probe_distance_m": None,
        "probes": 0,
        "notes": [],
    }


# ------------------------------------------------------------------ loading


def _load_clik(path: Path, base: str, result: dict[str, Any]) -> Any:
    """The robot clik loads, or None with the error in ``result["clik"]``; warnings noted."""
    import clik

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            robot = clik.Robot.load(path, base=base)
        except Exception as error:  # clik's refusal (RobotLoadError, ...) is the finding
            result["clik"] = f"{type(error).__name__}: {_one_line(error)}"
            robot = None
        else:
            result["clik"] = "ok"
    kinds = sorted({type(w.message).__name__ for w in caught})
    if kinds:
        result["notes"].append(f"clik warned: {', '.join(kinds)}")
    return robot


def _absent_file(path: Path, message: str) -> str | None:
    """The file MuJoCo could not open, when it is absent (a snapshot without large files)."""
    found = re.search(r"Error opening file '([^']+)'", message)
    if not found:
        return None
    name = found.group(1)  # relative to the model's folder (meshdir included)
    return None if (path.parent / name).exists() else name


def _without_absent_visuals(path: Path, notes: list[str]) -> Any:
    """MuJoCo's model without the visual-only geoms whose mesh file is absent, or None.

    What clik loads from such a file (it leaves them out with a warning): so a snapshot
    without its large visual meshes can still be compared. None when an absent mesh is
    used by a geom that can touch.
    """
    pruned = pruned_spec(path)
    if pruned is None:
        return None
    spec, left_out = pruned
    try:
        model = spec.compile()
    except Exception as error:  # MuJoCo's refusal is recorded, not raised
        notes.append(f"mujoco refuses without the absent meshes: {_one_line(error)}")
        return None
    notes.append(f"{left_out} visual-only geoms of absent meshes left out on both sides")
    return model


def _root_free_joint(m: Any) -> int | None:
    """The id of the free joint of a body on the world, or None."""
    import mujoco

    for j in range(m.njnt):
        body = m.jnt_bodyid[j]
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE and m.body_parentid[body] == 0:
            return j
    return None


# ------------------------------------------------------------------ configurations


class _Mapping:
    """MuJoCo's ``qpos`` to clik's ``q``: the joints matched, the free joint handled."""

    def __init__(self, mujoco: Any, m: Any, model: Any, base: str, notes: list[str]) -> None:
        self.m = m
        self.base = base
        self.free = _root_free_joint(m)
        self.first = 1 if base == "fixed" else 2  # clik's first joint after its base
        pin_names = [str(n) for n in model.names]
        mj_joints = [j for j in range(m.njnt) if j != self.free]
        named = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j): j for j in mj_joints}
        self.pairs: list[tuple[int, int]] = []  # (MuJoCo qposadr, clik idx_q)
        by_name = all(n in named for n in pin_names[self.first :])
        if by_name:
            for i in range(self.first, model.njoints):
                j = named[pin_names[i]]
                self.pairs.append((int(m.jnt_qposadr[j]), int(model.joints[i].idx_q)))
        elif model.njoints - self.first == len(mj_joints):
            notes.append("joints matched by order (names differ)")
            for i, j in zip(range(self.first, model.njoints), mj_joints, strict=True):
                self.pairs.append((int(m.jnt_qposadr[j]), int(model.joints[i].idx_q)))
        else:
            raise ValueError(
                f"joints not matched: clik has {model.njoints - self.first}, MuJoCo "
                f"{len(mj_joints)} (free joint aside), names differ"
            )
        if base != "fixed" and self.free is None:
            raise ValueError(f"base {base!r} but MuJoCo's root body has no free joint")
        self.nq = model.nq

    def q(self, qpos: np.ndarray) -> np.ndarray:
        """The configuration clik gives MuJoCo's ``qpos``."""
        q = np.zeros(self.nq)
        if self.base == "floating" and self.free is not None:
            a = int(self.m.jnt_qposadr[self.free])
            x, y, z, w, qx, qy, qz = qpos[a : a + 7]
            q[:7] = [x, y, z, qx, qy, qz, w]
        for adr, iq in self.pairs:
            q[iq] = qpos[adr]
        return q


def _configurations(mujoco: Any, m: Any, mapping: _Mapping) -> list[tuple[str, np.ndarray]]:
    """The reference qpos (``home`` key, else ``qpos0``) and seeded random ones."""
    reference = m.qpos0.copy()
    label = "qpos0"
    for k in range(m.nkey):
        if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, k) == "home":
            reference = m.key_qpos[k].copy()
            label = "home"
    free = mapping.free
    if free is not None and mapping.base == "fixed":  # clik welds the root at qpos0
        a = int(m.jnt_qposadr[free])
        reference[a : a + 7] = m.qpos0[a : a + 7]
    rng = np.random.default_rng(SEED)
    configurations = [(label, reference)]
    for n in range(RANDOM_CONFIGURATIONS):
        qpos = reference.copy()
        for j in range(m.njnt):
            a = int(m.jnt_qposadr[j])
            kind = m.jnt_type[j]
            if kind == mujoco.mjtJoint.mjJNT_FREE:
                if mapping.base == "floating":
                    qpos[a : a + 3] += rng.uniform(-BASE_SPREAD, BASE_SPREAD, 3)
                    quaternion = rng.normal(size=4)
                    qpos[a + 3 : a + 7] = quaternion / np.linalg.norm(quaternion)
            elif kind == mujoco.mjtJoint.mjJNT_BALL:
                quaternion = rng.normal(size=4)
                qpos[a : a + 4] = quaternion / np.linalg.norm(quaternion)
            elif m.jnt_limited[j]:
                low, high = m.jnt_range[j]
                qpos[a] = rng.uniform(low, high)
            elif kind == mujoco.mjtJoint.mjJNT_HINGE:
                qpos[a] = rng.uniform(-math.pi, math.pi)
            else:
                qpos[a] = rng.uniform(-UNLIMITED_SLIDE, UNLIMITED_SLIDE)
        configurations.append((f"random{n}", qpos))
    return configurations


# ------------------------------------------------------------------ comparing


def _compare(
    mujoco: Any, m: Any, robot: Any, path: Path, base: str, result: dict[str, Any]
) -> None:
    """Fill ``result``'s measures for a model both loaded."""
    import pinocchio as pin

    notes: list[str] = result["notes"]
    model = robot.model
    data = model.createData()
    geometry = robot.collision_model
    geometry_data = geometry.createData()
    mapping = _Mapping(mujoco, m, model, base, notes)
    configurations = _configurations(mujoco, m, mapping)
    reference_q = mapping.q(configurations[0][1])
    gap = float(np.max(np.abs(reference_q - robot.q_reference))) if model.nq else 0.0
    if gap > 1e-9:
        notes.append(
            f"clik's q_reference differs from MuJoCo's {configurations[0][0]} by {gap:.3g}"
        )
    frames = _frame_pairs(mujoco, m, model, notes)
    pairs = match_geoms(mujoco, m, model, geometry, notes)
    directions = fibonacci_sphere(SUPPORT_DIRECTIONS)
    d = mujoco.MjData(m)
    position = rotation = placement = 0.0
    for _, qpos in configurations:
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        q = mapping.q(qpos)
        pin.framesForwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, geometry_data)
        for kind, i, frame in frames:
            xpos, xmat = (d.xpos, d.xmat) if kind == "body" else (d.site_xpos, d.site_xmat)
            placed = data.oMf[frame]
            position = max(position, float(np.linalg.norm(xpos[i] - placed.translation)))
            rotation = max(rotation, _angle(xmat[i].reshape(3, 3), placed.rotation))
        for g, k in pairs:
            mj_support = mujoco_support(mujoco, m, d, g, directions)
            ours = clik_support(geometry.geometryObjects[k], geometry_data.oMg[k])
            if mj_support is None or ours is None:
                continue
            gaps = np.abs(mj_support(directions) - ours(directions))
            placement = max(placement, float(np.max(gaps)))
    result["configurations"] = len(configurations)
    result["frames_compared"] = len(frames)
    if frames:
        result["fk_position_m"], result["fk_rotation_rad"] = position, rotation
    result["geoms_compared"] = len(pairs)
    if pairs:
        result["geom_placement_m"] = placement
        probe(mujoco, path, m, robot, mapping, configurations, pairs, result)


def _frame_pairs(mujoco: Any, m: Any, model: Any, notes: list[str]) -> list[tuple[str, int, int]]:
    """``(body or site, MuJoCo id, clik frame id)`` of every named body and site clik has."""
    import pinocchio as pin

    pairs: list[tuple[str, int, int]] = []
    missing: list[str] = []
    for kind, count, obj, frame_type in (
        ("body", m.nbody, mujoco.mjtObj.mjOBJ_BODY, pin.BODY),
        ("site", m.nsite, mujoco.mjtObj.mjOBJ_SITE, pin.OP_FRAME),
    ):
        for i in range(1 if kind == "body" else 0, count):
            name = mujoco.mj_id2name(m, obj, i)
            if not name:
                continue
            if model.existFrame(name, frame_type):
                pairs.append((kind, i, model.getFrameId(name, frame_type)))
            elif model.existFrame(name):
                pairs.append((kind, i, model.getFrameId(name)))
            else:
                missing.append(name)
    if missing:
        notes.append(f"{len(missing)} named bodies/sites without a clik frame: {missing[:5]}")
    return pairs


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation between two rotation matrices [rad]."""
    r = a.T @ b
    sin = 0.5 * math.hypot(r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1])
    return float(math.atan2(sin, 0.5 * (np.trace(r) - 1.0)))  # precise near 0, unlike acos


# MuJoCo geom types (mjtGeom): plane 0, hfield 1, sphere 2, capsule 3, ellipsoid 4,
# cylinder 5, box 6, mesh 7, sdf 8.
# ------------------------------------------------------------------ reporting


def _one_line(error: BaseException) -> str:
    """An error's message on one line, shortened."""
    text = " ".join(str(error).split())
    return text if len(text) <= 300 else text[:297] + "..."


def _isolated(path: Path, base: str | None) -> dict[str, Any]:
    """:func:`agreement` in its own process (a crash or a hang costs one row)."""
    with tempfile.TemporaryDirectory(prefix="clik-agreement-") as folder:
        out = Path(folder, "result.json")
        command = [sys.executable, __file__, str(path), "--json", str(out), "--in-process"]
        if base:
            command += ["--base", base]
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=MODEL_TIMEOUT)
        except subprocess.TimeoutExpired:
            failure = f"timed out after {MODEL_TIMEOUT:g} s"
        else:
            if out.exists():
                results: list[dict[str, Any]] = json.loads(out.read_text())
                return results[0]
            tail = " ".join(done.stderr.split()[-30:])
            failure = f"process ended with code {done.returncode}: {tail}"
    result = _empty_result(path, "?", failure)
    result["base"] = base
    result["notes"].append(failure)
    return result


def main(argv: Sequence[str] | None = None) -> int:
    """Compare the models given (or the Menagerie's) and write JSON and a markdown table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("paths", nargs="*", type=Path, help="MJCF files")
    parser.add_argument("--menagerie", type=Path, help="a mujoco_menagerie working copy")
    parser.add_argument("--base", choices=("fixed", "floating"), help="default: from the file")
    parser.add_argument("--json", type=Path, help="write the results as JSON")
    parser.add_argument("--table", type=Path, help="write the markdown table")
    parser.add_argument("--in-process", action="store_true", help="no process per model")
    args = parser.parse_args(argv)
    paths: list[Path] = list(args.paths)
    absent: list[Path] = []
    if args.menagerie is not None:
        for relative in MENAGERIE_MODELS:
            file = args.menagerie / relative
            if file.exists():
                paths.append(file)
            else:
                absent.append(file)
    if absent:
        print(f"not in the Menagerie copy: {', '.join(map(str, absent))}", file=sys.stderr)
    if not paths:
        parser.error("no model: give MJCF paths or --menagerie")
    isolated = len(paths) > 1 and not args.in_process
    results = []
    for path in paths:
        start = time.perf_counter()
        result = _isolated(path, args.base) if isolated else agreement(path, args.base)
        results.append(result)
        seconds = time.perf_counter() - start
        print(
            f"{path}: mujoco {result['mujoco'][:60]}; clik {result['clik'][:80]}; "
            f"fk {result['fk_position_m']} m {result['fk_rotation_rad']} rad; "
            f"geoms {result['geoms_compared']} placement {result['geom_placement_m']} m; "
            f"probes {result['probes']} {result['probe_distance_m']} m ({seconds:.1f} s)",
            file=sys.stderr,
        )
    for path in absent:
        results.append(_empty_result(path, "model file absent", "model file absent"))
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1) + "\n")
    text = table(results, args.menagerie)
    if args.table is not None:
        args.table.write_text(text)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
