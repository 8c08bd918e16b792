"""A tick's targets: each task's target and velocity read into one sample's references.

At each tick a controller is given each task's target (and, optionally, its velocity for
the feed-forward of (10)), by task name (a mapping) or, with one task, the target itself.
They become the one-sample references an offline run samples from its trajectories, so a
controller given a trajectory's samples runs exactly what ``clik.track`` runs.

Both engines read a tick the same way, in two phases:

1. *staging*: each target and velocity as a float64 array (a NumPy float64 array as it
   is; anything else converted once by :func:`as_floats`: a ``pin.SE3`` to its 4x4
   matrix, any other numbers to float64), its shape checked against the forms its task
   takes (:mod:`clik.tasks.targets`);
2. *reading*: each task's reader checks the numbers and writes its reference and
   feed-forward; the tick is at rest (the stall check's) when every feed-forward is zero
   and either every velocity was given or every target is where it was at the previous
   tick.

The compiled engine stages in ``src/engine/loop/bind_ticker.cpp`` (calling
:func:`as_floats` and :func:`as_mapping` for anything but a NumPy float64 array or a dict)
and reads in ``loop/tick_targets.hpp``; :class:`TickTargets` is their specification.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from clik.errors import ClikError, InputError
from clik.tasks.targets import FrameTarget, Refusal, TickTarget


def as_floats(value: Any, field: str, expected: str) -> np.ndarray:
    """A target or velocity as a float64 C-contiguous array: the one conversion of a tick.

    A ``pin.SE3`` gives its 4x4 matrix; any other real numbers (arrays of any dtype, layout
    or alignment, sequences, buffers) their float64 values.

    Raises:
        InputError: None, complex numbers, or anything that is not numbers (``field``,
            ``expected``).
    """
    if isinstance(value, pin.SE3):
        return np.ascontiguousarray(value.homogeneous, dtype=np.float64)
    if value is None:
        raise InputError(field, expected, "None")
    try:
        array = np.asarray(value)
    except ClikError:  # from the caller's own code (its __array__): as it is
        raise
    except (TypeError, ValueError):
        raise InputError(field, expected, type(value).__name__) from None
    if array.dtype.kind == "c":
        raise InputError(field, f"real numbers: {expected}", f"complex numbers ({array.dtype})")
    if array.dtype.kind not in "fiub" and array.dtype != object:
        raise InputError(field, expected, f"{array.dtype} values")
    try:
        out = np.ascontiguousarray(array, dtype=np.float64)
    except ClikError:
        raise
    except (TypeError, ValueError):
        raise InputError(field, expected, type(value).__name__) from None
    return np.require(out, requirements=["C", "A"])


def as_mapping(value: Any, field: str, names: tuple[str, ...]) -> dict[Any, Any] | None:
    """Targets (or velocities) by task name as a dict; None for a value that is no mapping.

    Args:
        value: What the caller gave.
        field: ``"targets"`` or ``"velocities"`` (the message's).
        names: The tasks' names.
    """
    del field, names  # the keys are checked where the dict is read (TickTargets.stage)
    return dict(value) if isinstance(value, Mapping) else None


def _field(field: str, name: str) -> str:
    return f"{field}[{name!r}]"


class TickTargets:
    """Every task's target of one tick: the primary task's first, then the others', in row order.

    Args:
        readers: Each task's reader (its ``tick_target()``), in the run's task order.
        names: The tasks' names.
    """

    def __init__(self, readers: list[TickTarget], names: list[str]) -> None:
        self.readers, self.names = readers, names
        self._previous: tuple[np.ndarray, ...] | None = None  # the last tick's references

    def restart(self) -> None:
        """A new session: the next tick counts as moved (at rest needs its velocities)."""
        self._previous = None

    # -- staging ----------------------------------------------------------------------

    def _by_name(self, value: Any, field: str, every: bool) -> dict[Any, Any] | None:
        """A mapping of ``value`` (None: the one task's value itself), its keys checked."""
        n = len(self.names)
        if n == 1 and not isinstance(value, dict) and _plain(value):
            return None
        mapping = value if isinstance(value, dict) else as_mapping(value, field, tuple(self.names))
        if mapping is None:
            if n == 1:
                return None
            what = "target" if every else "velocity"
            raise InputError(
                field, f"a mapping of task name to {what} ({', '.join(self.names)})", value
            )
        found = sum(name in mapping for name in self.names)
        if len(mapping) > found:
            unknown = next(key for key in mapping if key not in self.names)
            raise InputError(field, f"task names among {self.names!r}", unknown)
        if every and found < n:
            raise InputError(field, f"a target for every task ({', '.join(self.names)})")
        return mapping

    def _stage(self, i: int, value: Any, velocity: bool) -> np.ndarray:
        """Task ``i``'s target (velocity) as a float64 array of a shape the task takes."""
        reader, name = self.readers[i], self.names[i]
        field = _field("velocities" if velocity else "targets", name)
        words = reader.velocity_forms() if velocity else reader.target_forms()
        array = value if _plain(value) else as_floats(value, field, words)
        size = reader.velocity_size(array.shape) if velocity else reader.target_size(array.shape)
        if size < 0:
            raise InputError(field, words, f"shape {array.shape}")
        return array.copy()

    def stage(self, targets: Any, velocities: Any) -> list[tuple[np.ndarray, np.ndarray | None]]:
        """Each task's target and velocity (None: not given), staged.

        Raises:
            InputError: A mapping's key that names no task, a task without a target, a
                target or velocity that is not numbers or not of a form its task takes.
        """
        tmap = self._by_name(targets, "targets", True)
        moving = velocities is not None
        vmap = self._by_name(velocities, "velocities", False) if moving else None
        staged = []
        for i, name in enumerate(self.names):
            target = self._stage(i, targets if tmap is None else tmap[name], False)
            velocity = None
            if moving:
                given = velocities if vmap is None else vmap.get(name)
                velocity = None if given is None else self._stage(i, given, True)
            staged.append((target, velocity))
        return staged

    # -- reading ------------------------------------------------------------------------

    def read(self, staged: list[tuple[np.ndarray, np.ndarray | None]]) -> tuple[Any, ...]:
        """This tick's references ``(p_d, R_d, ff, at_rest, g_ref, g_ff)`` (``_Run.sample``'s).

        ``p_d`` and ``R_d`` are None when the primary task has no such rows; the goals'
        None without goals.

        Raises:
            InputError: A number a task's reader refuses (named by the task's field).
        """
        refs, ffs = [], []
        for i, (target, velocity) in enumerate(staged):
            try:
                ref, ff = self.readers[i].read(target, velocity)
            except Refusal as why:
                shown: Any = velocity if why.velocity else target
                got = shown[3].tolist() if why.show == "last_row" else shown.tolist()
                field = _field("velocities" if why.velocity else "targets", self.names[i])
                raise InputError(field, why.expected, got) from None
            refs.append(ref)
            ffs.append(ff)
        primary: Any = self.readers[0]
        assert isinstance(primary, FrameTarget)
        p_d = refs[0][:3] if primary.pos else None
        R_d = refs[0][3:].reshape(3, 3) if primary.rot else None
        g_ref = np.concatenate(refs[1:]) if len(refs) > 1 else None
        g_ff = np.concatenate(ffs[1:]) if len(ffs) > 1 else None
        zero = all(not np.any(ff) for ff in ffs)
        now = (refs[0] if primary.pos or primary.rot else None, g_ref)
        at_rest = zero and (all(v is not None for _, v in staged) or self._unmoved(now, primary))
        self._previous = now  # type: ignore[assignment]
        return p_d, R_d, ffs[0], at_rest, g_ref, g_ff

    def _unmoved(self, now: tuple[Any, Any], primary: FrameTarget) -> bool:
        """Every target is where it was at the previous tick (Controller's "at rest")."""
        before = self._previous
        if before is None:
            return False
        p0, g0 = before
        p1, g1 = now
        same_primary = (not primary.pos or np.array_equal(p1[:3], p0[:3])) and (
            not primary.rot or np.array_equal(p1[3:], p0[3:])
        )
        return same_primary and (g1 is None or np.array_equal(g1, g0))


def _plain(value: Any) -> bool:
    """A NumPy float64 array read as it is: aligned, native byte order, C-contiguous."""
    return (
        isinstance(value, np.ndarray)
        and value.dtype == np.float64
        and value.dtype.isnative
        and value.flags.c_contiguous
        and value.flags.aligned
    )
