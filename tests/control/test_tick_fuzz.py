"""A fuzz of the controller's tick path, both engines side by side (the tick path
rewrite's case 7; cases 1-6 one by one: tests/control/test_tick_safety.py).

Two controllers built alike, one per engine (the Panda's hand, a pose or a position
task, a ball it may meet, joint ranges), are given the same operations, drawn by
hypothesis:

- ``step`` with a target of any dtype (float64, float32, float16, int64, bool,
  complex128, an object array of numbers, big-endian float64), layout (C, Fortran,
  strided, 0-d, a dimension too many, a wrong shape), alignment (a view at an odd
  address of a bytearray), or None, a list, a ``pin.SE3``, NaN and inf entries; a
  velocity drawn alike (or None); a ball moved (``obstacles={"ball": ...}``);
- ``reset()``, ``result()``;
- re-entrant targets and velocities: an object whose ``__array__`` steps, resets, asks
  for the result of, or drops its own controller;
- a ``step`` kept after its controller was dropped.

Properties (cases 1-5): both engines accept or refuse each operation alike; a refusal
is always ``clik.InputError``, on the same field in both, with nothing run (``k``
unchanged); a complex target or velocity is always refused; accepted ticks agree
(``k``, ``t = k dt``, ``verdict``, ``q`` within 1e-9); no other exception, ever. Under
``make sanitize`` any read or write past (or after) an array is a report.

The values stay moderate (an integer array holds 0 where NaN or inf was drawn, not
numpy's cast of them, -2**63): with obstacle rows active, a feed-forward of 1e6 m/s or
more makes the two engines' laws part by more than 1e-9, which is no matter of the
tick path.
"""

from __future__ import annotations

import functools
import gc
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import clik
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.errors import InputError

ENGINES = ("python", "compiled")
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
NEAR = np.array([0.1, 0.0, 0.0])  # the ball here activates obstacle rows
AWAY = np.array([0.0, 1.0, 0.0])  # and here releases them

FUZZ = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@functools.cache
def panda() -> tuple[clik.Robot, pin.SE3]:
    robot = clik.Robot.load("panda", lock=FINGERS)
    start = clik.Task(robot, "panda_hand", "pose").placement(robot.q_reference)
    return robot, start


def controller(engine: str, kind: str, record_size: int) -> clik.Controller:
    robot, start = panda()
    task = clik.Task(robot, "panda_hand", kind)
    ball = Obstacle("ball", "sphere", start.translation + AWAY, radius=0.03)
    cset = ConstraintSet(
        robot, obstacles=[ball], obstacle_threshold=0.04, joint_limits=JointLimits(robot)
    )
    return clik.Controller(
        task, engine=engine, constraints=cset, q0=robot.q_reference, record_size=record_size
    )


# ----------------------------------------------------------------- what is drawn

DTYPES = ["float64", "float32", "float16", "int64", "bool", "complex128", "object", ">f8"]
LAYOUTS = ["C", "F", "strided", "misaligned", "memoryview"]
TARGET_SHAPES = ["pose", "position", "rotation", "flat16", "0-d", "extra-dim", "short"]
TARGET_VALUES = ["home", "near", "far", "nan", "inf", "not-rotation", "last-row"]
VELOCITY_SHAPES = ["six", "three", "short", "0-d", "extra-dim"]
VELOCITY_VALUES = ["zero", "small", "nan", "inf"]
INNER = ["step", "reset", "result", "drop"]


@dataclass(frozen=True)
class ArraySpec:
    """A numeric array: its values, shape, dtype and layout."""

    values: str
    shape: str
    dtype: str
    layout: str


@dataclass(frozen=True)
class Special:
    """Not an array: None, a list, a pin.SE3, a string, or a re-entrant object."""

    kind: str  # "none", "list", "se3", "text", "reentrant"
    of: ArraySpec | None = None  # the list's (or the re-entrant object's) values
    inner: str = ""  # the re-entrant object's call on its controller


def inputs(values: list[str], shapes: list[str], usual: int, se3: bool) -> st.SearchStrategy[Any]:
    """Targets (or velocities): arrays of the task's usual values (the first ``usual``
    values, the first shape) in any layout and real dtype, the most often; arrays of any
    values, shape, dtype and layout; lists; None, text, a pin.SE3; re-entrant objects."""
    wellformed = st.builds(
        ArraySpec, st.sampled_from(values[:usual]), st.sampled_from(shapes[:1]),
        st.sampled_from([d for d in DTYPES if d not in ("bool", "complex128")]),
        st.sampled_from(LAYOUTS),
    )  # fmt: skip
    anything = st.builds(
        ArraySpec, st.sampled_from(values), st.sampled_from(shapes), st.sampled_from(DTYPES),
        st.sampled_from(LAYOUTS),
    )  # fmt: skip
    return st.one_of(
        wellformed,
        wellformed,
        wellformed,
        anything,
        anything,
        st.builds(Special, st.just("list"), st.one_of(wellformed, anything)),
        st.builds(Special, st.sampled_from(["none", "text"] + (["se3"] if se3 else []))),
        st.builds(Special, st.just("reentrant"), wellformed, st.sampled_from(INNER)),
    )


TARGETS = inputs(TARGET_VALUES, TARGET_SHAPES, 3, se3=True)
VELOCITIES = st.one_of(st.none(), st.none(), inputs(VELOCITY_VALUES, VELOCITY_SHAPES, 2, se3=False))
BALL = st.one_of(
    st.none(),
    st.none(),
    st.sampled_from(["near", "away", "inside", "moving", "nan", "unknown"]),
)
OPERATIONS = st.one_of(
    st.tuples(st.just("step"), TARGETS, VELOCITIES, BALL),
    st.tuples(st.just("step"), TARGETS, VELOCITIES, BALL),
    st.tuples(st.just("step"), TARGETS, VELOCITIES, BALL),
    st.tuples(st.just("step"), TARGETS, VELOCITIES, BALL),
    st.tuples(st.just("reset")),
    st.tuples(st.just("result")),
    st.tuples(st.just("drop"), TARGETS),
)


# ----------------------------------------------------------------- made, per engine


def target_values(spec: ArraySpec) -> np.ndarray:
    """The float64 values of a drawn target, in its drawn shape."""
    _, start = panda()
    pose = start.homogeneous.copy()
    if spec.values == "near":
        turn = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.05, 0.1), np.array([0.02, -0.01, 0.03]))
        pose = (start * turn).homogeneous
    elif spec.values == "far":
        pose[:3, 3] += [2.0, 0.0, 0.5]
    elif spec.values == "nan":
        pose[1, 3] = np.nan
    elif spec.values == "inf":
        pose[0, 0] = np.inf
    elif spec.values == "not-rotation":
        pose[:3, :3] *= 1.1
    elif spec.values == "last-row":
        pose[3, 0] = 0.5
    shaped = {
        "pose": pose,
        "position": pose[:3, 3],
        "rotation": pose[:3, :3],
        "flat16": pose.ravel(),
        "0-d": np.array(pose[0, 3]),
        "extra-dim": pose[None],
        "short": pose[:3, 3][:2],
    }
    return np.array(shaped[spec.shape], dtype=np.float64)


def velocity_values(spec: ArraySpec) -> np.ndarray:
    v = {
        "zero": np.zeros(6),
        "small": np.array([0.01, -0.02, 0.005, 0.0, 0.1, -0.05]),
        "nan": np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0]),
        "inf": np.array([0.0, 0.0, 0.0, -np.inf, 0.0, 0.0]),
    }[spec.values]
    shaped = {"six": v, "three": v[:3], "short": v[:2], "0-d": np.array(v[0]),
              "extra-dim": v[None]}  # fmt: skip
    return np.array(shaped[spec.shape], dtype=np.float64)


def laid_out(values: np.ndarray, dtype: str, layout: str) -> Any:
    """``values`` as ``dtype`` in ``layout`` (where the layout applies to them)."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if dtype in ("int64", "bool"):  # NaN and inf have no integer: 0 (not INT64_MIN)
            values = np.where(np.isfinite(values), values, 0.0)
        if dtype == "object":
            a = np.empty(values.shape, dtype=object)
            for i in np.ndindex(values.shape):
                a[i] = float(values[i])
        else:
            a = values.astype(dtype)
    if layout == "F":
        return np.asfortranarray(a)
    if layout == "strided" and a.ndim:
        big = np.zeros(tuple(2 * s for s in a.shape), dtype=a.dtype)
        view = big[tuple(slice(None, None, 2) for _ in a.shape)]
        view[...] = a
        return view
    if layout == "misaligned" and a.dtype != object:
        buf = bytearray(a.nbytes + 1)
        out = np.frombuffer(buf, dtype=a.dtype, count=a.size, offset=1).reshape(a.shape)
        out[...] = a
        return out
    if layout == "memoryview" and a.dtype != object:
        return memoryview(np.ascontiguousarray(a))
    return np.ascontiguousarray(a) if a.dtype != object else a


class Box:
    """A controller held where a re-entrant object (or a drop) can take it away."""

    def __init__(self, ctl: clik.Controller) -> None:
        self.ctl: clik.Controller | None = ctl


class Reentrant:
    """A target (or velocity) whose ``__array__`` calls its controller first."""

    def __init__(self, box: Box, inner: str, values: np.ndarray) -> None:
        self.box, self.inner, self.values = box, inner, values

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        ctl = self.box.ctl
        if self.inner == "drop":
            self.box.ctl = None
            del ctl
            gc.collect(0)  # young objects (a full collection per drop: seconds in all)
        elif ctl is not None:
            _, start = panda()
            if self.inner == "step":
                ctl.step(start.homogeneous)
            elif self.inner == "reset":
                ctl.reset()
            else:
                ctl.result()
        return np.array(self.values, dtype=dtype)


def made(spec: Any, box: Box, target: bool) -> Any:
    """The object a drawn target (or velocity) is, for the controller in ``box``."""
    if spec is None:
        return None
    values = target_values if target else velocity_values
    if isinstance(spec, ArraySpec):
        return laid_out(values(spec), spec.dtype, spec.layout)
    if spec.kind == "none":
        return None
    if spec.kind == "text":
        return "home"
    if spec.kind == "se3":
        return pin.SE3(panda()[1])
    assert spec.of is not None
    if spec.kind == "list":  # Python numbers of the drawn dtype (complex ones too)
        return np.asarray(laid_out(values(spec.of), spec.of.dtype, "C")).tolist()
    return Reentrant(box, spec.inner, values(spec.of))


def ball(spec: str | None) -> Any:
    if spec is None:
        return None
    home = panda()[1].translation
    return {
        "near": {"ball": home + NEAR},
        "away": {"ball": home + AWAY},
        "inside": {"ball": home},
        "nan": {"ball": [np.nan, 0.0, 0.0]},
        "moving": {"ball": (home + 2 * NEAR, np.array([-0.1, 0.0, 0.0]))},
        "unknown": {"wall": home},
    }[spec]


def is_complex(spec: Any) -> bool:
    """Whether a drawn target (or velocity) is made of complex numbers."""
    if isinstance(spec, Special) and spec.kind == "list":
        spec = spec.of
    return isinstance(spec, ArraySpec) and spec.dtype == "complex128"


# ----------------------------------------------------------------- run, per engine


def outcome(box: Box, op: tuple[Any, ...]) -> tuple[Any, ...]:
    """What ``op`` gave in the controller in ``box``: a tick, a result, a refusal (its
    field), or ("other", ...) for anything else (which fails the test).

    A step is called through its bound method, the controller itself not held here: a
    re-entrant object (or the drop) may take the controller from the box, and the
    method keeps it (case 5), put back in the box after the call.
    """
    ctl = box.ctl
    assert ctl is not None
    before, dt = ctl.k, ctl.dt
    try:
        if op[0] == "reset":
            ctl.reset()
            return ("reset", ctl.k)
        if op[0] == "result":
            result = ctl.result()
            return ("result", result.status, result.q.shape, np.array(result.q))
        s = ctl.step
        del ctl
        if op[0] == "drop":
            box.ctl = None
            gc.collect(0)  # young objects (a full collection per drop: seconds in all)
            args: tuple[Any, ...] = (made(op[1], box, True),)
        else:
            _, target, velocity, moved = op
            args = (made(target, box, True), made(velocity, box, False), ball(moved))
        try:
            tick = s(*args)
        finally:
            if box.ctl is None:  # dropped: the kept step holds it
                kept = getattr(s, "__self__", None)
                box.ctl = kept if isinstance(kept, clik.Controller) else None
    except InputError as error:
        if box.ctl is None:
            return ("other", "refused, and the controller gone", error.field)
        if box.ctl.k != before and op[0] != "reset":
            return ("other", "refused after running", error.field, before, box.ctl.k)
        return ("refused", error.field)
    except Exception as error:  # the property: never
        return ("other", type(error).__name__, str(error)[:300])
    now = box.ctl
    if now is None:
        return ("other", "the kept step did not keep its controller", type(s.__self__))
    if tick.k != before or now.k != before + 1:
        return ("other", "ticked out of turn", before, tick.k, now.k)
    if abs(tick.t - tick.k * dt) > 1e-12:
        return ("other", "t is not k dt", tick.k, tick.t)
    return ("tick", tick.k, tick.verdict, np.array(tick.q, dtype=float))


def same(a: tuple[Any, ...], b: tuple[Any, ...]) -> bool:
    if a[0] != b[0] or len(a) != len(b):
        return False
    if a[0] == "tick":
        return a[1:3] == b[1:3] and a[3].shape == b[3].shape and np.abs(a[3] - b[3]).max() <= 1e-9
    if a[0] == "result":
        return a[1:3] == b[1:3] and (a[3].size == 0 or np.abs(a[3] - b[3]).max() <= 1e-9)
    return a == b


def shown(out: tuple[Any, ...]) -> tuple[Any, ...]:
    return tuple(np.round(x, 6).tolist() if isinstance(x, np.ndarray) else x for x in out)


@FUZZ
@given(
    kind=st.sampled_from(["pose", "position"]),
    record_size=st.sampled_from([1, 3, 10_000]),
    operations=st.lists(OPERATIONS, min_size=1, max_size=8),
)
def test_both_engines_answer_any_tick_alike(kind: str, record_size: int, operations: list) -> None:
    boxes = [Box(controller(engine, kind, record_size)) for engine in ENGINES]
    for i, op in enumerate(operations):
        python, compiled = (outcome(box, op) for box in boxes)
        where = f"operation {i}: {op}\n  python:   {shown(python)}\n  compiled: {shown(compiled)}"
        assert python[0] != "other" and compiled[0] != "other", where
        assert same(python, compiled), where
        if op[0] == "step" and (is_complex(op[1]) or is_complex(op[2])):
            assert python[0] == "refused", where  # a complex target or velocity
        assert boxes[0].ctl is not None and boxes[1].ctl is not None
        assert boxes[0].ctl.k == boxes[1].ctl.k, where
