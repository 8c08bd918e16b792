"""The numbers both engines use are the same: the Python values are the specification.

Each constant the compiled engine declares is exposed as an attribute of
``clik._engine``; each must equal its Python counterpart, and every such attribute
must have one here (a new shared constant is a row of :data:`SHARED`).
"""

from __future__ import annotations

import importlib

import pytest

engine = pytest.importorskip("clik._engine")

SHARED = {
    "AT_THRESHOLD": ("clik.constraints.constraint_run", "AT_THRESHOLD"),
    "GJK_TOLERANCE": ("clik.constraints.collision_scene", "GJK_TOLERANCE"),
    "SINGULAR_DAMPING": ("clik.constraints.dexterity", "SINGULAR_DAMPING"),
    "CONDITION_RATIO": ("clik.loop.laws", "CONDITION_RATIO"),
    "STEP_BUDGET": ("clik.loop.laws", "STEP_BUDGET"),
    "RANK_TOLERANCE": ("clik.loop.laws", "RANK_TOLERANCE"),
    "GRAM_TOLERANCE": ("clik.loop.levels", "GRAM_TOLERANCE"),
    "NEGLIGIBLE": ("clik.loop.speed_step", "NEGLIGIBLE"),
    "CONTACT_DISTANCE": ("clik.constraints.obstacle_rows", "CONTACT_DISTANCE"),
    "MIN_WITNESS_GAP": ("clik.constraints.obstacle_rows", "MIN_WITNESS_GAP"),
    "PARALLEL_SINE": ("clik.constraints.cone", "PARALLEL_SINE"),
    "BLOCKED_FRACTION": ("clik.loop.stop_checks", "BLOCKED_FRACTION"),
    "STABILITY_EVERY": ("clik.loop.stop_checks", "STABILITY_EVERY"),
    "JOINT_TOLERANCE": ("clik.constraints.violations", "JOINT_TOLERANCE"),
    "STALL_PROGRESS": ("clik.solving.solve_problem", "STALL_PROGRESS"),
    "STALL_ITERATIONS": ("clik.solving.solve_problem", "STALL_ITERATIONS"),
    "ROTATION_TOLERANCE": ("clik.trajectory._validate", "ROTATION_TOLERANCE"),
    "CLOUD_GJK_TOLERANCE": ("clik.clouds.nearest", "CLOUD_GJK_TOLERANCE"),
    "POINT_RADIUS": ("clik.clouds.nearest", "POINT_RADIUS"),
    "MAX_PLANES": ("clik.clouds.nearest", "MAX_PLANES"),
    "MAX_GRID_SPAN": ("clik.clouds.grid", "MAX_GRID_SPAN"),
    "MIN_CELL": ("clik.clouds.grid", "MIN_CELL"),
}
"""Engine attribute -> (Python module, name) of the same number."""

NOT_SHARED = {"PINOCCHIO_VERSION", "COAL_VERSION"}
"""Upper-case engine attributes that are not numbers of the method (build facts)."""


@pytest.mark.parametrize("name", sorted(SHARED))
def test_engine_constant_is_the_python_one(name):
    module, attribute = SHARED[name]
    expected = getattr(importlib.import_module(module), attribute)
    value = getattr(engine, name)
    assert type(value) is type(expected), name
    assert value == expected, f"_engine.{name} = {value!r}, {module}.{attribute} = {expected!r}"


def test_every_engine_constant_has_a_counterpart():
    exposed = {n for n in dir(engine) if n.isupper() and not n.startswith("_")}
    assert exposed - NOT_SHARED == set(SHARED)
