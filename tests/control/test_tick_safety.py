"""The controller's tick path is memory-safe and refuses what it cannot read (the tick
path rewrite's cases 1-7; case 7, the fuzz, is tests/control/test_tick_fuzz.py).

Pinned here, in both engines (``engine="python"``, the specification, and
``engine="compiled"``, the product), as ``clik.Controller.step`` gives them:

1. ``Controller.step`` is an ordinary method (not an attribute set on the instance).
2. A tick's ``q`` and ``qdot`` are the caller's: float64 arrays owning their memory or
   viewing their tick's own copy, shared with nothing else; writing into them or
   resizing them changes no later tick (the resizing case runs in a subprocess: on an
   engine that hands out rows of its own blocks it is a write after free, which may
   abort the interpreter).
3. A target or velocity of any numeric layout (misaligned, a memoryview, float32, int,
   big-endian, Fortran order, strided) is read as its values: the same joints, bit for
   bit, as an aligned float64 C-contiguous copy gives; a complex one is refused by name.
4. One controller, one thread at a time: two threads stepping one controller are
   served one tick after the other (each tick its own index and time), re-entry from
   the same thread (a target whose ``__array__`` steps, resets or asks for the result)
   is refused with ``InputError``, and a thread reading the ticks handed to it while
   constraints switch on and off reads them whole (under ``make sanitize``, without a
   report).
5. What used to escape as a raw exception is an ``InputError`` (a ``None`` target, a
   model changed after the controller was built) or works (a ``step`` kept after its
   controller was dropped; ``result()`` before any tick with a one-tick record and an
   obstacle).
6. The session's event log is bounded (``event_size``): ``result().events`` holds the
   last ``event_size`` events, ``result().events_dropped`` counts the others, and every
   tick's own ``events`` stay complete.
"""

from __future__ import annotations

import functools
import gc
import os
import queue
import subprocess
import sys
import textwrap
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import clik
import clik.control.controller
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.control.tick import VERDICTS

ENGINES = ("python", "compiled")
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
PLANAR_Q0 = np.radians([180.0, -30.0, -90.0, -30.0])
NEAR = np.array([0.1, 0.0, 0.0])
"""The ball's offset from the Panda's hand that activates obstacle rows (no crossing)."""
AWAY = np.array([0.0, 1.0, 0.0])
"""The ball's offset from the hand that releases them."""


# ----------------------------------------------------------------------------- scenes


@functools.cache
def planar() -> tuple[clik.Robot, clik.Task]:
    """The planar arm and its tip's (x, y) position task (never modified by a test)."""
    robot = clik.Robot.load("planar4r")
    return robot, clik.Task(robot, "tip", "position", axes=["x", "y"])


@functools.cache
def panda() -> tuple[clik.Robot, clik.Task]:
    """The Panda (fingers locked) and its hand's pose task (never modified by a test)."""
    robot = clik.Robot.load("panda", lock=FINGERS)
    return robot, clik.Task(robot, "panda_hand", "pose")


def planar_controller(engine: str, **more: Any) -> clik.Controller:
    task = planar()[1]
    return clik.Controller(task, engine=engine, q0=PLANAR_Q0, **more)


def planar_targets(n: int) -> np.ndarray:
    """``n`` tip positions (3,) along a small arc from the start, then held."""
    _, task = planar()
    home = task.placement(PLANAR_Q0).translation
    k = np.minimum(np.arange(n), n // 2)[:, None]
    return home + 0.05 * np.hstack([np.sin(k * 0.02), np.cos(k * 0.02) - 1.0, 0.0 * k])


def ball_set(robot: clik.Robot) -> ConstraintSet:
    """A ball far from the Panda's hand (a test moves it), joint ranges kept."""
    home = panda()[1].placement(robot.q_reference).translation
    ball = Obstacle("ball", "sphere", home + AWAY, radius=0.03)
    return ConstraintSet(
        robot, obstacles=[ball], obstacle_threshold=0.04, joint_limits=JointLimits(robot)
    )


def panda_controller(engine: str, constraints: bool = False, **more: Any) -> clik.Controller:
    robot, task = panda()
    cset = ball_set(robot) if constraints else None
    return clik.Controller(task, engine=engine, constraints=cset, q0=robot.q_reference, **more)


def panda_poses(n: int) -> list[np.ndarray]:
    """``n`` hand poses (4x4): a small line and turn from the start, then held."""
    robot, task = panda()
    start = task.placement(robot.q_reference)
    out = []
    for k in range(n):
        s = min(k, n // 2) * 1e-3
        turn = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 0.5 * s), np.array([s, -0.5 * s, 0.2 * s]))
        out.append((start * turn).homogeneous)
    return out


def home() -> np.ndarray:
    """The Panda hand's position at the reference configuration."""
    robot, task = panda()
    return task.placement(robot.q_reference).translation.copy()


def ball_scene_step(ctl: clik.Controller, k: int, pose: np.ndarray, every: int = 1) -> Any:
    """Tick ``k`` of the ball scene: the ball near the hand and away, by turns of
    ``every`` ticks; the target in the form ``k`` picks (a 4x4 array, a list, a pin.SE3)."""
    near = (k // every) % 2 == 0
    moved = {"ball": home() + (NEAR if near else AWAY)} if k % every == 0 else None
    form = k % 3
    target: Any = pose if form == 0 else pose.tolist() if form == 1 else pin.SE3(pose)
    return ctl.step(target, obstacles=moved)


# -------------------------------------------------------- 1. an ordinary method


@pytest.mark.parametrize("engine", ENGINES)
def test_step_is_an_ordinary_method(engine: str) -> None:
    """Case 1: ``Controller.step`` is the class's method on every controller, also
    after ``reset`` (today the compiled engine sets ``ctl.step`` on the instance to
    its ticker's ``serve``)."""
    for ctl in (planar_controller(engine), panda_controller(engine, constraints=True)):
        for _ in range(2):
            assert "step" not in vars(ctl)
            assert type(ctl).step is clik.Controller.step
            assert ctl.step.__func__ is clik.Controller.step  # type: ignore[attr-defined]
            assert ctl.step.__self__ is ctl  # type: ignore[attr-defined]
            ctl.reset()


# -------------------------------------------------------- 2. the tick's arrays


def assert_own(a: Any, size: int, tick: Any) -> None:
    """``a`` is a float64 (size,) numpy array of the tick's own: it owns its memory (both
    engines copy a tick's joints), and the tick hands out that same array at each read."""
    assert type(a) is np.ndarray, type(a)
    assert a.dtype == np.float64 and a.shape == (size,)
    assert a.flags.owndata and a.base is None, type(a.base)
    assert any(a is b for b in (tick.q, tick.qdot))


@pytest.mark.parametrize("engine", ENGINES)
def test_a_ticks_arrays_are_its_own(engine: str) -> None:
    """Case 2: every tick's ``q`` and ``qdot`` are its own (owned copies) and share memory
    with no other tick's nor with ``ctl.q``, whichever way the target came
    (a 4x4 array, a list, a pin.SE3, with obstacles moved)."""
    robot = panda()[0]
    ctl = panda_controller(engine, constraints=True)
    ticks = []
    for k, pose in enumerate(panda_poses(60)):
        tick = ball_scene_step(ctl, k, pose, every=5)
        current = ctl.q
        assert np.array_equal(tick.q, current)  # q_{k+1}: where the next tick starts
        for a, size in ((tick.q, robot.nq), (tick.qdot, robot.nv)):
            assert_own(a, size, tick)
            assert not np.shares_memory(a, current)
        assert not np.shares_memory(tick.q, tick.qdot)
        ticks.append(tick)
    assert any(t.events for t in ticks)  # the scene switched rows on and off
    arrays = [a for t in ticks for a in (t.q, t.qdot)]
    for i, a in enumerate(arrays):
        for b in arrays[i + 1 :]:
            assert a is not b and not np.shares_memory(a, b)


@pytest.mark.parametrize("engine", ENGINES)
def test_writing_into_a_tick_changes_no_later_tick(engine: str) -> None:
    """Case 2: a controller whose ticks' arrays are overwritten (NaN, huge values) gives,
    tick for tick, exactly its untouched twin's joints."""
    tampered = panda_controller(engine, constraints=True)
    untouched = panda_controller(engine, constraints=True)
    for k, pose in enumerate(panda_poses(300)):
        a, b = ball_scene_step(tampered, k, pose, 7), ball_scene_step(untouched, k, pose, 7)
        assert (a.k, a.verdict, a.events) == (b.k, b.verdict, b.events)
        assert np.array_equal(a.q, b.q) and np.array_equal(a.qdot, b.qdot), k
        a.q[:] = np.nan if k % 2 else 1e300
        a.qdot[:] = -1e300
    assert np.array_equal(tampered.q, untouched.q)
    assert np.array_equal(tampered.result().q, untouched.result().q)


def run_child(code: str, timeout: float = 600.0) -> subprocess.CompletedProcess[str]:
    """``code`` run by ``sys.executable`` in a new interpreter importing the very clik
    this process imported (its folder first on ``sys.path`` and the editable install's
    import hook dropped when the child would otherwise import another one)."""
    root = os.path.dirname(os.path.dirname(os.path.realpath(clik.__file__)))
    preamble = f"""
        import importlib.util, os, sys
        WANT = {os.path.realpath(clik.__file__)!r}
        spec = importlib.util.find_spec("clik")
        if spec is None or os.path.realpath(spec.origin or "") != WANT:
            sys.meta_path[:] = [
                m for m in sys.meta_path
                if "editable" not in type(m).__module__.lower()
                and "skbc" not in type(m).__module__.lower()
            ]
            sys.path.insert(0, {root!r})
        import clik
        assert os.path.realpath(clik.__file__) == WANT, (clik.__file__, WANT)
    """
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(preamble) + textwrap.dedent(code)],
        capture_output=True, text=True, timeout=timeout, check=False,
    )  # fmt: skip


RESIZED = """
    import numpy as np
    engine = {engine!r}
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    home = task.placement(q0).translation
    tampered = clik.Controller(task, engine=engine, q0=q0)
    untouched = clik.Controller(task, engine=engine, q0=q0)
    differ = []
    for k in range(1000):
        target = home + [0.1 * np.sin(k * 1e-2), 0.05 * np.cos(k * 1e-2) - 0.05, 0.0]
        given = target.tolist() if k % 5 == 4 else target  # a list: packed in Python
        a, b = tampered.step(given), untouched.step(given)
        q = np.array(a.q, dtype=float, copy=True)
        if a.k != b.k or q.shape != b.q.shape or not np.array_equal(q, b.q):
            differ.append(k)
        for arr in (a.q, a.qdot):
            # the memory the tick hands out: the array itself, or the array it views
            owner = arr if arr.base is None else arr.base
            if isinstance(owner, np.ndarray):
                owner.resize(max(1000, 8 * owner.size), refcheck=False)
                owner.fill(1e300)
            else:  # a view of its tick's own copy: numpy refuses to resize it
                try:
                    arr.resize(1000, refcheck=False)
                    differ.append(f"resized {{k}}")
                except ValueError:
                    arr.fill(1e300)
    if not np.array_equal(tampered.q, untouched.q):
        differ.append("final")
    print("ticks", k + 1, "differ", len(differ), differ[:5])
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_resizing_a_ticks_arrays_changes_no_later_tick(engine: str) -> None:
    """Case 2, in a subprocess: each tick's ``q`` and ``qdot`` resized to 1,000 entries
    (``resize(..., refcheck=False)``: numpy reallocates their memory) and filled with
    1e300; the controller still gives its untouched twin's joints, tick for tick.
    Today's compiled engine hands out rows of a block it keeps writing into: resizing
    the block frees it under the engine (``realloc(): invalid next size``, an abort)."""
    child = run_child(RESIZED.format(engine=engine))
    tail = (child.stdout + child.stderr)[-2000:]
    assert child.returncode == 0, f"exit {child.returncode}: {tail}"
    assert child.stdout.strip().splitlines()[-1] == "ticks 1000 differ 0 []", tail


# -------------------------------------------------------- 3. targets of any layout


def misaligned(a: np.ndarray) -> np.ndarray:
    """``a``'s float64 values, C-contiguous, at an odd address (a bytearray's byte 1)."""
    values = np.asarray(a, dtype=np.float64)
    buf = bytearray(values.size * 8 + 1)
    out = np.frombuffer(buf, dtype=np.float64, count=values.size, offset=1).reshape(a.shape)
    out[...] = values
    assert not out.flags.aligned and out.flags.c_contiguous
    return out


def strided(a: np.ndarray) -> np.ndarray:
    """``a``'s values as a view taking every other element of a larger array."""
    big = np.zeros(tuple(2 * s for s in a.shape))
    view = big[tuple(slice(None, None, 2) for _ in a.shape)]
    view[...] = a
    assert not view.flags.c_contiguous
    return view


LAYOUTS: dict[str, Callable[[np.ndarray], Any]] = {
    "misaligned": misaligned,
    "memoryview": lambda a: memoryview(np.ascontiguousarray(a, dtype=np.float64)),
    "float32": lambda a: a.astype(np.float32),
    "int": lambda a: np.rint(a).astype(np.int64),
    "big-endian": lambda a: a.astype(">f8"),
    "fortran": lambda a: np.asfortranarray(a, dtype=np.float64),
    "strided": strided,
}


def aligned(x: Any) -> np.ndarray:
    """``x``'s values as a new aligned float64 C-contiguous array."""
    out = np.array(np.asarray(x), dtype=np.float64, order="C")
    assert out.flags.aligned and out.flags.c_contiguous and out.flags.owndata
    return out


def integer_pose(pose: np.ndarray) -> np.ndarray:
    """A pose with integer entries (the identity rotation, the translation rounded)."""
    out = np.eye(4)
    out[:3, 3] = np.rint(pose[:3, 3] * 2.0)
    return out


@pytest.mark.parametrize("layout", list(LAYOUTS))
@pytest.mark.parametrize("given", ["target", "velocity"])
@pytest.mark.parametrize("scene", ["planar-position", "panda-pose"])
@pytest.mark.parametrize("engine", ENGINES)
def test_targets_of_any_layout_are_read_as_values(
    engine: str, scene: str, given: str, layout: str
) -> None:
    """Case 3: a target (or its velocity) in ``layout`` gives, tick for tick, bit for bit
    the joints and verdicts an aligned float64 C-contiguous copy of its values gives."""
    make = LAYOUTS[layout]
    if scene == "planar-position":
        ctl, twin = planar_controller(engine), planar_controller(engine)
        targets = list(planar_targets(40))
        width = 3
    else:
        ctl, twin = panda_controller(engine), panda_controller(engine)
        targets = panda_poses(40)
        if layout == "int" and given == "target":
            targets = [integer_pose(p) for p in targets]
        width = 6
    for k, target in enumerate(targets):
        velocity = np.linspace(-0.02, 0.03, width) * (k % 4)
        if given == "target":
            odd_t, odd_v = make(target), velocity
            plain_t, plain_v = aligned(odd_t), velocity
        else:
            odd_v = make(np.sign(velocity) if layout == "int" else velocity)
            odd_t, plain_t, plain_v = target, target, aligned(odd_v)
        a, b = ctl.step(odd_t, odd_v), twin.step(plain_t, plain_v)
        assert (a.k, a.verdict) == (b.k, b.verdict) and a.k == k
        assert np.array_equal(a.q, b.q), (k, np.abs(a.q - b.q).max())
    assert ctl.k == twin.k == len(targets)


@pytest.mark.parametrize("form", ["zero imaginary", "imaginary"])
@pytest.mark.parametrize("scene", ["planar-position", "panda-pose"])
@pytest.mark.parametrize("engine", ENGINES)
def test_complex_targets_and_velocities_are_refused(engine: str, scene: str, form: str) -> None:
    """Case 3: a complex target or velocity, even with zero imaginary parts, is refused
    by name (``targets['task']``, ``velocities['task']``), nothing run. Today both
    engines drop the imaginary parts (a ComplexWarning) and run the tick."""
    if scene == "planar-position":
        ctl = planar_controller(engine)
        target, velocity = planar_targets(1)[0], np.zeros(3)
    else:
        ctl = panda_controller(engine)
        target, velocity = panda_poses(1)[0], np.zeros(6)
    ctl.step(target)
    imaginary = 0.0 if form == "zero imaginary" else 1e-3
    for bad_target, bad_velocity, field in (
        (target + imaginary * 1j, None, "targets['task']"),
        (target + imaginary * 1j, velocity, "targets['task']"),
        (target, velocity + imaginary * 1j, "velocities['task']"),
        (target, (velocity + imaginary * 1j).tolist(), "velocities['task']"),
        ((target + imaginary * 1j).tolist(), None, "targets['task']"),
    ):
        with pytest.raises(clik.InputError) as refused:
            ctl.step(bad_target, bad_velocity)
        assert refused.value.field == field
        assert ctl.k == 1  # nothing run
    assert ctl.step(target, velocity).k == 1  # and the controller goes on


# -------------------------------------------------------- 4. one thread at a time


@pytest.mark.parametrize("engine", ENGINES)
def test_two_threads_stepping_one_controller_take_turns(engine: str) -> None:
    """Case 4a: two threads stepping one controller (targets as arrays, lists and
    pin.SE3, obstacles moved), a third asking for its result now and then: no exception,
    the ticks' indices exactly 0 .. total - 1 (none twice), each at its own time.
    Today ticks carry other ticks' indices (and some runs raise)."""
    ctl = panda_controller(engine, constraints=True)
    n = 3000 if engine == "compiled" else 300
    poses = panda_poses(2 * n)
    ticks: list[list[Any]] = [[], []]
    errors: list[str] = []
    done = threading.Event()
    results = []
    start = threading.Barrier(3)

    def stepping(i: int) -> None:
        try:
            start.wait()
            for j in range(n):
                ticks[i].append(ball_scene_step(ctl, j, poses[2 * j + i], every=5))
        except Exception as error:
            errors.append(f"step: {error!r}")

    def resulting() -> None:
        try:
            start.wait()
            while not done.wait(0.002):
                results.append(ctl.result())
        except Exception as error:
            errors.append(f"result: {error!r}")

    threads = [threading.Thread(target=stepping, args=(i,)) for i in range(2)]
    reader = threading.Thread(target=resulting)
    for t in [*threads, reader]:
        t.start()
    for t in threads:
        t.join()
    done.set()
    reader.join()
    assert errors == []
    total = 2 * n
    ks = sorted(t.k for tt in ticks for t in tt)
    assert ks == list(range(total)), f"{total - len(set(ks))} indices repeated or missing"
    for t in (t for tt in ticks for t in tt):
        assert t.t == pytest.approx(t.k * ctl.dt, abs=1e-12)
    assert ctl.k == total
    assert all(isinstance(r, clik.TrackingResult) for r in results)
    assert isinstance(ctl.result(), clik.TrackingResult)


class Reentrant:
    """A target (or velocity) whose ``__array__`` calls ``call`` (the same controller's
    step, reset or result) before giving ``values`` (what ``call`` raises, raised)."""

    def __init__(self, call: Callable[[], Any], values: np.ndarray) -> None:
        self.call, self.values = call, values

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        self.call()
        return np.array(self.values, dtype=dtype)


@pytest.mark.parametrize("inner", ["step", "reset", "result"])
@pytest.mark.parametrize("given", ["target", "velocity"])
@pytest.mark.parametrize("engine", ENGINES)
def test_reentry_from_the_same_thread_is_refused(engine: str, given: str, inner: str) -> None:
    """Case 4b: a target (or velocity) whose ``__array__`` steps, resets or asks for the
    result of the very controller stepping it: the outer step raises ``InputError``
    ("one thread at a time"), nothing ran (``k`` unchanged), and the controller goes on
    as its twin. Today the inner call runs in the middle of the outer tick."""
    ctl, twin = planar_controller(engine), planar_controller(engine)
    targets = planar_targets(6)
    for target in targets[:3]:
        ctl.step(target)
        twin.step(target)
    calls = {
        "step": lambda: ctl.step(targets[5]),
        "reset": lambda: ctl.reset(),
        "result": lambda: ctl.result(),
    }
    if given == "target":
        obj = Reentrant(calls[inner], targets[3])
        args: tuple[Any, ...] = (obj,)
    else:
        obj = Reentrant(calls[inner], np.zeros(3))
        args = (targets[3], obj)
    with pytest.raises(clik.InputError, match="one thread at a time"):
        ctl.step(*args)
    assert ctl.k == 3  # neither the inner call nor the outer tick ran
    for target in targets[3:]:
        a, b = ctl.step(target), twin.step(target)
        assert (a.k, a.verdict) == (b.k, b.verdict)
        assert np.array_equal(a.q, b.q)
    assert np.array_equal(ctl.result().q, twin.result().q)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_reader_thread_reads_the_ticks_while_rows_switch(engine: str) -> None:
    """Case 4c: a thread reading every attribute of the ticks handed to it (and ``ctl.k``,
    ``ctl.q``) while the stepping thread moves a ball near the hand and away: no
    exception, each tick's events at its own time (to 1e-12 s: an event's time and its
    tick's are computed apart and may differ in the last bit). Today reading
    ``tick.events`` there reads freed memory: a report under AddressSanitizer (``make
    sanitize``); in a normal build the invariants hold."""
    robot = panda()[0]
    ctl = panda_controller(engine, constraints=True)
    n = 2000 if engine == "compiled" else 300
    handed: queue.Queue[Any] = queue.Queue(maxsize=64)
    errors: list[str] = []
    read = {"ticks": 0, "events": 0, "active": 0}

    def stepping() -> None:
        try:
            for k, pose in enumerate(panda_poses(n)):
                handed.put(ball_scene_step(ctl, k, pose, every=3))
        except Exception as error:
            errors.append(f"step: {error!r}")
        finally:
            handed.put(None)

    def reading() -> None:
        try:
            last_k = -1
            while (tick := handed.get()) is not None:
                values = (tick.q, tick.qdot, tick.events, tick.active, tick.errors,
                          tick.verdict, tick.reason, tick.k, tick.t)  # fmt: skip
                q, qdot, events, active, errors_, verdict, reason, k, t = values
                assert q.shape == (robot.nq,) and qdot.shape == (robot.nv,)
                assert np.all(np.isfinite(q)) and np.all(np.isfinite(qdot))
                assert all(e["t"] == pytest.approx(t, abs=1e-12) for e in events), (t, events)
                assert all(isinstance(name, str) for name in active)
                assert set(errors_) == {"task"} and verdict in VERDICTS
                assert isinstance(reason, str) and t == pytest.approx(k * ctl.dt, abs=1e-12)
                now, joints = ctl.k, ctl.q
                assert now >= max(last_k, k + 1) and joints.shape == (robot.nq,)
                last_k = now
                read["ticks"] += 1
                read["events"] += len(events)
                read["active"] += len(active)
        except Exception as error:
            errors.append(f"read: {error!r}")
            while handed.get() is not None:  # let the stepping thread finish
                pass

    threads = [threading.Thread(target=stepping), threading.Thread(target=reading)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert read["ticks"] == n and ctl.k == n
    assert read["events"] > 0 and read["active"] > 0  # rows did switch on and off


# -------------------------------------------------------- 5. InputError, not raw errors


@pytest.mark.parametrize("engine", ENGINES)
def test_a_none_target_is_refused_by_name(engine: str) -> None:
    """Case 5: ``step(None)`` is ``InputError`` on ``targets['task']``, nothing run (today
    the compiled engine raises nanobind's TypeError)."""
    for ctl in (planar_controller(engine), panda_controller(engine, constraints=True)):
        for args in ((None,), (None, None), (None, None, None)):
            with pytest.raises(clik.InputError) as refused:
                ctl.step(*args)
            assert refused.value.field == "targets['task']"
            assert ctl.k == 0


@pytest.mark.parametrize("engine", ENGINES)
def test_a_step_kept_after_its_controller_is_dropped_works(engine: str) -> None:
    """Case 5: ``s = ctl.step; del ctl`` then ``s(target)`` runs the next tick of the
    session (its verdict's reason given). Today the compiled engine's kept ``serve``
    runs the tick, then raises ``ValueError: ... its controller is gone`` (its
    controller held weakly)."""
    ctl = planar_controller(engine)
    far = planar_targets(1)[0] + [2.0, 0.0, 0.0]  # out of reach: verdicts other than ok
    for _ in range(700):  # off_track, then deadlock
        last = ctl.step(far)
    assert last.verdict in ("off_track", "deadlock")
    s = ctl.step
    del ctl
    gc.collect()
    tick = s(far)  # the fast path's form
    assert tick.k == last.k + 1 and tick.verdict != "ok" and tick.reason
    tick = s(far.tolist())  # packed in Python
    assert tick.k == last.k + 2 and np.all(np.isfinite(tick.q))


@pytest.mark.parametrize("engine", ENGINES)
def test_a_model_changed_after_the_controller_was_built_is_refused(engine: str) -> None:
    """Case 5: a frame added to the model after the controller was built: the next step
    is ``InputError`` on ``robot.model``, nothing run (today: a ValueError in the
    compiled engine; the Python engine runs on)."""
    robot = clik.Robot.load("planar4r")  # its own model: changed here
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    ctl = clik.Controller(task, engine=engine, q0=PLANAR_Q0)
    target = task.placement(PLANAR_Q0).translation
    ctl.step(target)
    robot.model.addFrame(pin.Frame("extra", 0, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    for given in (target, target.tolist(), target.astype(np.float32)):
        with pytest.raises(clik.InputError) as refused:
            ctl.step(given)
        assert refused.value.field == "robot.model"
        assert ctl.k == 1


@pytest.mark.parametrize("engine", ENGINES)
def test_the_result_before_any_tick_of_a_one_tick_record_with_an_obstacle(engine: str) -> None:
    """Case 5: ``result()`` before any tick, with ``record_size=1`` and an obstacle, is a
    TrackingResult (today numpy's ``ValueError: zero-size array to reduction``)."""
    ctl = panda_controller(engine, constraints=True, record_size=1)
    result = ctl.result()
    assert isinstance(result, clik.TrackingResult)
    ctl.step(panda_poses(1)[0])
    assert isinstance(ctl.result(), clik.TrackingResult)


# -------------------------------------------------------- 6. a bounded event log


def event_session(engine: str, n: int, **more: Any) -> tuple[clik.Controller, list[dict]]:
    """``n`` ticks of the Panda held at its pose, the ball near the hand and away on
    alternate ticks (rows activated and released); the ticks' events, in order."""
    ctl = panda_controller(engine, constraints=True, **more)
    pose = panda_poses(1)[0]
    events: list[dict] = []
    for k in range(n):
        events += ctl.step(pose, obstacles={"ball": home() + (NEAR if k % 2 == 0 else AWAY)}).events
    return ctl, events


def test_the_default_event_size() -> None:
    """Case 6: the event log keeps 10,000 events by default."""
    assert clik.control.controller.EVENT_SIZE == 10_000


@pytest.mark.parametrize("event_size", [1, 100])
@pytest.mark.parametrize("engine", ENGINES)
def test_the_event_log_keeps_the_last_events(engine: str, event_size: int) -> None:
    """Case 6: after 1,200 ticks of rows switching on and off, ``result().events`` are the
    session's last ``event_size`` events, ``events_dropped`` the others; every tick's own
    events complete. (Today ``event_size`` is an unknown setting: ``InputError:
    Controller``.)"""
    ctl, events = event_session(engine, 20, event_size=event_size)
    early = ctl.result()
    kept = min(len(events), event_size)
    assert early.events == events[len(events) - kept :]
    assert early.events_dropped == len(events) - kept
    for k in range(20, 1200):
        events += ctl.step(
            panda_poses(1)[0], obstacles={"ball": home() + (NEAR if k % 2 == 0 else AWAY)}
        ).events
    assert len(events) >= 1000  # every tick switched rows
    assert {e["action"] for e in events} == {"activate", "release"}
    result = ctl.result()
    assert len(result.events) == event_size
    assert result.events == events[-event_size:]
    assert type(result.events_dropped) is int
    assert result.events_dropped == len(events) - event_size


@pytest.mark.parametrize("engine", ENGINES)
def test_a_session_within_the_event_size_drops_nothing(engine: str) -> None:
    """Case 6: with the default size, a session's events are all kept (none dropped)."""
    ctl, events = event_session(engine, 300)
    assert len(events) >= 300
    result = ctl.result()
    assert result.events == events and result.events_dropped == 0


def test_both_engines_keep_the_same_events() -> None:
    """Case 6: the two engines' ticks give the same events, and their logs keep the same
    last ones and drop as many."""
    logs = {e: event_session(e, 1100, event_size=100) for e in ENGINES}
    (py_ctl, py_events), (c_ctl, c_events) = logs["python"], logs["compiled"]
    assert py_events == c_events and len(py_events) > 100
    a, b = py_ctl.result(), c_ctl.result()
    assert a.events == b.events == py_events[-100:]
    assert a.events_dropped == b.events_dropped == len(py_events) - 100


@pytest.mark.parametrize("bad", [0, -1, 2.5, "100"])
@pytest.mark.parametrize("engine", ENGINES)
def test_a_bad_event_size_is_refused_by_name(engine: str, bad: Any) -> None:
    """Case 6: ``event_size`` 0, negative or not an integer: ``InputError`` on it (today:
    ``InputError`` on ``Controller``, an unknown setting)."""
    with pytest.raises(clik.InputError) as refused:
        planar_controller(engine, event_size=bad)
    assert refused.value.field == "event_size"
