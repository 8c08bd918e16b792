"""The physics check: a run replayed in MuJoCo (``clik simulate``, docs/guides/simulate.md).

:func:`simulate` drives the robot MuJoCo compiles through position servos with gravity
compensation and the run's joint velocities fed forward, and measures how far each task
point strays from its reference, how close the robot comes to the obstacles and which
servos saturate (:class:`Simulation`).
"""

from clik.sim.replay import simulate
from clik.sim.report import SIMULATION_FILE, SIMULATION_PLOT, Simulation

__all__ = ["SIMULATION_FILE", "SIMULATION_PLOT", "Simulation", "simulate"]
