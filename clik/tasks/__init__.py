"""Tasks: where a frame of the robot must be, as rows of the task vector.

A task gives the rows of eq. (3): its error ``e = x_d - x`` and its Jacobian
``J`` at a configuration (``task``, the frame task on a component mask). What
is built from tasks: the extended task of eqs. (24)-(25), the task's rows and
the constraints' active rows stacked for the law (``extended_task``), and the
task's manipulability ``w(q)`` (``manipulability``).

The kinds of task (``kind``: what each says; ``registry``: the list): each one module
``*_task``, e.g. a frame in the world (``task``); a ``goal`` gives one its trajectory,
gain and priority.
"""
