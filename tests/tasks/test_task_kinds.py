"""Every kind of task, through one generic test (clik/tasks/registry.py).

For each registered kind a case (a robot, the kind as a goal beside a frame task that
leads, a trajectory, a start) drives:

- its rows against central differences of its error (``edot = xdot_d - J qdot``, so
  ``J = -de/dq``), to 1e-6 of the rows' size, and its feed-forward against the
  reference's motion;
- both engines on a short run: the same status, events and joint trajectory (1e-9 rad);
- a scenario round trip: its ``[[tasks]]`` table written, read, built and run;
- bad input: each of its table's keys refused by name;
- a controller's target in each form its reader takes, in both engines (the same joints
  as the trajectory's samples), and forms it refuses, named;
- its protocol: every part of :class:`~clik.tasks.kind.BaseTask` implemented, its C++
  type bound, its words in the docs.

Each kind's case is ``case()`` in ``tests/tasks/test_<its module>.py``, beside its own
tests (:mod:`tests.tasks.kind_case`); a kind without one fails
:func:`test_every_kind_has_a_case`: registering a kind is how it gets tested.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.engine import load
from clik.errors import InputError, ScenarioError
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.tasks.kind import BaseTask
from clik.tasks.registry import TASK_KINDS, kind_class
from clik.trajectory import Hold
from tests.tasks.kind_case import Q0, Case, case_of, hand, linear

ROOT = Path(__file__).parents[2]
ENGINES = ("python", "compiled")
STEP = 1e-6
"""Central-difference step [rad]."""
ROW_TOLERANCE = 1e-6
"""Largest ``|J - J_fd| / |J|``."""
PARITY = 1e-9
"""Largest joint difference between the engines [rad]."""
KIND_IDS = [k.__name__ for k in TASK_KINDS]


def rows_at(task: BaseTask, q: np.ndarray, ref: np.ndarray, ff: np.ndarray) -> tuple[Any, ...]:
    model = task.robot.model
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J, e, x = np.zeros((task.m, model.nv)), np.zeros(task.m), np.zeros(task.m)
    task.fill(model, data, q, ref, ff, J, e, x)
    return J, e, x


def fd_rows(task: BaseTask, q: np.ndarray, ref: np.ndarray, ff: np.ndarray) -> np.ndarray:
    """``-de/dq`` by central differences at ``q`` (the error's own derivative)."""
    model = task.robot.model
    out = np.empty((task.m, model.nv))
    for i in range(model.nv):
        dq = np.zeros(model.nv)
        dq[i] = STEP
        ep = rows_at(task, pin.integrate(model, q, dq), ref, ff)[1]
        em = rows_at(task, pin.integrate(model, q, -dq), ref, ff)[1]
        out[:, i] = -(ep - em) / (2 * STEP)
    return out


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_rows_are_the_error_s_derivative(kind: type[BaseTask]) -> None:
    """At configurations where the task is on its reference (every kind), and anywhere
    for a kind whose rows are exact (all but a frame's orientation rows)."""
    case = case_of(kind)
    task, model = case.task, case.task.robot.model
    ref_rows, ff_rows = task.reference_arrays(case.trajectory.sample(np.array([0.1, 0.1 + STEP])))
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = pin.integrate(model, Q0, 0.3 * rng.standard_normal(model.nv))
        refs = [case.held(q)] + ([ref_rows[0]] if case.exact else [])
        for ref in refs:
            J = rows_at(task, q, ref, ff_rows[0])[0]
            assert np.abs(J - fd_rows(task, q, ref, ff_rows[0])).max() <= ROW_TOLERANCE * max(
                np.abs(J).max(), 1e-3
            )
    # the feed-forward: the error's change with the reference alone, at a fixed q
    _, e0, x = rows_at(task, Q0, ref_rows[0], ff_rows[0])
    _, e1, _ = rows_at(task, Q0, ref_rows[1], ff_rows[1])
    assert np.allclose(x, (e1 - e0) / STEP, rtol=1e-4, atol=1e-6)


def goals(case: Case) -> list[clik.Goal]:
    robot = case.task.robot
    lead = hand(robot)
    held = Hold(position=lead.placement(Q0).translation, duration=0.3)
    return [clik.Goal(lead, held, name="hand"), clik.Goal(case.task, case.trajectory, name="kind")]


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_both_engines_run_it_alike(kind: type[BaseTask]) -> None:
    case = case_of(kind)
    runs = {
        e: clik.track(tasks=goals(case), q0=Q0, law="pseudoinverse", gain=100.0, engine=e)
        for e in ENGINES
    }
    a, b = runs["python"], runs["compiled"]
    assert a.status == b.status == "completed", (a.reason, b.reason)
    assert a.events == b.events
    assert np.abs(a.q - b.q).max() <= PARITY
    entry = a.task_errors["kind"]
    first, second = case.task.norms
    assert (entry["error"], entry["unit"]) == (first.what, first.unit)
    assert entry["max"] == pytest.approx(b.task_errors["kind"]["max"], abs=1e-9)
    assert ("max_orientation" in entry) == (second is not None)


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_solve_reaches_its_trajectory_s_final_value(kind: type[BaseTask]) -> None:
    """Solve mode with the kind as a goal beside the hand's: both engines reach its final
    value (its error within the solve's tolerances), from the same start, alike."""
    case = case_of(kind)
    lead = hand(case.task.robot)
    home = lead.placement(Q0).translation
    tasks = [
        clik.Goal(lead, Hold(position=home, duration=0.3), name="hand"),
        clik.Goal(case.task, case.trajectory, name="kind"),
    ]
    solved = {e: clik.solve(tasks=tasks, q0=Q0, engine=e, restarts=0) for e in ENGINES}
    a, b = solved["python"], solved["compiled"]
    assert a.success and b.success, (a.reason, b.reason)
    assert np.abs(a.q - b.q).max() <= 1e-6
    end = case.trajectory.sample(np.array([0.3]))
    ref, ff = case.task.reference_arrays(end)
    _, e, _ = rows_at(case.task, a.q, ref[0], ff[0])
    assert np.abs(e).max() <= 1e-3


def scenario_text(case: Case) -> str:
    return f"""
name = "a {case.task.kind} task"
robot = {{ source = "panda", lock = {{ panda_finger_joint1 = 0.02, panda_finger_joint2 = 0.02 }} }}
initial = {{ q = {Q0.tolist()} }}

[[tasks]]
name = "hand"
kind = "position"
frame = "panda_hand"
[tasks.trajectory]
kind = "hold"
duration = 0.3

[[tasks]]
name = "kind"
{case.table}

[solver]
law = "pseudoinverse"
gain = 100.0
"""


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
@pytest.mark.parametrize("engine", ENGINES)
def test_a_scenario_of_it_runs(kind: type[BaseTask], engine: str, tmp_path: Path) -> None:
    case = case_of(kind)
    path = tmp_path / "kind.toml"
    path.write_text(scenario_text(case))
    run = build(path)
    built = next(g for g in run.goals if g.name == "kind")
    assert type(built.task) is type(case.task)
    run.tracker.engine = engine
    result = run.execute()
    assert result.status == "completed", result.reason
    assert result.task_errors["kind"]["max"] <= 1e-3


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_each_key_of_its_table_is_refused_by_name(kind: type[BaseTask], tmp_path: Path) -> None:
    case = case_of(kind)
    for key, bad in case.bad_keys.items():
        lines = [ln for ln in case.table.splitlines() if not ln.startswith(f"{key} =")]
        head = lines.index("[tasks.trajectory]") if "[tasks.trajectory]" in lines else len(lines)
        value = repr(bad).replace("'", '"').replace("True", "true")
        lines.insert(head, f"{key} = {value}")
        text = scenario_text(
            Case(case.task, None, "\n".join(lines), {}, case.forms, linear, case.held)
        )
        path = tmp_path / f"bad_{key}.toml"
        path.write_text(text)
        with pytest.raises(ScenarioError, match=rf"tasks\[1\]\.{key}"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                build(path)


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_a_controller_takes_each_form_of_its_target(kind: type[BaseTask]) -> None:
    """Each form gives, tick for tick, ``clik.track``'s joints on the same samples."""
    case = case_of(kind)
    t = np.arange(200) * 1e-3
    sample = case.trajectory.sample(t)
    refs, _ = case.task.reference_arrays(sample)
    lead = hand(case.task.robot)
    home = lead.placement(Q0).translation
    offline = clik.track(
        tasks=[clik.Goal(lead, Hold(position=home, duration=0.3), name="hand"),
               clik.Goal(case.task, case.trajectory, name="kind")],
        q0=Q0, law="pseudoinverse", gain=100.0,
    )  # fmt: skip
    for engine in ENGINES:
        for form in range(len(case.forms(refs[0]))):
            ctl = clik.Controller(
                tasks=[clik.Goal(lead, name="hand"), clik.Goal(case.task, name="kind")],
                law="pseudoinverse", gain=100.0, q0=Q0, engine=engine,
            )  # fmt: skip
            for k in range(t.shape[0]):
                targets = {"hand": home, "kind": case.forms(refs[k])[form]}
                tick = ctl.step(targets, {"hand": np.zeros(3), "kind": case.velocity(sample, k)})
                assert tick.verdict == "ok", tick.reason
            q = ctl.result().q
            assert np.abs(q - offline.q[: q.shape[0]]).max() <= PARITY, (engine, form)
        bad = clik.Controller(
            tasks=[clik.Goal(lead, name="hand"), clik.Goal(case.task, name="kind")], q0=Q0,
            engine=engine,
        )  # fmt: skip
        for wrong in (np.zeros((2, 7)), "text", None, np.full(refs[0].shape, np.nan)):
            with pytest.raises(InputError, match=r"targets\['kind'\]"):
                bad.step({"hand": home, "kind": wrong})
        assert bad.k == 0


def test_every_kind_has_a_case() -> None:
    for kind in TASK_KINDS:
        case_of(kind)  # raises for a kind without one


@pytest.mark.parametrize("kind", TASK_KINDS, ids=KIND_IDS)
def test_every_kind_has_every_part_of_the_protocol(kind: type[BaseTask]) -> None:
    abstract = {
        name
        for name, value in inspect.getmembers(BaseTask)
        if getattr(value, "__isabstractmethod__", False)
    }
    assert not getattr(kind, "__abstractmethods__", set()), kind.__abstractmethods__
    assert abstract <= {n for n in dir(kind)}
    case = case_of(kind)
    task = case.task
    goal = task.engine_goal(load())
    assert type(goal).__module__ == "clik._engine"
    module = importlib.import_module(kind.__module__)
    for name in [n for n in vars(type(goal)) if n.isupper()]:  # its numbers, both engines'
        assert getattr(type(goal), name) == getattr(module, name), name
    assert task.tick_target().target_forms()
    assert task.describe() and task.axes and len(task.axes) == task.m
    for name in kind.names:
        assert kind_class(name) is kind
    # its row of the scenario guide's table of kinds (docs/hooks/task_kinds.py makes it)
    assert bool(kind.names) == bool(kind.table_keys) == bool(kind.table_trajectory)
    assert "<!-- clik-task-kinds -->" in (ROOT / "docs" / "guides" / "scenarios.md").read_text()
    rows = guide_table().splitlines()
    for name in kind.names:
        assert sum(f'`"{name}"`' in row and kind.table_keys in row for row in rows) == 1, name
    if kind.example is not None:
        assert scenario_path(kind.example).is_file()
    assert getattr(clik, kind.__name__) is kind and kind.__name__ in clik.__all__  # its API entry
    assert type(task).__name__ in (ROOT / "docs" / "method.md").read_text()


def guide_table() -> str:
    """The scenario guide's table of kinds, as the docs build makes it."""
    spec = importlib.util.spec_from_file_location("task_kinds", ROOT / "docs/hooks/task_kinds.py")
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    return str(hook.table())
