"""Shared fixtures: robots load once per test session."""

from __future__ import annotations

import pytest

from clik.model.robot import PANDA_FINGERS, Robot


@pytest.fixture(scope="session")
def planar4r() -> Robot:
    """The paper's planar 4-DOF arm (robots/planar4r.urdf)."""
    return Robot.load("planar4r")


@pytest.fixture(scope="session")
def panda() -> Robot:
    """Franka Panda from example-robot-data, fingers locked: 7 DOF."""
    return Robot.load("panda", lock=PANDA_FINGERS)


@pytest.fixture(scope="session")
def ur5() -> Robot:
    """UR5 from example-robot-data: 6 DOF."""
    return Robot.load("ur5")
