"""Joint-range constraints, eqs. (16)-(19) of docs/method.md.

For ``q_imin <= q_i <= q_imax`` and a threshold ``d_q``, the distance to the
nearer limit is ``d = q_i - q_imin`` (lower) or ``d = q_imax - q_i`` (upper).
The error is ``e_q = d_q - d`` (17), positive inside the threshold band; the
row is ``u_q = +-(0 ... 1 ... 0)`` (19), ``+`` for the lower limit and ``-``
for the upper one, so that ``edot_q = -u_q qdot`` (feed-forward 0 for a
constant threshold).

Only one-DOF joints with a finite range have rows: revolute joints (values in
[rad]) and prismatic joints ([m]). A continuous joint (no limits, stored as
(cos, sin)), a planar or floating base (:mod:`clik.model.base`: unlimited x, y, z,
its rotation a (cos, sin) pair or a quaternion, never a row) and any other joint get
none, while the other joints keep theirs;
each limited joint is mapped to its configuration index (to evaluate ``q_i``)
and its velocity index (the nonzero entry of its rows).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.bounds import in_range, real
from clik.constraints.joint_thresholds import check_angles, warn_capped
from clik.constraints.kind import (
    CHECK_TOLERANCE,
    Candidate,
    ConstraintKind,
    KindRun,
    PoseCheck,
    RunSetup,
    Sample,
    Violation,
)
from clik.constraints.read_only import ReadOnlyList
from clik.constraints.words import AS_IS, CROSSED
from clik.errors import InputError, JointNotFound
from clik.model.joints import CONTINUOUS, PRISMATIC, REVOLUTE, joint_kind

if TYPE_CHECKING:
    from clik.outputs.result import TrackingResult

DEFAULT_THRESHOLD = math.pi / 90.0
"""Default ``d_q`` of revolute joints: 2 deg [rad]."""
RANGE_FRACTION = 0.25
"""Largest threshold, as a fraction of the joint's range: a row cannot fire over the whole range."""


def convert_override(
    robot: object, override: Mapping[str, Mapping[str, float]], unit: str
) -> dict[str, dict[str, float]]:
    """Limits written in a scenario's ``unit`` converted to [rad] for revolute joints.

    Prismatic joints' limits are metres whatever the unit and stay as written;
    unknown joints are kept (:class:`JointLimits` reports them).

    Args:
        robot: The robot (its joint kinds).
        override: Joint name -> ``{"lower": value, "upper": value}`` as written.
        unit: ``"rad"`` or ``"deg"``.

    Returns:
        The same mapping with revolute joints' values in [rad].
    """
    kinds = robot.joint_kinds  # type: ignore[attr-defined]
    scale = math.pi / 180.0 if unit == "deg" else 1.0
    return {
        joint: {
            side: float(value) * (scale if kinds.get(joint) in (REVOLUTE, CONTINUOUS) else 1.0)
            for side, value in limits.items()
        }
        for joint, limits in override.items()
    }


class JointLimits(ConstraintKind):
    """The joint-range rows of one robot, evaluated for all limited joints at once.

    Rows exist for the one-DOF joints (revolute, prismatic) whose limits, after
    ``override``, are finite with ``lower < upper``: a continuous joint, a joint
    with an infinite limit or a zero range gets none.

    Each joint's threshold is capped at a quarter of its range
    (:data:`RANGE_FRACTION`), so that its two threshold bands never cover the
    whole range (a row that fires everywhere, e.g. a 2 deg threshold read as
    0.035 m on the Panda's 0.04 m finger, would hold the joint still).

    Args:
        robot: The robot (its URDF limits are the defaults).
        threshold: ``d_q``, a scalar or one value per configuration entry (nq,):
            [rad] for revolute joints, and [m] for prismatic joints unless
            ``prismatic_threshold`` is given.
        override: Joint name -> ``{"lower": value, "upper": value}`` replacing URDF
            limits (e.g. the case study's ``q3 <= -80 deg``) [rad or m]; only
            revolute and prismatic joints.
        prismatic_threshold: ``d_q`` of the prismatic joints [m]; default: ``threshold``.
        gain: The rows' gain [1/s]; None: the law's default.
        warn_cap: Warn (:class:`~clik.constraints.joint_thresholds.ThresholdCapWarning`)
            when a threshold is capped (:mod:`clik.constraints.joint_thresholds`); False
            for rows clik derives from capped thresholds (solve mode's).

    Raises:
        InputError: A threshold that is not positive, a revolute one above 2 pi
            (degrees read as radians), or one at least as wide as every joint range
            of its kind; a bad override.

    Attributes:
        joint_names: The limited joints (rows exist for these only).
        q_index: Configuration index of each limited joint (for evaluation).
        v_index: Velocity index of each limited joint (the row's nonzero entry).
        kinds: ``"revolute"`` or ``"prismatic"`` per limited joint.
        units: ``"rad"`` or ``"m"`` per limited joint.
        lower, upper: Limits used per limited joint [rad or m].
        threshold: ``d_q`` used per limited joint (after the cap) [rad or m].
        names: Constraint name of each of the ``2 n`` candidate rows
            (``joint:<name>:lower`` for every limited joint, then ``joint:<name>:upper``).
        row_threshold: ``d_q`` of each entry of ``names`` [rad or m] (also ``_thr``).
        n: Number of limited joints.
    """

    def __init__(
        self,
        robot: object,
        threshold: float | np.ndarray = DEFAULT_THRESHOLD,
        override: Mapping[str, Mapping[str, float]] | None = None,
        prismatic_threshold: float | None = None,
        gain: float | None = None,
        warn_cap: bool = True,
    ) -> None:
        self.robot = robot
        self.gain = gain
        self._args = (threshold, override, prismatic_threshold)
        model = robot.model  # type: ignore[attr-defined]
        all_names = list(robot.joint_names)  # type: ignore[attr-defined]
        joints = list(model.joints[1:])
        nq = model.nq
        lower = np.array(model.lowerPositionLimit, dtype=float)
        upper = np.array(model.upperPositionLimit, dtype=float)
        for joint_name, lim in (override or {}).items():
            if joint_name not in all_names:
                raise JointNotFound(joint_name, all_names)
            joint = joints[all_names.index(joint_name)]
            kind = joint_kind(joint)
            if kind not in (REVOLUTE, PRISMATIC):
                raise InputError(
                    f"constraints.joint_limits.override.{joint_name}",
                    "a revolute or prismatic joint (a continuous joint or a base has no range)",
                    kind,
                )
            for side, value in lim.items():
                if side not in ("lower", "upper") or not np.isfinite(value):
                    raise InputError(
                        f"constraints.joint_limits.override.{joint_name}.{side}",
                        "'lower' or 'upper' with a finite value",
                        value,
                    )
                (lower if side == "lower" else upper)[joint.idx_q] = value
        one_dof = [
            (name, joint)
            for name, joint in zip(all_names, joints, strict=True)
            if joint_kind(joint) in (REVOLUTE, PRISMATIC)
        ]
        bad = [name for name, joint in one_dof if lower[joint.idx_q] > upper[joint.idx_q]]
        if bad:
            raise InputError("constraints.joint_limits", "lower <= upper for every joint", bad)
        thr_q = _thresholds(threshold, nq)
        p_thr = None if prismatic_threshold is None else real(prismatic_threshold)
        if p_thr is not None and not in_range(p_thr, 0.0, strict=True):
            field = "constraints.joint_limits.prismatic_threshold"
            raise InputError(field, "a positive length [m]", prismatic_threshold)
        limited = [
            (name, joint)
            for name, joint in one_dof
            if np.isfinite(lower[joint.idx_q])
            and np.isfinite(upper[joint.idx_q])
            and lower[joint.idx_q] < upper[joint.idx_q]
        ]
        self.joint_names = [name for name, _ in limited]
        self.n = n = len(limited)
        self.q_index = np.array([j.idx_q for _, j in limited], dtype=int)
        self.v_index = np.array([j.idx_v for _, j in limited], dtype=int)
        self.kinds = [joint_kind(j) for _, j in limited]
        self.units = ["m" if k == PRISMATIC else "rad" for k in self.kinds]
        self.lower = lower[self.q_index]
        self.upper = upper[self.q_index]
        thr = thr_q[self.q_index]
        if p_thr is not None:
            thr[[k == PRISMATIC for k in self.kinds]] = p_thr
        self._check_usable(thr, model, prismatic=prismatic_threshold is not None)
        self.threshold = np.minimum(thr, RANGE_FRACTION * (self.upper - self.lower))
        if warn_cap:
            warn_capped(self.joint_names, self.kinds, thr, self.threshold, p_thr is not None)
        self.names = [f"joint:{name}:lower" for name in self.joint_names] + [
            f"joint:{name}:upper" for name in self.joint_names
        ]
        self._bound = np.concatenate([self.lower, -self.upper])
        self.row_threshold = np.concatenate([self.threshold, self.threshold])
        self._thr = self.row_threshold
        self.sign = np.concatenate([np.ones(n), -np.ones(n)])
        self._freeze()

    def _freeze(self) -> None:
        """The limits and names, read-only: what both engines' rows are built on."""
        change = "a new JointLimits(robot, ...)"
        for name in ("joint_names", "kinds", "units", "names"):
            setattr(self, name, ReadOnlyList(getattr(self, name), f"JointLimits.{name}", change))
        for name in ("q_index", "v_index", "lower", "upper", "threshold", "_bound", "sign"):
            getattr(self, name).flags.writeable = False
        self.row_threshold.flags.writeable = False  # also _thr

    name = "joint"
    covers_robot_limits = True
    """Its rows for solve mode also keep the other joints inside the robot's limits."""
    depth_measure, limit_words = AS_IS, CROSSED
    """Depths and excursions [rad or m] as they are (a key does not say which)."""

    @classmethod
    def check_name(cls, key: str) -> str:
        """``joint:panda_joint2:lower`` -> ``joint range of panda_joint2``."""
        return f"joint range of {key.partition(':')[2].rpartition(':')[0]}"

    def _check_usable(self, thr: np.ndarray, model: Any, prismatic: bool) -> None:
        """Refuse a threshold at least as wide as the widest (URDF) range of its kind.

        Each threshold is capped at :data:`RANGE_FRACTION` of its joint's range, so a
        somewhat large one still works; one that no joint of its kind could use
        (``1e300``) is a typo, named by its key. Prismatic joints are checked only
        against a ``prismatic_threshold`` given for them.
        """
        urdf = model.upperPositionLimit[self.q_index] - model.lowerPositionLimit[self.q_index]
        kinds = [(REVOLUTE, "threshold", "rad")]
        if prismatic:
            kinds.append((PRISMATIC, "prismatic_threshold", "m"))
        check_angles(thr, self.kinds)  # degrees read as radians
        for kind, key, unit in kinds:
            mine = np.array([k == kind for k in self.kinds], dtype=bool)
            ranges = urdf[mine][np.isfinite(urdf[mine]) & (urdf[mine] > 0.0)]
            if ranges.size and thr[mine].max() >= ranges.max():
                raise InputError(
                    f"constraints.joint_limits.{key}",
                    f"a threshold smaller than a {kind} joint's range (the widest range is "
                    f"{ranges.max():.6g} {unit}, this threshold {thr[mine].max():.6g} {unit})",
                )

    def evaluate(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Errors ``e_q = d_q - d`` (17) of all ``2 n`` rows (lower rows, then upper rows).

        Args:
            q: A configuration (nq,).
            out: Where to write them (2 n,); None: a new array.

        Returns:
            One error per entry of :attr:`names` [rad or m], positive inside the
            threshold band.
        """
        n = self.n
        e = np.empty(2 * n) if out is None else out
        qi = np.take(q, self.q_index)
        # d = q - lower  (lower rows),  d = upper - q  (upper rows)
        np.subtract(qi, self._bound[:n], out=e[:n])
        np.add(qi, self._bound[n:], out=e[n:])
        e[n:] *= -1.0
        np.subtract(self._thr, e, out=e)
        return e

    def excursion(self, q: np.ndarray) -> np.ndarray:
        """How far past its limit each row's joint is, per entry of :attr:`names`.

        Args:
            q: A configuration (nq,).

        Returns:
            A new array (2 n,) [rad or m]: ``lower - q_i`` (lower rows), ``q_i -
            upper`` (upper rows); positive past the limit, <= 0 inside.
        """
        qi = np.take(q, self.q_index)
        return np.concatenate([self.lower - qi, qi - self.upper])

    def slack(self, q: np.ndarray) -> float:
        """How far [rad or m] the nearest joint is from entering its threshold band.

        Negative or zero when some row's error is >= 0 (``-max e_q`` of eq. (17));
        ``inf`` when the robot has no limited joint.
        """
        if self.n == 0:
            return math.inf
        return -float(self.evaluate(q).max())

    def row(self, i: int, out: np.ndarray) -> None:
        """Row ``u_q`` (19) of candidate ``i`` into ``out`` (nv,).

        ``+1`` (lower limit) or ``-1`` (upper limit) at the joint's velocity
        index, zeros elsewhere.
        """
        out[:] = 0.0
        out[self.v_index[i % self.n]] = self.sign[i]

    # -- the kind --------------------------------------------------------------------------

    def start(self, setup: RunSetup) -> JointRangeRun:
        """The rows' state for one run."""
        return JointRangeRun(self)

    def engine_config(self) -> Any:
        """``_engine.JointRangeConfig``."""
        from clik.engine import load

        return load().JointRangeConfig(
            q_index=[int(i) for i in self.q_index],
            v_index=[int(i) for i in self.v_index],
            lower=self.lower,
            upper=self.upper,
            threshold=self.threshold,
            joint_names=list(self.joint_names),
            names=list(self.names),
            row_threshold=self.row_threshold,
            sign=self.sign,
            gain=self.gain,
        )

    def used(self) -> dict[str, Any]:
        """The rows' limits and thresholds, as a run's summary reports them."""
        return {
            "lower": self.lower.tolist(),
            "upper": self.upper.tolist(),
            "threshold": self.threshold.tolist(),
            "q_index": [int(i) for i in self.q_index],
            "joint_names": list(self.joint_names),
        }

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """The limits used, as ``joint_limits_used``."""
        extra["joint_limits_used"] = self.used()

    def joint_ranges(self) -> dict[str, tuple[float, float]]:
        """The constraint's limits per joint (tighter than the robot's where overridden)."""
        return {
            name: (float(lo), float(hi))
            for name, lo, hi in zip(self.joint_names, self.lower, self.upper, strict=True)
        }

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Joints inside a row's threshold band (17) or beyond the constraint's limit."""
        out: list[Violation] = []
        qi = q[self.q_index]
        for k, name in enumerate(self.joint_names):
            unit, thr = self.units[k], float(self.threshold[k])
            for side, d in (("lower", qi[k] - self.lower[k]), ("upper", self.upper[k] - qi[k])):
                if thr - d <= CHECK_TOLERANCE:
                    continue
                limit = self.lower[k] if side == "lower" else self.upper[k]
                where = f"{-d:.4g} {unit} beyond" if d < 0 else f"{d:.4g} {unit} from"
                detail = (
                    f"{name} = {qi[k]:.6g} {unit}, {where} its {side} limit {limit:.6g} {unit} "
                    f"(threshold {thr:.4g} {unit})"
                )
                key = f"joint:{name}:{side}"
                out.append(Violation(self.check_name(key), detail, float(thr - d)))
        return out

    def with_margin(self, margin: float) -> JointLimits:
        """Rows ``margin`` beyond each threshold; other joints' rows at the robot's limits.

        The other limited joints get rows :data:`ROBOT_LIMIT_ROWS` inside the robot's
        own limits (solve mode).
        """
        return robot_limit_rows(self.robot, self, margin)

    def fingerprint(self) -> tuple[Any, ...]:
        """Limits, thresholds and gain."""
        return (
            self.lower.tobytes(), self.upper.tobytes(), self.threshold.tobytes(), self.gain
        )  # fmt: skip


ROBOT_LIMIT_ROWS = 1e-3
"""Solve mode's rows keep joints this far inside the robot's own limits [rad or m]."""


def robot_limit_rows(
    robot: object, limits: JointLimits | None = None, margin: float = 0.0
) -> JointLimits:
    """Rows :data:`ROBOT_LIMIT_ROWS` inside the robot's limits (solve mode's joint rows).

    ``limits``' joints keep their own limits, with thresholds ``margin`` larger.
    """
    thresholds = np.full(robot.nq, ROBOT_LIMIT_ROWS)  # type: ignore[attr-defined]
    override = None
    gain = None
    if limits is not None:
        thresholds[limits.q_index] = limits.threshold + margin
        override = {
            name: {"lower": float(lo), "upper": float(hi)}
            for name, lo, hi in zip(limits.joint_names, limits.lower, limits.upper, strict=True)
        }
        gain = limits.gain
    return JointLimits(robot, thresholds, override, gain=gain, warn_cap=False)


class JointRangeRun(KindRun):
    """Joint-range rows in one run, behind a certificate.

    The smallest margin to a threshold band, lowered by ``max |dq|`` per step, says
    when a band may be entered; the rows are evaluated only then or while one is active.
    """

    def __init__(self, kind: JointLimits) -> None:
        super().__init__(kind)
        self.kind: JointLimits = kind
        self.errors = np.zeros(2 * kind.n)
        self.slack = -1.0  # unknown: evaluate at the first sample

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """Joint-range errors (17): candidates inside their band, or active."""
        jl = self.kind
        if s.dq_abs is not None and s.dq_abs.size:
            self.slack -= float(s.dq_abs.max())
        if self.slack > 0.0 and not s.active_items(self):
            return
        e = jl.evaluate(s.q, self.errors)
        self.slack = -float(e.max()) if e.size else math.inf
        thr = jl.row_threshold
        for i in np.flatnonzero(e > -thr):
            key = jl.names[i]
            if e[i] > 0.0 or key in s.active_keys:
                out.append(Candidate(key, self, int(i), float(e[i]), float(thr[i]), float(thr[i])))

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Row (19): ``+-1`` at the joint."""
        self.kind.row(c.item, out)
        c.feed = 0.0


def _thresholds(threshold: float | np.ndarray, nq: int) -> np.ndarray:
    """``threshold`` as one positive value per configuration entry (nq,) [rad or m]."""
    try:
        thr = np.broadcast_to(np.asarray(threshold, dtype=float), (nq,)).copy()
    except (TypeError, ValueError):
        thr = np.full(nq, math.nan)
    if not np.all(np.isfinite(thr)) or np.any(thr <= 0):
        raise InputError(
            "constraints.joint_limits.threshold",
            f"positive values [rad or m] (one, or {nq} for the configuration)",
            threshold,
        )
    return thr


def limits_by_q(
    used: Mapping[str, Any], robot: object | None, nq: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """A run's ``joint_limits_used`` (per limited joint) spread over the configuration.

    The limited joints are placed at their configuration index, from, in order:
    ``used["q_index"]``; ``used["joint_names"]`` with the robot; one entry per
    configuration value (every joint limited, or a record from before continuous
    joints were left out); the robot's limited joints (:class:`JointLimits` with
    its URDF limits).

    Args:
        used: ``{"lower": ..., "upper": ..., "threshold": ...}`` [rad or m], as in
            ``result.info["summary_extra"]["joint_limits_used"]``.
        robot: The run's robot, or None.
        nq: Size of the run's configuration.

    Returns:
        ``(lower, upper, threshold)``, each (nq,), NaN where a value has no row; None
        when the joints cannot be placed.
    """
    values = [np.asarray(used[k], dtype=float).ravel() for k in ("lower", "upper", "threshold")]
    n = len(values[0])
    index: list[int] | None = None
    if used.get("q_index") is not None:
        index = [int(i) for i in used["q_index"]]
    elif used.get("joint_names") is not None and robot is not None:
        names = robot.q_joint_names  # type: ignore[attr-defined]
        if all(name in names for name in used["joint_names"]):
            index = [names.index(name) for name in used["joint_names"]]
    elif n == nq:
        index = list(range(nq))
    elif robot is not None and robot.nq == nq:  # type: ignore[attr-defined]
        index = JointLimits(robot).q_index.tolist()
    if index is None or len(index) != n or any(not 0 <= i < nq for i in index):
        return None
    if any(len(v) != n for v in values):
        return None
    out = []
    for v in values:
        full = np.full(nq, np.nan)
        full[index] = v
        out.append(full)
    return out[0], out[1], out[2]
