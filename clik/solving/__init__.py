"""Solve mode: one target pose reached from ``q0`` by iterating a law to tolerance.

``solve_mode`` holds :func:`clik.solve` (its attempts and restarts),
``solve_problem`` the iteration (target, settings, error and step: the
specification the compiled engine follows), ``compiled_solve`` the same solve in
the compiled engine (its solvers kept per task), ``solve_result`` what it
returns, ``constrained_solve`` the constrained law used when the unconstrained
pose breaks a constraint (checked by :mod:`clik.constraints.pose_check`: whether a
configuration is clear of its constraints).
"""
