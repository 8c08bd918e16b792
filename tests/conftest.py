"""Shared fixtures: robots load once per test session."""

from __future__ import annotations

import os

import pytest

from clik.model.robot import PANDA_FINGERS, Robot

if os.environ.get("CLIK_SANITIZE"):
    # make sanitize: a subprocess a test starts stops at its first UBSan report (exit status
    # 1), so the test fails even when it captures the stderr the report goes to. This
    # process keeps going: a sanitizer reads its options from the environment the process
    # started with (/proc/self/environ), not from os.environ.
    os.environ["UBSAN_OPTIONS"] = os.environ.get("UBSAN_OPTIONS", "") + ":halt_on_error=1"


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
