"""Playback frames: which recorded samples a scene shows, and when.

A result holds every ``record_every``-th CLIK step (often every step, 1 ms
apart); a viewer needs far fewer. The timeline keeps one sample per frame at
``fps`` frames per second of the run's time, plus the last sample, so the
animation plays in real time and ends on the final pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from clik.errors import InputError


@dataclass(frozen=True)
class Timeline:
    """Playback times and the samples shown at them.

    Attributes:
        times: Playback times (K,) [s], from 0 to the run's duration.
        index: Index of the recorded sample shown at each time (K,).
    """

    times: np.ndarray
    index: np.ndarray

    @classmethod
    def from_times(cls, t: np.ndarray, fps: float) -> Timeline:
        """Frames at ``fps`` [1/s] over the sample times ``t`` (N,) [s], nearest samples."""
        if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
            raise InputError("fps", "a positive number of frames per second", got=fps)
        t = np.asarray(t, dtype=float).reshape(-1)
        if t.size == 0:
            raise InputError("result.t", "at least one recorded sample")
        duration = float(t[-1] - t[0])
        n = math.floor(duration * fps + 1e-9) + 1
        times = np.arange(n) / fps
        if duration - times[-1] > 1e-9:
            times = np.append(times, duration)
        right = np.clip(np.searchsorted(t - t[0], times), 0, t.size - 1)
        left = np.clip(right - 1, 0, t.size - 1)
        nearer_left = np.abs(t[left] - t[0] - times) < np.abs(t[right] - t[0] - times)
        index = np.where(nearer_left, left, right)
        return cls(times, index)

    @property
    def duration(self) -> float:
        """Length of the animation [s]."""
        return float(self.times[-1])

    def __len__(self) -> int:
        return len(self.times)


def joint_placements(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """World placements of every joint for each configuration: (K, njoints, 4, 4)."""
    data = model.createData()
    out = np.empty((len(q), model.njoints, 4, 4))
    for k, qk in enumerate(q):
        pin.forwardKinematics(model, data, qk)
        for j in range(model.njoints):
            out[k, j] = data.oMi[j].homogeneous
    return out


def frame_origins(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """World positions of every frame's origin for each configuration: (K, nframes, 3) [m]."""
    data = model.createData()
    out = np.empty((len(q), model.nframes, 3))
    for k, qk in enumerate(q):
        pin.framesForwardKinematics(model, data, qk)
        for f in range(model.nframes):
            out[k, f] = data.oMf[f].translation
    return out
