"""What a replay measured (:class:`Simulation`): ``simulation.json``, words and a plot."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from clik.errors import InputError

SIMULATION_FILE = "simulation.json"
"""The replay's measures in an output folder."""
SIMULATION_PLOT = "simulation.png"
"""The replay's plot in an output folder."""


def _stats(x: np.ndarray) -> dict[str, float]:
    return {"max": float(np.max(x)), "median": float(np.median(x))}


@dataclass
class Simulation:
    """A run replayed in MuJoCo (:func:`clik.sim.replay.simulate`).

    Attributes:
        t: The run's sample times (N,) [s].
        joints: The joints driven, by name (n).
        q_run: The run's joint values (N, n) [rad or m].
        q_sim: The joint values MuJoCo reached at the same times (N, n).
        task_names: The task points measured, in order.
        errors: Each task point's distance from its reference in the replay (N,) [m].
        run_errors: The same on the run's own joints (N,) [m].
        min_clearance: The smallest robot-obstacle distance at each sample (N,) [m], or
            None without obstacles.
        obstacles: The obstacles' names.
        saturated_steps: Per joint, the simulation steps its servo spent at its force
            limit.
        peak_force_ratio: Per joint, the largest |servo force| / force limit (0 without a
            limit).
        steps: Simulation steps.
        feedforward: Whether the joint velocities were fed forward.
        kp: Servo stiffness.
        kv: Servo damping.
        timestep: The simulation step [s].
        dropped: Collision meshes MuJoCo could not read, left out.
        mujoco_version: MuJoCo's version.
    """

    t: np.ndarray
    joints: list[str]
    q_run: np.ndarray
    q_sim: np.ndarray
    task_names: list[str]
    errors: dict[str, np.ndarray]
    run_errors: dict[str, np.ndarray]
    min_clearance: np.ndarray | None
    obstacles: list[str]
    saturated_steps: np.ndarray
    peak_force_ratio: np.ndarray
    steps: int
    feedforward: bool
    kp: float
    kv: float
    timestep: float
    dropped: list[str] = field(default_factory=list)
    mujoco_version: str = ""

    def summary(self) -> dict[str, Any]:
        """``simulation.json``'s content (lengths in m, times in s)."""
        saturated = [
            {"joint": j, "time_s": float(n * self.timestep), "fraction": float(n / self.steps)}
            for j, n in zip(self.joints, self.saturated_steps, strict=True)
            if n > 0
        ]
        clearance = None if self.min_clearance is None else float(np.min(self.min_clearance))
        return {
            "position_error_m": {n: _stats(self.errors[n]) for n in self.task_names},
            "run_position_error_m": {n: _stats(self.run_errors[n]) for n in self.task_names},
            "min_clearance_m": clearance,
            "obstacles": list(self.obstacles),
            "saturated_joints": saturated,
            "max_joint_gap": float(np.max(np.abs(self.q_sim - self.q_run))),
            "feedforward": self.feedforward,
            "servo": {"kp": self.kp, "kv": self.kv, "gravity_compensation": True},
            "timestep_s": self.timestep,
            "steps": self.steps,
            "duration_s": float(self.t[-1] - self.t[0]),
            "contacts": False,
            "dropped_meshes": list(self.dropped),
            "mujoco": self.mujoco_version,
        }

    def words(self) -> str:
        """The summary in a few lines, as ``clik simulate`` prints it."""
        s = self.summary()
        feed = "with" if self.feedforward else "without"
        lines = [
            f"MuJoCo {self.mujoco_version}: {self.steps} steps of {1e3 * self.timestep:g} ms, "
            f"position servos (kp {self.kp:g}, kv {self.kv:g}) {feed} velocity feed-forward, "
            "gravity compensated"
        ]
        for name in self.task_names:
            e, r = s["position_error_m"][name], s["run_position_error_m"][name]
            lines.append(
                f"  task {name}: off its reference by {1e3 * e['median']:.3g} mm median, "
                f"{1e3 * e['max']:.3g} mm max (the run itself: {1e3 * r['max']:.3g} mm max)"
            )
        if not self.task_names:
            lines.append("  no task point to measure (no frame or centre-of-mass task)")
        if s["min_clearance_m"] is not None:
            c = s["min_clearance_m"]
            verdict = "a collision" if c < 0 else "clear"
            lines.append(f"  obstacles: smallest clearance {1e3 * c:.3g} mm ({verdict})")
        if s["saturated_joints"]:
            names = ", ".join(f"{j['joint']} {j['time_s']:.3g} s" for j in s["saturated_joints"])
            lines.append(f"  servos at their force limit: {names}")
        else:
            lines.append("  no servo reached its force limit")
        lines.append(f"  largest joint gap to the run: {s['max_joint_gap']:.3g} rad or m")
        if self.dropped:
            lines.append(f"  left out (MuJoCo reads STL, OBJ, MSH): {len(self.dropped)} meshes")
        return "\n".join(lines)

    def write(self, folder: str | Path, force: bool = False) -> list[Path]:
        """Write ``simulation.json`` and ``simulation.png`` into ``folder``; their paths.

        Args:
            folder: An existing folder (an output folder of ``clik solve``).
            force: Replace an existing ``simulation.json``.

        Raises:
            InputError: ``simulation.json`` exists and ``force`` is False.
        """
        folder = Path(folder)
        path = folder / SIMULATION_FILE
        if path.exists() and not force:
            raise InputError(
                str(path), "a new file (it exists: pass force=True, or --force, to replace it)"
            )
        path.write_text(json.dumps(self.summary(), indent=2) + "\n")
        return [path, self.plot(folder / SIMULATION_PLOT)]

    def plot(self, path: str | Path) -> Path:
        """Each task point's distance from its reference, replay and run, over time."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        rows = 2 if self.min_clearance is not None else 1
        fig, axes = plt.subplots(rows, 1, figsize=(8, 3.2 * rows), sharex=True, squeeze=False)
        ax = axes[0, 0]
        for name in self.task_names:
            ax.plot(self.t, 1e3 * self.errors[name], label=f"{name}: MuJoCo")
            ax.plot(self.t, 1e3 * self.run_errors[name], "--", label=f"{name}: the run")
        ax.set_ylabel("distance from reference [mm]")
        feed = "with" if self.feedforward else "without"
        ax.set_title(f"replay in MuJoCo, {feed} velocity feed-forward")
        if self.task_names:
            ax.legend(fontsize="small")
        if self.min_clearance is not None:
            ax2 = axes[1, 0]
            ax2.plot(self.t, 1e3 * self.min_clearance)
            ax2.axhline(0.0, color="k", lw=0.8)
            ax2.set_ylabel("smallest clearance [mm]")
        axes[-1, 0].set_xlabel("t [s]")
        fig.tight_layout()
        fig.savefig(path, dpi=100)
        plt.close(fig)
        return Path(path)
