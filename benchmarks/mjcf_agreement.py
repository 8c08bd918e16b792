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
  ``mesh_quat``), Pinocchio keeps the file's vertices; the world vertex sets agree.
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

RANDOM_CONFIGURATIONS = 5
"""Random configurations compared after the reference one."""
SEED = 0
"""Seed of the random configurations and probe directions."""
SUPPORT_DIRECTIONS = 256
"""Directions (a Fibonacci sphere) on which the support functions are compared."""
PROBE_RADIUS = 0.01
"""Radius of a probe sphere [m]."""
PROBE_OFFSETS = (0.02, 0.035, 0.05)
"""Gaps between a probe sphere and a geom's supporting plane [m] (one probe per offset)."""
PROBE_DISTMAX = 10.0
"""``distmax`` of ``mj_geomDistance`` [m] (above every probe's distance)."""
UNLIMITED_SLIDE = 0.1
"""Half-range of an unlimited slide joint's random values [m]."""
BASE_SPREAD = 0.5
"""Half-range of a floating base's random position offset [m]."""
MODEL_TIMEOUT = 600.0
"""Seconds one model may take in its own process."""

MENAGERIE_MODELS = (
    "franka_emika_panda/panda.xml",
    "franka_fr3/fr3.xml",
    "universal_robots_ur5e/ur5e.xml",
    "universal_robots_ur10e/ur10e.xml",
    "kinova_gen3/gen3.xml",
    "kuka_iiwa_14/iiwa14.xml",
    "ufactory_xarm7/xarm7.xml",
    "ufactory_lite6/lite6.xml",
    "rethink_robotics_sawyer/sawyer.xml",
    "unitree_z1/z1.xml",
    "trossen_vx300s/vx300s.xml",
    "flexiv_rizon4/flexiv_rizon4.xml",
    "unitree_h1/h1.xml",
    "unitree_g1/g1.xml",
    "pal_talos/talos.xml",
    "robotis_op3/op3.xml",
    "booster_t1/t1.xml",
    "apptronik_apollo/apptronik_apollo.xml",
    "stanford_tidybot/tidybot.xml",
    "hello_robot_stretch/stretch.xml",
    "hello_robot_stretch_3/stretch.xml",
    "pal_tiago/tiago.xml",
    "unitree_go2/go2.xml",
    "unitree_go1/go1.xml",
    "unitree_a1/a1.xml",
    "anybotics_anymal_c/anymal_c.xml",
    "boston_dynamics_spot/spot.xml",
    "agility_cassie/cassie.xml",
    "agilex_piper/piper.xml",
    "aloha/aloha.xml",
    "arx_l5/arx_l5.xml",
    "franka_fr3_v2/fr3v2.xml",
    "i2rt_yam/yam.xml",
    "low_cost_robot_arm/low_cost_robot_arm.xml",
    "robotstudio_so101/so101.xml",
    "trs_so_arm100/so_arm100.xml",
    "trossen_wx250s/wx250s.xml",
    "trossen_wxai/trossen_ai_bimanual.xml",
    "dynamixel_2r/dynamixel_2r.xml",
    "google_robot/robot.xml",
    "pal_tiago_dual/tiago_dual.xml",
    "berkeley_humanoid/berkeley_humanoid.xml",
    "fourier_n1/n1.xml",
    "pndbotics_adam_lite/adam_lite.xml",
    "toddlerbot_2xc/toddlerbot_2xc.xml",
    "toddlerbot_2xm/toddlerbot_2xm.xml",
    "anybotics_anymal_b/anymal_b.xml",
    "google_barkour_vb/barkour_vb.xml",
    "shadow_hand/right_hand.xml",
    "leap_hand/right_hand.xml",
    "wonik_allegro/right_hand.xml",
    "robotiq_2f85/2f85.xml",
    "shadow_dexee/shadow_dexee.xml",
)
"""Menagerie models run by ``--menagerie`` (arms, humanoids, mobile and legged robots)."""

TABLE_HEADER = (
    "| model | MuJoCo loads | clik loads (or its error) | FK max m / rad "
    "| geoms compared | geom placement max m | probe distance max m |"
)


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


def pruned_spec(path: Path) -> tuple[Any, int] | None:
    """The file's ``MjSpec`` without visual-only geoms of absent meshes, and their count.

    None when an absent mesh is used by a geom that can touch.
    """
    import mujoco

    spec = mujoco.MjSpec.from_file(str(path))
    folder = path.parent / (spec.meshdir or "")
    absent = {mesh.name for mesh in spec.meshes if not (folder / mesh.file).exists()}
    users = [g for g in spec.geoms if g.meshname in absent]
    if any(g.contype or g.conaffinity for g in users):
        return None
    for geom in users:
        spec.delete(geom)
    for mesh in [m for m in spec.meshes if m.name in absent]:
        spec.delete(mesh)
    return spec, len(users)


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
    directions = _fibonacci_sphere(SUPPORT_DIRECTIONS)
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
            mj_support = _mujoco_support(mujoco, m, d, g, directions)
            clik_support = _clik_support(geometry.geometryObjects[k], geometry_data.oMg[k])
            if mj_support is None or clik_support is None:
                continue
            gaps = np.abs(mj_support(directions) - clik_support(directions))
            placement = max(placement, float(np.max(gaps)))
    result["configurations"] = len(configurations)
    result["frames_compared"] = len(frames)
    if frames:
        result["fk_position_m"], result["fk_rotation_rad"] = position, rotation
    result["geoms_compared"] = len(pairs)
    if pairs:
        result["geom_placement_m"] = placement
        _probe(mujoco, path, m, robot, mapping, configurations, pairs, result)


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
_MJ_KIND = {2: "Sphere", 3: "Capsule", 4: "Ellipsoid", 5: "Cylinder", 6: "Box", 7: "mesh"}


def _collision_geoms(m: Any) -> list[int]:
    """MuJoCo's collision geoms of the robot (clik's rule), not a plane.

    ``contype`` or ``conaffinity`` not zero, or group 3 (the Menagerie's collision group,
    contacts off for explicit pairs).
    """
    return [
        g
        for g in range(m.ngeom)
        if (m.geom_contype[g] or m.geom_conaffinity[g] or m.geom_group[g] == 3)
        and int(m.geom_type[g]) not in (0, 1)
        and m.geom_bodyid[g] != 0
    ]


def _clik_kind(geometry_object: Any) -> str:
    """A clik (coal) shape's kind as :data:`_MJ_KIND` names it ("mesh" for meshes)."""
    name = type(geometry_object.geometry).__name__
    return "mesh" if name.startswith(("BVHModel", "Convex")) else name


def match_geoms(
    mujoco: Any, m: Any, model: Any, geometry: Any, notes: list[str]
) -> list[tuple[int, int]]:
    """``(MuJoCo geom id, clik geometry index)`` of MuJoCo's collision geoms.

    A named geom is clik's object of the same name (Pinocchio keeps a geom's name). The
    others, body by body, in order: Pinocchio names an unnamed geom ``<body>Geom_<k>``
    (``k`` counting its body's geoms), so clik's unmatched objects of a body (its
    parent frame) are paired in order with MuJoCo's unnamed collision geoms of that
    body, when their kinds (sphere, box, mesh...) agree. What stays unpaired is noted.
    """
    by_name = {go.name: k for k, go in enumerate(geometry.geometryObjects)}
    used: set[int] = set()
    pairs: list[tuple[int, int]] = []
    rest: dict[str, list[int]] = {}
    for g in _collision_geoms(m):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
        if name and name in by_name:
            pairs.append((g, by_name[name]))
            used.add(by_name[name])
        else:
            body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[g])) or ""
            rest.setdefault(body, []).append(g)
    clik_rest: dict[str, list[int]] = {}
    for k, go in enumerate(geometry.geometryObjects):
        if k not in used:
            clik_rest.setdefault(str(model.frames[go.parentFrame].name), []).append(k)
    unpaired: list[str] = []
    kinds_differ = 0
    for body, geoms in rest.items():
        theirs = clik_rest.pop(body, [])
        for n, g in enumerate(geoms):
            if n >= len(theirs):
                unpaired.append(f"{body}#{g}")
                continue
            k = theirs[n]
            if _MJ_KIND.get(int(m.geom_type[g])) != _clik_kind(geometry.geometryObjects[k]):
                kinds_differ += 1
                continue
            pairs.append((g, k))
        clik_left = theirs[len(geoms) :]
        if clik_left:
            clik_rest[body] = clik_left
    if unpaired:
        notes.append(f"{len(unpaired)} MuJoCo collision geoms without clik's: {unpaired[:5]}")
    if kinds_differ:
        notes.append(f"{kinds_differ} geoms paired by order have different shapes (skipped)")
    extra = [geometry.geometryObjects[k].name for ks in clik_rest.values() for k in ks]
    if extra:
        notes.append(f"{len(extra)} clik collision objects not MuJoCo collision geoms: {extra[:5]}")
    return pairs


def _fibonacci_sphere(n: int) -> np.ndarray:
    """``n`` unit directions spread over the sphere (rows)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


Support = Any  # a callable: directions (n, 3) -> support values (n,)


def _primitive_support(
    kind: str, sizes: np.ndarray, rotation: np.ndarray, centre: np.ndarray
) -> Support:
    """The support function of a placed primitive shape (MuJoCo's and coal's sizes alike).

    ``sizes``: sphere ``(r,)``, capsule and cylinder ``(r, half length)`` along the
    local z axis, box half sides, ellipsoid radii.
    """

    def support(directions: np.ndarray) -> np.ndarray:
        local = directions @ rotation  # the directions in the shape's frame
        value = directions @ centre
        if kind == "Sphere":
            return value + sizes[0]
        if kind == "Capsule":
            return value + sizes[1] * np.abs(local[:, 2]) + sizes[0]
        if kind == "Cylinder":
            radial = np.sqrt(np.maximum(0.0, 1.0 - local[:, 2] ** 2))
            return value + sizes[1] * np.abs(local[:, 2]) + sizes[0] * radial
        if kind == "Box":
            return value + np.abs(local) @ sizes[:3]
        if kind == "Ellipsoid":
            return value + np.sqrt(((local * sizes[:3]) ** 2).sum(axis=1))
        raise ValueError(kind)

    return support


def _points_support(points: np.ndarray) -> Support:
    """The support function of the convex hull of world points."""
    return lambda directions: np.max(directions @ points.T, axis=1)


def _mujoco_vertices(m: Any, d: Any, g: int) -> np.ndarray:
    """A mesh geom's vertices in the world (MuJoCo's re-centred vertices, placed).

    Those of the convex hull MuJoCo collides (``mesh_graph``, ``maxhullvert`` applied)
    when it computed one.
    """
    mesh = int(m.geom_dataid[g])
    start, count = int(m.mesh_vertadr[mesh]), int(m.mesh_vertnum[mesh])
    vertices = np.asarray(m.mesh_vert[start : start + count], dtype=float)
    graph = int(m.mesh_graphadr[mesh])
    if graph >= 0:  # numvert, numface, vert_edgeadr[numvert], vert_globalid[numvert], ...
        n_vert = int(m.mesh_graph[graph])
        ids = np.asarray(m.mesh_graph[graph + 2 + n_vert : graph + 2 + 2 * n_vert], dtype=int)
        vertices = vertices[ids]
    return vertices @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]


def _mujoco_support(mujoco: Any, m: Any, d: Any, g: int, directions: np.ndarray) -> Support:
    """The support function of MuJoCo's geom ``g`` in the world, or None (unknown type)."""
    kind = _MJ_KIND.get(int(m.geom_type[g]))
    if kind is None:
        return None
    if kind == "mesh":
        return _points_support(_mujoco_vertices(m, d, g))
    rotation = d.geom_xmat[g].reshape(3, 3)
    return _primitive_support(kind, np.asarray(m.geom_size[g]), rotation, d.geom_xpos[g])


def _coal_sizes(shape: Any, kind: str) -> np.ndarray:
    """A coal primitive's sizes in MuJoCo's convention (:func:`_primitive_support`)."""
    if kind == "Sphere":
        return np.array([shape.radius])
    if kind in ("Capsule", "Cylinder"):
        return np.array([shape.radius, shape.halfLength])
    if kind == "Box":
        return np.asarray(shape.halfSide, dtype=float)
    return np.asarray(shape.radii, dtype=float)


def _clik_vertices(geometry_object: Any) -> np.ndarray:
    """A clik mesh's vertices in its own frame (as coal holds them, scaled)."""
    shape = geometry_object.geometry
    if hasattr(shape, "vertices"):
        return np.asarray(shape.vertices(), dtype=float)
    return np.asarray(shape.points(), dtype=float)


def _clik_support(geometry_object: Any, placement: Any) -> Support:
    """The support function of clik's geometry object at ``placement``, or None."""
    kind = _clik_kind(geometry_object)
    rotation, centre = placement.rotation, placement.translation
    if kind == "mesh":
        return _points_support(_clik_vertices(geometry_object) @ rotation.T + centre)
    if kind not in _MJ_KIND.values():
        return None
    sizes = _coal_sizes(geometry_object.geometry, kind)
    return _primitive_support(kind, sizes, rotation, centre)


def _coal_shape(geometry_object: Any) -> Any:
    """The shape clik's collision scene uses: a mesh's convex hull, else the shape."""
    shape = geometry_object.geometry
    if _clik_kind(geometry_object) != "mesh" or not hasattr(shape, "buildConvexHull"):
        return shape
    if shape.convex is None:
        shape.buildConvexHull(True, "Qt")
    return shape.convex


def _probe(
    mujoco: Any,
    path: Path,
    m: Any,
    robot: Any,
    mapping: _Mapping,
    configurations: Sequence[tuple[str, np.ndarray]],
    pairs: Sequence[tuple[int, int]],
    result: dict[str, Any],
) -> None:
    """Probe spheres off each paired geom: MuJoCo's and coal's distances compared."""
    import coal
    import pinocchio as pin

    pruned = pruned_spec(path)
    if pruned is None:
        result["notes"].append("an absent mesh can touch: no probes")
        return
    spec = pruned[0]
    body = spec.worldbody.add_body(name="clik_agreement_probe", mocap=True)
    body.add_geom(
        name="clik_agreement_probe",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[PROBE_RADIUS, 0.0, 0.0],
        contype=0,
        conaffinity=0,
    )
    mp = spec.compile()
    probe = mujoco.mj_name2id(mp, mujoco.mjtObj.mjOBJ_GEOM, "clik_agreement_probe")
    same = mp.ngeom == m.ngeom + 1 and all(
        mp.geom_type[g] == m.geom_type[g] and mp.geom_bodyid[g] == m.geom_bodyid[g]
        for g, _ in pairs
    )
    if not same:
        result["notes"].append("probe model's geoms differ from the file's: no probes")
        return
    dp = mujoco.MjData(mp)
    model, geometry = robot.model, robot.collision_model
    data, geometry_data = model.createData(), geometry.createData()
    rng = np.random.default_rng(SEED + 1)
    sphere = coal.Sphere(PROBE_RADIUS)
    request = coal.DistanceRequest()
    worst, count, skipped = 0.0, 0, 0
    for _, qpos in configurations[:2]:  # the reference and one random configuration
        dp.qpos[:] = qpos
        mujoco.mj_kinematics(mp, dp)
        pin.framesForwardKinematics(model, data, mapping.q(qpos))
        pin.updateGeometryPlacements(model, data, geometry, geometry_data)
        for g, k in pairs:
            geometry_object = geometry.geometryObjects[k]
            if _clik_kind(geometry_object) == "Ellipsoid":
                skipped += 1  # clik's collision scene skips ellipsoids
                continue
            shape = _coal_shape(geometry_object)
            support = _mujoco_support(mujoco, mp, dp, g, np.zeros((1, 3)))
            placement = geometry_data.oMg[k]
            tf = coal.Transform3s(placement.rotation, placement.translation)
            for offset in PROBE_OFFSETS:
                direction = rng.normal(size=3)
                direction /= np.linalg.norm(direction)
                height = float(support(direction[None, :])[0])
                centre = direction * (height + PROBE_RADIUS + offset)
                dp.mocap_pos[mp.body_mocapid[mp.geom_bodyid[probe]]] = centre
                mujoco.mj_kinematics(mp, dp)
                theirs = mujoco.mj_geomDistance(mp, dp, g, probe, PROBE_DISTMAX, None)
                res = coal.DistanceResult()
                tf_probe = coal.Transform3s(np.eye(3), centre)
                ours = coal.distance(shape, tf, sphere, tf_probe, request, res)
                worst = max(worst, abs(float(theirs) - float(ours)))
                count += 1
    result["probes"] = count
    if count:
        result["probe_distance_m"] = worst
    if skipped:
        result["notes"].append(f"ellipsoids not probed (clik's scene skips them): {skipped}")


# ------------------------------------------------------------------ reporting


def _one_line(error: BaseException) -> str:
    """An error's message on one line, shortened."""
    text = " ".join(str(error).split())
    return text if len(text) <= 300 else text[:297] + "..."


def _number(value: float | None) -> str:
    """A measure for the table (``-`` when not taken)."""
    return "-" if value is None else f"{value:.2g}"


def table(results: Sequence[dict[str, Any]], root: Path | None = None) -> str:
    """The results as a markdown table (one row per model)."""
    lines = [TABLE_HEADER, "|" + " --- |" * 7]
    for r in results:
        name = r["model"]
        if root is not None and Path(name).is_relative_to(root):
            name = str(Path(name).relative_to(root))
        mujoco = "yes" if r["mujoco"] == "ok" else r["mujoco"].replace("|", "/")
        clik = r["clik"].replace(f"cannot load robot {r['model']}, ", "").replace("|", "/")
        if r["clik"] == "ok":
            clik = f"yes ({r['base']})"
        fk = (
            "-"
            if r["fk_position_m"] is None
            else f"{_number(r['fk_position_m'])} / {_number(r['fk_rotation_rad'])}"
        )
        lines.append(
            f"| {name} | {mujoco} | {clik} | {fk} | {r['geoms_compared']} "
            f"| {_number(r['geom_placement_m'])} | {_number(r['probe_distance_m'])} |"
        )
    notes = [(r["model"], n) for r in results for n in r["notes"]]
    if notes:
        lines += ["", "Notes:", ""]
        for model, note in notes:
            shown = (
                Path(model).relative_to(root)
                if root and Path(model).is_relative_to(root)
                else model
            )
            lines.append(f"- {shown}: {note.replace('|', '/')}")
    return "\n".join(lines) + "\n"


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
