r"""When the law's joint speed bounds held the joints back: the ``speed_limited`` summary keys.

A run whose law bounds the joint speeds records them in ``info["joint_speed"]``:
``None`` when off, else ``{"scale", "velocity", "acceleration", "default_velocity",
"unlimited"}`` with ``velocity`` the bound :math:`v_i` used per velocity coordinate
[rad/s or m/s, scale applied] and ``acceleration`` :math:`a_i` per coordinate (None
where not given) or None. On the recorded samples ``k``:

- a coordinate runs *at its bound* when :math:`|\dot q_{i,k}| \ge v_i (1 - 10^{-6})`;
  ``speed_limited`` holds one record per such coordinate,
  ``{"joint", "t_first", "t_last", "samples"}`` (its name, the first and last recorded
  time at its bound [s], how many recorded samples), and ``speed_limited_time`` the time
  [s] any coordinate was at its bound: the recorded samples at a bound times their
  spacing (``dt * record_every``);
- ``max_acceleration_ratio`` is :math:`\max_{k,i} |\ddot q_{i,k}| / a_i` over the
  coordinates with an acceleration bound, or None without any.
"""

from __future__ import annotations

from typing import Any

import numpy as np

AT_BOUND = 1e-6
"""A speed within this fraction of its bound is at the bound."""


def _bounds(info: dict[str, Any], key: str, nv: int) -> np.ndarray | None:
    """``info["joint_speed"][key]`` as an (nv,) array (nan: no bound), or None."""
    joint_speed = info.get("joint_speed")
    values = None if not joint_speed else joint_speed.get(key)
    if values is None:
        return None
    out = np.array([np.nan if v is None else float(v) for v in values], dtype=float)
    if out.shape != (nv,):
        return None
    out[~(np.isfinite(out) & (out > 0.0))] = np.nan
    return out


def speed_limited(
    t: np.ndarray, qdot: np.ndarray, names: list[str], info: dict[str, Any]
) -> tuple[list[dict[str, Any]], float]:
    """The ``speed_limited`` records and ``speed_limited_time`` [s] (module docstring).

    Args:
        t: Recorded times (N,) [s].
        qdot: Recorded joint velocities (N, nv) [rad/s or m/s].
        names: Name of each velocity coordinate (nv,).
        info: The result's ``info`` (``joint_speed``, ``dt``, ``record_every``).
    """
    bound = _bounds(info, "velocity", qdot.shape[1])
    if bound is None or qdot.shape[0] == 0:
        return [], 0.0
    speed = np.abs(qdot)
    with np.errstate(invalid="ignore"):
        at = np.isfinite(speed) & (speed >= bound * (1.0 - AT_BOUND))
    records = []
    for i in np.flatnonzero(at.any(axis=0)):
        hit = np.flatnonzero(at[:, i])
        records.append(
            {
                "joint": names[i] if i < len(names) else f"coordinate {i}",
                "t_first": round(float(t[hit[0]]), 9),
                "t_last": round(float(t[hit[-1]]), 9),
                "samples": int(hit.size),
            }
        )
    spacing = float(info.get("dt", 0.0)) * int(info.get("record_every", 1))
    return records, float(at.any(axis=1).sum()) * spacing


def max_acceleration_ratio(qddot: np.ndarray, info: dict[str, Any]) -> float | None:
    """Largest ``|qddot_i| / a_i`` over the recorded samples, or None (module docstring)."""
    bound = _bounds(info, "acceleration", qddot.shape[1])
    if bound is None or not np.isfinite(bound).any():
        return None
    if qddot.shape[0] == 0:
        return 0.0
    keep = np.isfinite(bound)
    accel = np.abs(qddot[:, keep])
    accel[~np.isfinite(accel)] = 0.0
    return float((accel / bound[keep]).max())
