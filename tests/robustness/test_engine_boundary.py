"""The compiled engine's own boundary: every function and constructor of ``clik._engine``
checks what it receives and raises a clear Python exception; nothing reaches the loop
unchecked.

Each test hands the engine one bad value next to valid ones (built here as
``clik/loop/compiled_run.py`` builds them) and asserts the exception and the field its
message names. Run under ``make sanitize`` too: a value that slipped through would be a
report there, or a crash of the test process here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.engine import load
from clik.model.robot import PANDA_FINGERS

E = load()


@dataclass
class Parts:
    """A valid run's parts for planar4r's tip, position task on x and y (N samples)."""

    robot: clik.Robot
    N: int = 50
    every: int = 1
    args: dict[str, Any] = field(default_factory=dict)

    def record(self, **changes: Any) -> Any:
        n = (self.N - 1) // self.every + 1 + ((self.N - 1) % self.every > 0)
        nq, nv = self.robot.nq, self.robot.nv
        arrays: dict[str, Any] = dict(
            N=self.N, every=self.every, idx=np.zeros(n, dtype=np.intp), q=np.zeros((n, nq)),
            qdot=np.zeros((n, nv)), qddot=np.zeros((n, nv)), position=np.zeros((n, 3)),
            reference=np.zeros((n, 3)), error=np.zeros(n), orientation_error=None,
            active=None, distance=None, joint_min=np.zeros(nq), joint_max=np.zeros(nq),
            qdot_prev=np.zeros(nv),
        )  # fmt: skip
        arrays.update(changes)
        return E.RecordArrays(**arrays)

    def run(self, **changes: Any) -> Any:
        task = clik.Task(self.robot, "tip", "position", axes=["x", "y"])
        args: dict[str, Any] = dict(
            model=self.robot.model,
            task=E.TaskConfig(frame=task.frame_id, rows=[0, 1], has_position=True,
                              has_orientation=False),
            law=E.LawConfig(law="transpose", damping=0.0, dt=1e-3, beta_max=2000.0,
                            K_task=np.full(2, 1000.0), rows=2, alpha=1000.0),
            stop=E.StopConfig(deadlock_window=0.1, deadlock_ratio=1e-4, deadlock_error=1e-3,
                              max_joint_step=1.0, stall_window=0.5, stall_progress=0.01),
            t=np.arange(self.N) * 1e-3,
            record=None,
            joints=E.JointMonitorConfig(index=[], lower=np.zeros(0), upper=np.zeros(0),
                                        names=[]),
            constraints=None,
        )  # fmt: skip
        args.update(changes)
        if args["record"] is None:
            args["record"] = self.record()
        return E.TrackingRun(**args)

    def chunk(self, c0: int, c1: int) -> dict[str, Any]:
        """A valid advance(): the tip held where it starts."""
        n = c1 - c0
        p = clik.Task(self.robot, "tip", "position").placement(self.q0()).translation
        return dict(
            c0=c0, c1=c1, P_d=np.tile(p, (n, 1)), R_d=None, FF=np.zeros((n, 2)),
            at_rest=np.ones(n, dtype=bool), q=self.q0(),
        )  # fmt: skip

    def q0(self) -> np.ndarray:
        return np.radians([180.0, -30.0, -90.0, -30.0])


@pytest.fixture
def parts() -> Parts:
    return Parts(clik.Robot.load("planar4r"))


def test_a_valid_run_advances_to_its_end(parts):
    run = parts.run()
    args = parts.chunk(0, parts.N)
    out = run.advance(**args)
    assert out[0] == parts.N and out[1] == ""
    assert run.steps == parts.N and run.kept == parts.N
    assert np.all(np.isfinite(args["q"]))


# ---------------------------------------------------------------- advance


@pytest.mark.parametrize(
    ("change", "error"),
    [
        pytest.param({"FF": np.zeros((10, 2))}, ValueError, id="FF-too-short"),
        pytest.param({"FF": np.zeros((50, 3))}, ValueError, id="FF-wrong-rows"),
        pytest.param({"FF": np.zeros(100)}, ValueError, id="FF-flat"),
        pytest.param({"at_rest": np.ones(10, dtype=bool)}, ValueError, id="at_rest-too-short"),
        pytest.param({"P_d": np.zeros((10, 3))}, ValueError, id="P_d-too-short"),
        pytest.param({"P_d": np.zeros((50, 2))}, ValueError, id="P_d-two-columns"),
        pytest.param({"P_d": None}, ValueError, id="P_d-missing-for-a-position-task"),
        pytest.param({"R_d": np.zeros((50, 3))}, ValueError, id="R_d-not-3x3"),
        pytest.param({"q": np.zeros(3)}, ValueError, id="q-short"),
        pytest.param({"q": np.zeros((4, 1))}, ValueError, id="q-2d"),
        pytest.param({"q": np.zeros(4, dtype=np.float32)}, TypeError, id="q-float32"),
        pytest.param({"q": np.zeros(8)[::2]}, TypeError, id="q-strided"),
        pytest.param({"FF": np.zeros((50, 2), dtype=np.float32)}, TypeError, id="FF-float32"),
        pytest.param({"FF": np.zeros((50, 4))[:, ::2]}, TypeError, id="FF-strided"),
        pytest.param({"at_rest": np.ones(50)}, TypeError, id="at_rest-float"),
        pytest.param({"c1": 51}, ValueError, id="c1-beyond-N"),
        pytest.param({"c0": -1}, ValueError, id="c0-negative"),
        pytest.param({"c0": 5}, ValueError, id="c0-not-the-next-sample"),
        pytest.param({"c1": 2**62}, ValueError, id="c1-huge"),
        pytest.param({"c1": 2**70}, TypeError, id="c1-beyond-a-long"),
    ],
)
def test_advance_refuses_a_bad_chunk(parts, change, error):
    run = parts.run()
    args = parts.chunk(0, parts.N)
    args.update(change)
    with pytest.raises(error):
        run.advance(**args)
    assert run.steps == 0  # nothing ran


def test_advance_twice_over_the_same_samples_is_refused(parts):
    """Re-running samples would write the record past its end (kept > capacity)."""
    run = parts.run()
    run.advance(**parts.chunk(0, parts.N))
    with pytest.raises(ValueError, match="next sample"):
        run.advance(**parts.chunk(0, parts.N))
    assert run.kept == parts.N


def test_advance_after_a_stop_is_refused(parts):
    run = parts.run(
        stop=E.StopConfig(deadlock_window=0.1, deadlock_ratio=1e-4, deadlock_error=1e-3,
                          max_joint_step=1e-12, stall_window=0.5, stall_progress=0.01),
    )  # fmt: skip
    args = parts.chunk(0, parts.N)
    args["P_d"] = args["P_d"] + 0.1  # a step of 1e-12 rad at most: stops at once
    out = run.advance(**args)
    assert out[1] == "joint_step"
    more = parts.chunk(out[0], parts.N)
    with pytest.raises(ValueError, match="stopped"):
        run.advance(**more)


def test_a_model_changed_after_the_run_was_built_is_refused(parts):
    run = parts.run()
    chunk = parts.chunk(0, parts.N)
    model = parts.robot.model
    model.addJoint(model.njoints - 1, pin.JointModelRZ(), pin.SE3.Identity(), "extra")
    with pytest.raises(ValueError, match=r"pin\.Model changed"):
        run.advance(**chunk)
    assert run.steps == 0


# ---------------------------------------------------------------- the run's configs


def _stop(**changes: float) -> Any:
    values = dict(deadlock_window=0.1, deadlock_ratio=1e-4, deadlock_error=1e-3,
                  max_joint_step=1.0, stall_window=0.5, stall_progress=0.01)  # fmt: skip
    values.update(changes)
    return E.StopConfig(**values)


@pytest.mark.parametrize("name", ["deadlock_window", "stall_window"])
@pytest.mark.parametrize("value", [np.inf, np.nan, 0.0, -1.0])
def test_stop_windows_must_be_finite_and_positive(name, value):
    with pytest.raises(ValueError, match=name):
        _stop(**{name: value})


@pytest.mark.parametrize("name", ["deadlock_window", "stall_window"])
def test_a_window_of_more_samples_than_a_long_holds_is_refused(parts, name):
    """1e300 s / dt used to be cast to an integer: undefined behaviour (UBSan)."""
    with pytest.raises(ValueError, match=name):
        parts.run(stop=_stop(**{name: 1e300}))


@pytest.mark.parametrize(
    ("name", "value"),
    [("deadlock_ratio", np.nan), ("deadlock_error", -1.0), ("max_joint_step", 0.0),
     ("stall_progress", np.inf)],
)  # fmt: skip
def test_stop_thresholds_are_checked(name, value):
    with pytest.raises(ValueError, match="StopConfig"):
        _stop(**{name: value})


@pytest.mark.parametrize(
    ("name", "value"),
    [("dt", np.inf), ("dt", 0.0), ("damping", np.nan), ("beta_max", -1.0), ("alpha", np.inf),
     ("rows", 0), ("K_task", np.zeros(0))],
)  # fmt: skip
def test_law_settings_are_checked(name, value):
    values: dict[str, Any] = dict(law="transpose", damping=0.0, dt=1e-3, beta_max=2000.0,
                                  K_task=np.full(2, 1000.0), rows=2, alpha=1000.0)  # fmt: skip
    values[name] = value
    with pytest.raises(ValueError, match="LawConfig"):
        E.LawConfig(**values)


def test_task_gains_must_be_finite_and_positive(parts):
    law = E.LawConfig(law="transpose", damping=0.0, dt=1e-3, beta_max=2000.0,
                      K_task=np.array([1000.0, np.nan]), rows=2, alpha=1000.0)  # fmt: skip
    with pytest.raises(ValueError, match="K_task"):
        parts.run(law=law)


def test_rows_beyond_the_task_and_the_joints_are_refused(parts):
    """rows sizes the extended task's matrices: 10**9 would allocate gigabytes."""
    law = E.LawConfig(law="transpose", damping=0.0, dt=1e-3, beta_max=2000.0,
                      K_task=np.full(2, 1000.0), rows=10**9, alpha=1000.0)  # fmt: skip
    with pytest.raises(ValueError, match="rows"):
        parts.run(law=law)


@pytest.mark.parametrize(
    "task",
    [dict(frame=10**6, rows=[0, 1]), dict(frame=-1, rows=[0, 1]), dict(frame=1, rows=[0, 9]),
     dict(frame=1, rows=[])],
)  # fmt: skip
def test_a_task_outside_the_model_is_refused(parts, task):
    config = E.TaskConfig(has_position=True, has_orientation=False, **task)
    with pytest.raises(ValueError, match="TrackingRun"):
        parts.run(task=config)


def test_the_time_grid_must_match_the_record_and_be_finite(parts):
    with pytest.raises(ValueError, match="TrackingRun"):
        parts.run(t=np.arange(40) * 1e-3)
    t = np.arange(parts.N) * 1e-3
    t[7] = np.nan
    with pytest.raises(ValueError, match="finite times"):
        parts.run(t=t)
    with pytest.raises(TypeError):  # never a converted copy the run would keep
        parts.run(t=(np.arange(parts.N) * 1e-3).astype(np.float32))


@pytest.mark.parametrize(
    "change",
    [
        pytest.param({"q": np.zeros((50, 4), dtype=np.float32)}, id="q-float32"),
        pytest.param({"idx": np.zeros(50, dtype=np.int32)}, id="idx-int32"),
        pytest.param({"error": np.zeros(100)[::2]}, id="error-strided"),
        pytest.param({"position": np.zeros((50, 3), order="F")}, id="position-fortran"),
        pytest.param({"every": 2**63}, id="every-beyond-a-long"),
    ],
)
def test_record_arrays_are_never_converted(parts, change):
    """A converted copy would be the array the engine writes: the caller's stays empty."""
    with pytest.raises(TypeError):
        parts.record(**change)


@pytest.mark.parametrize(
    "change",
    [
        pytest.param({"q": np.zeros((10, 4))}, id="q-too-few-rows"),
        pytest.param({"qdot": np.zeros((50, 3))}, id="qdot-wrong-nv"),
        pytest.param({"joint_min": np.zeros(3)}, id="joint_min-short"),
        pytest.param({"N": 0}, id="N-zero"),
        pytest.param({"every": 0}, id="every-zero"),
    ],
)
def test_record_shapes_are_checked(parts, change):
    with pytest.raises(ValueError, match="RecordArrays"):
        parts.record(**change)


@pytest.mark.parametrize(
    ("lower", "upper", "index"),
    [([np.nan], [1.0], [0]), ([1.0], [0.0], [0]), ([0.0], [1.0], [99]), ([0.0], [1.0], [-1])],
)
def test_joint_monitor_limits_and_indices_are_checked(parts, lower, upper, index):
    with pytest.raises(ValueError, match="JointMonitorConfig"):
        joints = E.JointMonitorConfig(index=index, lower=np.array(lower),
                                      upper=np.array(upper), names=["j"])  # fmt: skip
        parts.run(joints=joints)


# ---------------------------------------------------------------- laws


def test_law_velocity_checks_its_sizes():
    J, v = np.ones((3, 4)), np.ones(3)
    E.law_velocity("transpose", J, v, v, v, 2, 0.0, 1e-3, 1.0)
    for bad in (np.ones(2), np.ones(5)):
        for position in range(3):
            args = [v, v, v]
            args[position] = bad
            with pytest.raises(ValueError, match="law_velocity"):
                E.law_velocity("transpose", J, *args, 2, 0.0, 1e-3, 1.0)
    for m in (0, 4, -1):
        with pytest.raises(ValueError, match="law_velocity"):
            E.law_velocity("transpose", J, v, v, v, m, 0.0, 1e-3, 1.0)
    with pytest.raises(ValueError, match="law_velocity"):
        E.law_velocity("transpose", J, v, v, v, 2, 0.0, np.nan, 1.0)


# ---------------------------------------------------------------- solve mode


def _solver(robot: clik.Robot, **changes: Any) -> Any:
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    settings: dict[str, Any] = dict(law="pseudoinverse", step=1.0, damping=1e-6, mu=1e-2,
                                    tolerance=1e-4, orientation_tolerance=1e-3,
                                    max_iterations=100)  # fmt: skip
    settings.update(changes)
    return E.Solver(robot.model, task.frame_id, [0, 1], robot.q_reference, **settings)


@pytest.mark.parametrize(
    ("name", "value"),
    [("step", np.inf), ("step", 0.0), ("damping", -1.0), ("mu", np.nan), ("tolerance", 0.0),
     ("orientation_tolerance", np.inf), ("max_iterations", 0)],
)  # fmt: skip
def test_solver_settings_are_checked(parts, name, value):
    with pytest.raises(ValueError, match="Solver"):
        _solver(parts.robot, **{name: value})


def test_solver_refuses_a_q_it_would_not_update(parts):
    solver = _solver(parts.robot)
    target = np.array([0.5, 0.5, 0.0])
    with pytest.raises(TypeError):
        solver.start(target, np.eye(3), parts.q0(), np.zeros(4, dtype=np.float32))
    with pytest.raises(ValueError, match="nq"):
        solver.start(target, np.eye(3), parts.q0(), np.zeros(3))
    q = np.zeros(4)
    assert solver.start(target, np.eye(3), parts.q0(), q) is not None
    assert np.all(q != 0.0)  # written in place


def test_solver_restarts_must_be_finite_configurations(parts):
    solver = _solver(parts.robot)
    q = np.zeros(4)
    solver.start(np.array([5.0, 5.0, 0.0]), np.eye(3), parts.q0(), q)  # out of reach
    with pytest.raises(ValueError, match="finite"):
        solver.run(np.full((2, 4), np.nan), q)
    with pytest.raises(ValueError, match="columns"):
        solver.run(np.zeros((2, 3)), q)


def test_a_model_changed_after_the_solver_was_built_is_refused(parts):
    solver = _solver(parts.robot)
    model = parts.robot.model
    model.addJoint(model.njoints - 1, pin.JointModelRZ(), pin.SE3.Identity(), "extra")
    q = np.zeros(4)
    with pytest.raises(ValueError, match=r"pin\.Model changed"):
        solver.start(np.array([0.5, 0.5, 0.0]), np.eye(3), parts.q0(), q)


# ---------------------------------------------------------------- constraints


def _panda_set(robot: clik.Robot) -> Any:
    from clik.constraints import ConstraintSet, Obstacle

    ball = Obstacle("ball", "sphere", [0.5, 0.0, 0.5], radius=0.05)
    return ConstraintSet(robot, obstacles=[ball])


@pytest.mark.parametrize(
    "kind",
    [
        lambda: E.DexterityConfig(threshold=0.1, gain=np.nan),
        lambda: E.DexterityConfig(threshold=np.inf),
        lambda: E.WorkspaceConfig(frame=1, lower=np.zeros(3), upper=np.ones(3), threshold=0.1,
                                  keys=["k"] * 6, gain=-1.0),
        lambda: E.WorkspaceConfig(frame=1, lower=np.ones(3), upper=np.zeros(3), threshold=0.1,
                                  keys=["k"] * 6),
        lambda: E.ConeConfig(frame=1, axis=np.array([0.0, 0.0, 1.0]),
                             direction=np.array([0.0, 0.0, 1.0]), angle=0.5, threshold=0.1,
                             key="c", gain=np.inf),
        lambda: E.ObstacleConfig(name="o", position=np.array([np.nan, 0.0, 0.0]),
                                 rotation=np.eye(3), velocity=np.zeros(3), threshold=0.1),
        lambda: E.JointRangeConfig(q_index=[0], v_index=[0], lower=np.array([1.0]),
                                   upper=np.array([0.0]), threshold=np.array([0.1]),
                                   joint_names=["j"], names=["a", "b"],
                                   row_threshold=np.array([0.1, 0.1]),
                                   sign=np.array([1.0, -1.0])),
        lambda: E.JointRangeConfig(q_index=[0], v_index=[0], lower=np.array([0.0]),
                                   upper=np.array([1.0]), threshold=np.array([0.1]),
                                   joint_names=["j"], names=["a", "b"],
                                   row_threshold=np.array([0.1, 0.1]),
                                   sign=np.array([1.0, 2.0])),
    ],
    ids=["dexterity-gain", "dexterity-threshold", "workspace-gain", "workspace-corners",
         "cone-gain", "obstacle-position", "joint-range-limits", "joint-range-sign"],
)  # fmt: skip
def test_kind_configs_check_their_numbers(kind):
    with pytest.raises(ValueError):
        kind()


def test_a_geometry_model_changed_after_the_set_is_refused():
    import coal

    cset = _panda_set(clik.Robot.load("panda", lock=PANDA_FINGERS))  # its own: changed here
    config = cset.engine_config()
    gmodel = config.scene.gmodel
    extra = pin.GeometryObject("extra", 0, pin.SE3.Identity(), coal.Sphere(0.1))
    gmodel.addGeometryObject(extra)
    with pytest.raises(ValueError, match="GeometryModel changed"):
        config.row_limit(3, "pseudoinverse")
    with pytest.raises(ValueError, match="GeometryModel changed"):
        _ = config.rho


def test_constraint_set_settings_are_checked(panda):
    config = _panda_set(panda).engine_config()
    args = dict(
        model=panda.model,
        kinds=list(config.kinds),
        scene=config.scene,
        release="projection",
        hysteresis=0.0,
        max_active=None,
        monitor_margin=0.1,
    )
    for name, value in (("hysteresis", np.nan), ("monitor_margin", np.inf), ("max_active", -1)):
        with pytest.raises(ValueError, match="ConstraintSetConfig"):
            E.ConstraintSetConfig(**{**args, name: value})
    with pytest.raises(TypeError):  # beyond a C int: refused by the binding, never cast
        E.ConstraintSetConfig(**{**args, "max_active": 10**12})
