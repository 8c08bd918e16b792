"""The robot model: a fixed-base robot's Pinocchio models, loaded safely.

:class:`~clik.model.robot.Robot` is the entry point (``Robot.load``); the
concerns it delegates sit one per module: where a robot is read from
(``sources``), the models built from a checked URDF (``loading``), joint kinds
and units (``joints``), locked joints (``locking``), mimic joints (``mimic``)
and configuration checks (``configuration``).
"""
