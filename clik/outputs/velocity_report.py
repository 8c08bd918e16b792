r"""Joint speeds against the robot's velocity limits: the ``velocity`` part of a summary.

The law's joint velocities are not bounded by the robot's own velocity limits
(the URDF's ``<limit velocity=...>``, Pinocchio's ``model.velocityLimit``): a
fast reference asks for whatever speed it needs. This report says how far a run
went past them. Per velocity coordinate ``i`` with a limit ``vmax_i``:

.. math::

    \rho_i = \max_k \frac{|\dot q_{i,k}|}{v_{\max,i}}

over the *recorded* samples ``k`` (every ``record_every``-th sample and the last:
with a decimated record, a peak between two recorded samples is not seen).
``max_velocity_ratio`` is :math:`\max_i \rho_i` (None when no coordinate has a
limit). A coordinate whose limit is zero, negative, infinite or not a number has
none and is skipped. Each coordinate that went past its limit (:math:`\rho_i > 1`)
gets one record:

``{"joint", "max_ratio", "max_velocity", "limit", "t_first", "t_last", "samples"}``:
the joint's name, :math:`\rho_i`, the largest :math:`|\dot q_i|` [rad/s or m/s],
``vmax_i`` [rad/s or m/s], the first and last recorded times above the limit [s],
and how many recorded samples were above it. Non-finite velocities (the last
samples of a ``diverged`` run) are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class VelocityLimits:
    """The velocity limit of each velocity coordinate, with its joint's name.

    Attributes:
        names: Name of each velocity coordinate (nv,): the joint's name, or
            ``"<joint>[k]"`` for coordinate ``k`` of a joint with several.
        limit: Largest allowed ``|qdot_i|`` (nv,) [rad/s or m/s]; a value that is
            not finite and positive means no limit.
    """

    names: list[str]
    limit: np.ndarray

    def __post_init__(self) -> None:
        limit = np.asarray(self.limit, dtype=float).reshape(-1)
        if limit.shape != (len(self.names),):
            raise ValueError(
                f"VelocityLimits: {len(self.names)} names but limit of shape {limit.shape}"
            )
        object.__setattr__(self, "limit", limit)

    @property
    def limited(self) -> np.ndarray:
        """Indices of the coordinates that have a limit (finite and > 0)."""
        return np.flatnonzero(np.isfinite(self.limit) & (self.limit > 0.0))


@dataclass(frozen=True)
class VelocityReport:
    """How far a run's joint speeds went past their limits.

    Attributes:
        max_velocity_ratio: Largest ``|qdot_i| / vmax_i`` over the recorded samples
            and the limited coordinates, or None when no coordinate has a limit.
        records: One record per coordinate above its limit (see the module docstring),
            in velocity order.
    """

    max_velocity_ratio: float | None
    records: list[dict[str, Any]] = field(default_factory=list)


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


def model_velocity_limits(model: Any) -> VelocityLimits:
    """The velocity limits of a Pinocchio model (``model.velocityLimit``) with their names.

    Args:
        model: A ``pinocchio.Model``.
    """
    return VelocityLimits(velocity_names(model), np.array(model.velocityLimit, dtype=float))


def velocity_report(t: np.ndarray, qdot: np.ndarray, limits: VelocityLimits) -> VelocityReport:
    """Compare recorded joint speeds with their limits.

    Args:
        t: Sample times (N,) [s].
        qdot: Joint velocities (N, nv) [rad/s or m/s].
        limits: The limit of each of the nv coordinates.

    Returns:
        The largest ratio and one record per coordinate above its limit.
    """
    qdot = np.asarray(qdot, dtype=float)
    t = np.asarray(t, dtype=float)
    index = limits.limited
    if index.size == 0:
        return VelocityReport(None, [])
    if qdot.shape[0] == 0:
        return VelocityReport(0.0, [])
    speed = np.abs(qdot[:, index])  # (N, n_limited)
    speed[~np.isfinite(speed)] = 0.0  # a diverged run's last samples: not a speed
    ratio = speed / limits.limit[index]
    peak = ratio.max(axis=0)
    records = []
    for column, i in enumerate(index):
        over = np.flatnonzero(ratio[:, column] > 1.0)
        if over.size == 0:
            continue
        records.append(
            {
                "joint": limits.names[i],
                "max_ratio": float(peak[column]),
                "max_velocity": float(speed[:, column].max()),
                "limit": float(limits.limit[i]),
                "t_first": round(float(t[over[0]]), 9),
                "t_last": round(float(t[over[-1]]), 9),
                "samples": int(over.size),
            }
        )
    return VelocityReport(float(peak.max()), records)
