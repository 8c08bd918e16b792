r"""Joint speeds against the bound the run used for each joint: the ``velocity`` part of a summary.

Every velocity coordinate ``i`` is compared with the bound ``vmax_i`` the run used
for it, which says where it comes from (its *source*):

- ``"urdf"``: the robot file's ``<limit velocity=...>`` (Pinocchio's ``model.velocityLimit``);
- ``"setting"``: a per-joint bound, ``joint_speed.velocity`` (replaces the URDF's);
- ``"default"``: ``joint_speed.default_velocity`` (clik's default, 2 rad/s or m/s) for a
  joint whose file gives none (an MJCF model gives none for any joint);
- ``"base_speed"``: a planar or floating base's coordinates, bounded by the robot's base
  speed (``Robot.load(..., base_speed=...)``, else 1 m/s and 1 rad/s), which the law
  keeps like a joint's;
- ``"none"``: no bound (only when the law's joint speed limits are off,
  ``joint_speed=None``: then a joint without a URDF limit is not bounded, and not compared).

With the law's joint speed limits on (the default) these are the bounds it keeps, its
``scale`` not applied (the law keeps ``|qdot_i| <= scale vmax_i``); they are recorded in
``info["joint_speed"]`` (``limit``, ``source``). Over the *recorded* samples ``k``
(every ``record_every``-th sample and the last: with a decimated record, a peak
between two recorded samples is not seen):

.. math::

    \rho_i = \max_k \frac{|\dot q_{i,k}|}{v_{\max,i}}

``max_velocity_ratio`` is :math:`\max_i \rho_i` over the bounded coordinates (None
when none is), ``max_velocity_ratio_joint`` and ``max_velocity_ratio_source`` the
coordinate that reached it and its source, ``velocity_bounds`` every coordinate's
``{"bound", "source"}`` (``bound`` None with ``"none"``). Each coordinate that went
past its bound (:math:`\rho_i > 1`) gets one record:

``{"joint", "max_ratio", "max_velocity", "limit", "source", "t_first", "t_last", "samples"}``:
the joint's name, :math:`\rho_i`, the largest :math:`|\dot q_i|` [rad/s or m/s],
``vmax_i`` [rad/s or m/s], its source, the first and last recorded times above the
bound [s], and how many recorded samples were above it. Non-finite velocities (the
last samples of a ``diverged`` run) are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from clik.model.base import FIXED, base_kind

SOURCES = ("urdf", "setting", "default", "base_speed", "none")
"""Where a coordinate's bound comes from (module docstring)."""


@dataclass(frozen=True)
class VelocityLimits:
    """The velocity bound of each velocity coordinate, with its joint's name and source.

    Attributes:
        names: Name of each velocity coordinate (nv,): the joint's name, or
            ``"<joint>[k]"`` for coordinate ``k`` of a joint with several.
        limit: Largest allowed ``|qdot_i|`` (nv,) [rad/s or m/s]; a value that is
            not finite and positive means no bound.
        source: Where each bound comes from (:data:`SOURCES`, nv,); None: ``"urdf"``
            for each bounded coordinate, ``"none"`` for the others.
    """

    names: list[str]
    limit: np.ndarray
    source: list[str] | None = None

    def __post_init__(self) -> None:
        limit = np.asarray(self.limit, dtype=float).reshape(-1)
        if limit.shape != (len(self.names),):
            raise ValueError(
                f"VelocityLimits: {len(self.names)} names but limit of shape {limit.shape}"
            )
        object.__setattr__(self, "limit", limit)
        bounded = np.isfinite(limit) & (limit > 0.0)
        source = self.source or ["urdf"] * len(self.names)
        if len(source) != len(self.names) or not set(source) <= set(SOURCES):
            raise ValueError(f"VelocityLimits: source {source!r} for {len(self.names)} names")
        source = [s if ok else "none" for s, ok in zip(source, bounded, strict=True)]
        object.__setattr__(self, "source", source)

    @property
    def limited(self) -> np.ndarray:
        """Indices of the coordinates that have a bound (finite and > 0)."""
        return np.flatnonzero(np.isfinite(self.limit) & (self.limit > 0.0))

    def sources(self) -> list[str]:
        """:attr:`source`, filled in (``__post_init__`` sets it)."""
        return list(self.source or [])


@dataclass(frozen=True)
class VelocityReport:
    """How close a run's joint speeds came to their bounds, and how far past them.

    Attributes:
        max_velocity_ratio: Largest ``|qdot_i| / vmax_i`` over the recorded samples
            and the bounded coordinates, or None when no coordinate has a bound.
        joint: The coordinate that reached it (None with no bound).
        source: Its bound's source (None with no bound).
        bounds: ``{name: {"bound", "source"}}`` for every coordinate.
        records: One record per coordinate above its bound (see the module docstring),
            in velocity order.
    """

    max_velocity_ratio: float | None
    records: list[dict[str, Any]] = field(default_factory=list)
    joint: str | None = None
    source: str | None = None
    bounds: dict[str, dict[str, Any]] = field(default_factory=dict)

    def as_summary(self) -> dict[str, Any]:
        """The summary's keys (module docstring)."""
        return {
            "max_velocity_ratio": self.max_velocity_ratio,
            "max_velocity_ratio_joint": self.joint,
            "max_velocity_ratio_source": self.source,
            "velocity_bounds": {k: dict(v) for k, v in self.bounds.items()},
            "velocity": [dict(r) for r in self.records],
        }


def velocity_names(model: Any) -> list[str]:
    """Name of each velocity coordinate of a Pinocchio model (nv,).

    Args:
        model: A ``pinocchio.Model``.
    """
    names = [""] * int(model.nv)
    # model.idx_vs and model.nvs: plain integers (model.joints would wrap each joint)
    joints = zip(list(model.names)[1:], list(model.idx_vs)[1:], list(model.nvs)[1:], strict=True)
    for name, idx_v, nv in joints:
        for k, i in enumerate(range(idx_v, idx_v + nv)):
            names[i] = name if nv == 1 else f"{name}[{k}]"
    return names


def base_coordinates(model: Any) -> np.ndarray:
    """Which velocity coordinates (nv,) are a planar or floating base's."""
    base = np.zeros(int(model.nv), dtype=bool)
    if base_kind(model) != FIXED:
        start = int(list(model.idx_vs)[1])
        base[start : start + int(list(model.nvs)[1])] = True
    return base


def file_sources(model: Any, given: np.ndarray, otherwise: str) -> list[str]:
    """Each coordinate's source when its bound is the model's where ``given``, else ``otherwise``.

    The model's bound is a base's speed on a base's coordinates, the URDF's elsewhere.
    """
    base = base_coordinates(model)
    return [
        ("base_speed" if b else "urdf") if g else otherwise
        for g, b in zip(given, base, strict=True)
    ]


def model_velocity_limits(model: Any) -> VelocityLimits:
    """The velocity limits of a Pinocchio model (``model.velocityLimit``) with their names.

    Args:
        model: A ``pinocchio.Model``.
    """
    limit = np.array(model.velocityLimit, dtype=float)
    given = np.isfinite(limit) & (limit > 0.0)
    return VelocityLimits(velocity_names(model), limit, file_sources(model, given, "none"))


def run_velocity_limits(info: dict[str, Any], model: VelocityLimits | None) -> VelocityLimits:
    """The bounds a run used (module docstring): the law's, else the model's.

    Args:
        info: The result's ``info``; ``info["joint_speed"]`` holds the law's bounds
            (``limit`` and ``source``; a record without them: ``velocity / scale``).
        model: The model's limits (names and the URDF's), or None.
    """
    joint_speed = info.get("joint_speed") or {}
    names = model.names if model is not None else []
    limit, source = joint_speed.get("limit"), joint_speed.get("source")
    if limit is None and joint_speed.get("velocity") is not None and model is not None:
        limit = np.asarray(joint_speed["velocity"], dtype=float) / joint_speed["scale"]
        source = _older_sources(limit, model, joint_speed.get("unlimited") or [])
    if limit is None or len(limit) != len(names):
        return model if model is not None else VelocityLimits([], np.zeros(0))
    return VelocityLimits(names, np.asarray(limit, dtype=float), source)


def _older_sources(limit: np.ndarray, model: VelocityLimits, unlimited: list[str]) -> list[str]:
    """Sources of a result recorded before ``info["joint_speed"]["source"]`` existed."""
    return [
        "default"
        if name.split("[")[0] in unlimited
        else (s if np.isclose(v, m, rtol=1e-12) else "setting")
        for name, v, m, s in zip(model.names, limit, model.limit, model.sources(), strict=True)
    ]


def velocity_report(t: np.ndarray, qdot: np.ndarray, limits: VelocityLimits) -> VelocityReport:
    """Compare recorded joint speeds with their bounds.

    Args:
        t: Sample times (N,) [s].
        qdot: Joint velocities (N, nv) [rad/s or m/s].
        limits: The bound of each of the nv coordinates.

    Returns:
        The largest ratio, its joint, every bound and one record per coordinate above its bound.
    """
    qdot = np.asarray(qdot, dtype=float)
    t = np.asarray(t, dtype=float)
    index, sources = limits.limited, limits.sources()
    bounds = {
        name: {"bound": float(v) if s != "none" else None, "source": s}
        for name, v, s in zip(limits.names, limits.limit, sources, strict=True)
    }
    if index.size == 0:
        return VelocityReport(None, [], bounds=bounds)
    speed = np.abs(qdot[:, index])  # (N, n_limited)
    speed[~np.isfinite(speed)] = 0.0  # a diverged run's last samples: not a speed
    ratio = speed / limits.limit[index]
    peak = ratio.max(axis=0) if qdot.shape[0] else np.zeros(index.size)
    records = [
        _record(t, limits, i, speed[:, column], ratio[:, column])
        for column, i in enumerate(index)
        if (ratio[:, column] > 1.0).any()
    ]
    top = int(index[int(np.argmax(peak))])
    return VelocityReport(float(peak.max()), records, limits.names[top], sources[top], bounds)


def _record(
    t: np.ndarray, limits: VelocityLimits, i: int, speed: np.ndarray, ratio: np.ndarray
) -> dict[str, Any]:
    """The record of coordinate ``i``, above its bound (module docstring)."""
    over = np.flatnonzero(ratio > 1.0)
    return {
        "joint": limits.names[i],
        "max_ratio": float(ratio.max()),
        "max_velocity": float(speed.max()),
        "limit": float(limits.limit[i]),
        "source": limits.sources()[i],
        "t_first": round(float(t[over[0]]), 9),
        "t_last": round(float(t[over[-1]]), 9),
        "samples": int(over.size),
    }


SOURCE_WORDS = {
    "urdf": "URDF limit",
    "setting": "joint_speed.velocity",
    "default": "default bound joint_speed.default_velocity",
    "base_speed": "base speed",
}
"""How the console names each source."""


def speed_line(summary: dict[str, Any]) -> str | None:
    """The console's joint speed line of a summary (None for a robot without joints).

    E.g. ``joint speed: max |qdot| / bound 1.00 (panda_joint4, URDF limit)``, then the
    coordinates without a bound and those above theirs. A run with no bound at all says so.
    """
    ratio = summary.get("max_velocity_ratio")
    if ratio is None:
        if not summary.get("velocity_bounds"):
            return None
        return "joint speed: no joint has a bound (no URDF limit, joint_speed off)"
    source = SOURCE_WORDS.get(summary.get("max_velocity_ratio_source") or "", "bound")
    joint = summary.get("max_velocity_ratio_joint")
    line = f"joint speed: max |qdot| / bound {ratio:.2f}"
    line += f" ({joint}, {source})" if joint is not None else ""
    free = [k for k, v in (summary.get("velocity_bounds") or {}).items() if v["source"] == "none"]
    if free:
        line += f"; without a bound: {', '.join(free)}"
    over = ", ".join(
        f"{v['joint']} x{v['max_ratio']:.2f} from t = {v['t_first']:.3f} s"
        for v in summary.get("velocity", [])
    )
    return line + (f" (over the bound: {over})" if over else "")
