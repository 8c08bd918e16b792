"""A shipped scenario run in an engine, and its frames by Pinocchio's forward kinematics.

The kinds' example checks read the written joints through Pinocchio, not clik's own
numbers.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin

from clik.scenarios import scenario_path
from clik.scenarios.runner import Run, build

ENGINES = ("python", "compiled")
"""Both engines."""


def ran(name: str, engine: str) -> tuple[Run, object]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Baxter's SRDF names prefixed joints
        run = build(scenario_path(name))
    run.tracker.engine = engine
    return run, run.execute()


def placements(run: Run, q: np.ndarray, frames: list[str]) -> dict[str, np.ndarray]:
    """Each frame's world placement (N, 4, 4) at the written joints (Pinocchio's FK)."""
    model = run.robot.model
    data = model.createData()
    ids = {f: model.getFrameId(f) for f in frames}
    out: dict[str, list[np.ndarray]] = {f: [] for f in frames}
    for qk in q:
        pin.framesForwardKinematics(model, data, qk)
        for f, i in ids.items():
            out[f].append(data.oMf[i].homogeneous.copy())
    return {f: np.array(v) for f, v in out.items()}
