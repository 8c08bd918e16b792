r"""The criteria of eq. (5) and their gradients ``z = k grad H`` [rad/s].

docs/method.md, "Several tasks, priority levels and eq. (5)". Each is projected by the
law into the null space of the constraints and the task levels above it
(:func:`clik.loop.levels.prioritized_levels`), so it moves the arm only where no task
(and no constraint) asks anything.

- Joint-range centring (Liegeois 1977, the paper's reference [3]):
  ``H = 1/2 sum_i ((q_i - a_i) / h_i)^2`` over the joints with finite limits, ``a_i``
  the middle and ``h_i`` the half of the range: ``z_i = -k (q_i - a_i) / h_i^2``
  (``k`` in [rad^2/s]: a joint at its limit is pushed back at ``k / h_i`` [rad/s]).
- Manipulability: ``H = w = sqrt(det(J J^T))`` of the primary task's rows (D1),
  ``z = k grad_q w`` (D3), the dexterity row's gradient.
- Posture: ``H = -1/2 |q - q_p|^2`` (``q - q_p`` as ``pin.difference``):
  ``z = k difference(q, q_p)`` (``k`` in [1/s]).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def joint_centering(
    q: np.ndarray, idx_q: np.ndarray, idx_v: np.ndarray, center: np.ndarray,
    half_range: np.ndarray, gain: float, out: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """``z_i = -k (q_i - a_i) / h_i^2`` on the joints listed, 0 elsewhere, into ``out`` (nv,)."""
    out[:] = 0.0
    out[idx_v] = -gain * (q[idx_q] - center) / (half_range * half_range)
    return out


def posture(
    model: pin.Model, q: np.ndarray, q_ref: np.ndarray, gain: float, out: np.ndarray
) -> np.ndarray:
    """``z = k difference(q, q_p)`` into ``out`` (nv,)."""
    out[:] = gain * pin.difference(model, q, q_ref)
    return out
