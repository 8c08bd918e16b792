"""The robot model: a fixed-base robot's Pinocchio models, loaded safely.

:class:`~clik.model.robot.Robot` is the entry point (``Robot.load``); the
concerns it delegates sit one per module: where a robot is read from
(``sources``), the strict checks on a URDF and its meshes before any library
reads them (``urdf_check``, with ``urdf_joints``, ``urdf_links`` and
``urdf_numbers``; ``mesh_check``), optional visual meshes (``visual_meshes``:
a missing one is a warning), xacro expansion
(``xacro_expand``), SRDF files: disabled collision pairs and group states
(``srdf``), the models built from a checked URDF (``loading``), joint
kinds and units (``joints``), locked and mimic joints (``locking``, ``mimic``),
configuration checks (``configuration``) and the check that a loaded model
has not changed since (``model_signature``). Beside them, what the model alone
decides: planar arms written as URDF (``planar_arm``) and the bound on how far a
frame can reach (``reach``).
"""
