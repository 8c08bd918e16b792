"""Solve mode: one target pose reached from ``q0`` by iterating a law to tolerance.

``solve_mode`` holds :func:`clik.solve` (in Python or in the compiled engine),
``solve_result`` what it returns, ``constrained_solve`` the constrained law used
when the unconstrained pose breaks a constraint, ``pose_check`` whether a
configuration is clear of its constraints.
"""
