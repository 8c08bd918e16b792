"""Scenarios: one TOML file names everything a run needs.

``scenario`` reads and checks a file (with :mod:`clik.schema`), ``runner``
turns a scenario into objects and runs it. The package also
ships scenario files (the ``*.toml`` here, found with ``importlib.resources``):
the case study of docs/method.md, laws (9) and (10), the Panda's, and
``baxter_two_hands`` (several tasks: ``[[tasks]]``). ``build_tasks`` and ``task_tables``
read and build several tasks, ``fields`` holds what several tables share.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

CASE_STUDY = (
    "case_study_unconstrained",
    "case_study_obstacle",
    "case_study_joint_limit",
    "case_study_both",
    "case_study_unconstrained_pinv",
    "case_study_obstacle_pinv",
    "case_study_joint_limit_pinv",
    "case_study_both_pinv",
)
"""The shipped case-study scenarios: runs 1-4 with law (9), then with law (10)."""


def scenario_path(name: str) -> Path:
    """Path of a shipped scenario file (``name`` without ``.toml``)."""
    return Path(str(resources.files("clik.scenarios").joinpath(f"{name}.toml")))
