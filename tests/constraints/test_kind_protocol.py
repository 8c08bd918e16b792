"""Every registered kind has every part of its protocol (clik/constraints/kind.py).

A kind is one Python class and one C++ type; nothing else lists the kinds. So each
registered kind must itself have: its C++ counterpart (the ``_engine`` config it
builds), its scenario table reader if it has a table, the pose check's name of its
keys and the unit of its depths (recovery records), its violation words, its drawing
when it reports regions (the 3-D view), its entry in docs/guides/constraints.md and its
case in tests/constraints/test_kinds.py. :func:`protocol_gaps` lists what a kind lacks;
:func:`test_a_missing_part_is_found` removes parts and sees them named.

And a start inside a threshold gives exactly one recovery record per constraint key
inside it, measured by the kind's own check and worded in its unit, in both engines.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.constraints import ConstraintRun, Dexterity, JointLimits, LinkPairs, ObstacleAvoidance
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.cone import Cone
from clik.constraints.kind import ConstraintKind, KindRun
from clik.constraints.pose_check import PoseCheck
from clik.constraints.recovery import recovery_clause
from clik.constraints.region import Lines, Region
from clik.constraints.registry import KINDS, TABLE_KINDS, kind_of, limit_words
from clik.constraints.words import LimitWords, Measure
from clik.constraints.workspace import Workspace
from clik.trajectory import Hold
from clik.viz.shape_layer import region_layer
from clik.viz.timeline import Timeline
from tests.constraints import test_kinds
from tests.constraints.test_kinds import BAD_INPUT, CASES, KIND_IDS, Case, kind_run

GUIDE = Path(__file__).parents[2] / "docs" / "guides" / "constraints.md"


def guide_text() -> str:
    """docs/guides/constraints.md (read each time: a test may stand in another)."""
    return GUIDE.read_text()


def _defined(kind_type: type[ConstraintKind], attr: str) -> bool:
    """Whether ``attr`` is the kind's own (not only the base class's annotation or default)."""
    return any(attr in vars(c) for c in kind_type.__mro__ if c is not ConstraintKind)


def _runs(case: Case, kind_type: type) -> list[KindRun]:
    task = case.task
    crun = ConstraintRun(
        case.cset, task.m, "pseudoinverse", 1.0, np.array([0.0, 1e-3]), 1, task.frame_id,
        task.rows,
    )  # fmt: skip
    return [run for run in crun.runs if type(run.kind) is kind_type]


def hold_run(case: Case, engine: str = "python", duration: float = 0.05) -> clik.TrackingResult:
    """The case held at its configuration (inside the kind's threshold) for ``duration``."""
    hold = Hold(position=case.task.placement(case.q).translation, duration=duration)
    tracker = clik.Tracker(
        case.task, law="pseudoinverse", gain=100.0, dt=1e-3, constraints=case.cset, engine=engine
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a start inside a threshold warns
        return tracker.run(hold, case.q)


def _engine_gaps(case: Case, kind_type: type) -> list[str]:
    from clik.engine import load

    engine = load()
    mine = [k for k in case.cset.kinds if type(k) is kind_type]
    configs = [k.engine_config() for k in mine]
    case.cset.engine_config()  # the engine's set takes them (its variant has the type)
    return [
        f"its C++ counterpart (engine_config() gave a {type(c).__module__}.{type(c).__name__})"
        for c in configs
        if getattr(engine, type(c).__name__, None) is not type(c)
        or not type(c).__name__.endswith("Config")
    ] + ([] if mine else ["a kind in its case's set"])


def _table_gaps(kind_type: type[ConstraintKind]) -> list[str]:
    if kind_type.table is None:
        return ["no table, yet listed in TABLE_KINDS"] if kind_type in TABLE_KINDS else []
    gaps = [] if _defined(kind_type, "read_table") else ["its scenario table reader (read_table)"]
    if kind_type not in TABLE_KINDS:
        gaps.append("its place in registry.TABLE_KINDS")
    if f"[[constraints.{kind_type.table}]]" not in guide_text():
        gaps.append(f"[[constraints.{kind_type.table}]] in docs/guides/constraints.md")
    return gaps


def _recovery_gaps(case: Case, kind_type: type[ConstraintKind]) -> list[str]:
    gaps = []
    if getattr(kind_type.check_name, "__isabstractmethod__", False):
        gaps.append("its pose check's name of a key (check_name)")
    elif not kind_type.owns(kind_type.name) or kind_of(kind_type.name) is not kind_type:
        gaps.append(f"its keys' prefix {kind_type.name!r} (another kind owns it)")
    else:
        keys = kind_run(case, kind_type, case.q)
        checker = PoseCheck(case.cset, case.task)
        names = {
            v.constraint
            for k in case.cset.kinds
            if type(k) is kind_type
            for v in k.check(checker, case.q)
        }
        for key in keys:
            if kind_of(key) is not kind_type:
                gaps.append(f"its key {key!r} (owned by {kind_of(key)})")
            elif kind_type.check_name(key) not in names:
                gaps.append(f"check_name({key!r}) = {kind_type.check_name(key)!r}, not in {names}")
    if not _defined(kind_type, "depth_measure") or not isinstance(kind_type.depth_measure, Measure):
        gaps.append("the unit of its depths (depth_measure)")
    return gaps


def _words_gaps(case: Case, kind_type: type[ConstraintKind]) -> list[str]:
    if not _defined(kind_type, "limit_words"):
        return ["its violation words (limit_words)"]
    words = kind_type.limit_words
    if words is not None and not isinstance(words, LimitWords):
        return [f"its violation words (limit_words = {words!r})"]
    guards = any(
        type(r).observe_limits is not KindRun.observe_limits for r in _runs(case, kind_type)
    )
    if guards and words is None:
        return ["its violation words (its run observes limits, limit_words is None)"]
    return []


def _view_gaps(case: Case, kind_type: type[ConstraintKind]) -> list[str]:
    result = hold_run(case, duration=0.002)
    gaps = []
    for spec in result.info.get("shapes") or []:
        owner = kind_of(str(spec.get("name", "")))
        if owner is None:
            gaps.append(f"a region named by one of its keys (info['shapes'] has {spec})")
            continue
        if owner is not kind_type:
            continue
        try:
            region = owner.region(spec)
        except NotImplementedError:
            gaps.append("its drawing of a region it reports (region)")
            continue
        q = result.q[:1]
        commands, _ = region_layer(
            case.cset.robot, [spec], q, Timeline.from_times(result.t[:1], 30)
        )
        drawn = {c["path"].rsplit("/", 1)[-1] for c in commands if c["type"] == "set_object"}
        if not isinstance(region, Region) or drawn != set(region.names):
            gaps.append(f"its region drawn: {drawn} of {region}")
    return gaps


def protocol_gaps(kind_type: type[ConstraintKind]) -> list[str]:
    """The parts of the protocol ``kind_type`` lacks ([] when it is complete)."""
    gaps = []
    if not re.search(rf"\b{kind_type.__name__}\b", guide_text()):
        gaps.append(f"its entry in docs/guides/constraints.md ({kind_type.__name__})")
    if kind_type not in {k for k, _, _ in BAD_INPUT}:
        gaps.append("its bad input in tests/constraints/test_kinds.py (BAD_INPUT)")
    gaps += _table_gaps(kind_type)
    if kind_type not in CASES:
        return [*gaps, "its case in tests/constraints/test_kinds.py (CASES)"]
    case = CASES[kind_type]()
    gaps += _engine_gaps(case, kind_type)
    gaps += _recovery_gaps(case, kind_type)
    gaps += _words_gaps(case, kind_type)
    return gaps + _view_gaps(case, kind_type)


@pytest.mark.parametrize("kind_type", KINDS, ids=KIND_IDS)
def test_every_kind_has_its_whole_protocol(kind_type):
    assert protocol_gaps(kind_type) == []


def test_each_kind_has_its_own_engine_type():
    names = {}
    for kind_type in KINDS:
        case = CASES[kind_type]()
        (kind,) = [k for k in case.cset.kinds if type(k) is kind_type]
        names[kind_type] = type(kind.engine_config()).__name__
    assert len(set(names.values())) == len(KINDS), names


REMOVALS = [
    ("attr", Workspace, "limit_words", "its violation words (limit_words)"),
    ("attr", Cone, "depth_measure", "the unit of its depths (depth_measure)"),
    ("attr", LinkPairs, "check_name", "its pose check's name of a key (check_name)"),
    ("attr", Cone, "region", "its drawing of a region it reports (region)"),
    ("attr", Workspace, "read_table", "its scenario table reader (read_table)"),
    ("case", Dexterity, None, "its case in tests/constraints/test_kinds.py (CASES)"),
    ("docs", ObstacleAvoidance, None, "its entry in docs/guides/constraints.md"),
]


@pytest.mark.parametrize(("what", "kind_type", "attr", "gap"), REMOVALS)
def test_a_missing_part_is_found(monkeypatch, what, kind_type, attr, gap):
    """The check bites: with one part of one kind taken away, it names that part."""
    assert protocol_gaps(kind_type) == []
    if what == "attr":
        monkeypatch.delattr(kind_type, attr)
    elif what == "case":
        monkeypatch.delitem(CASES, kind_type)
    else:
        text = guide_text().replace(kind_type.__name__, "the obstacle kind")
        monkeypatch.setattr(f"{__name__}.guide_text", lambda: text)
    assert any(g.startswith(gap) for g in protocol_gaps(kind_type)), protocol_gaps(kind_type)


# -- a start inside a threshold -----------------------------------------------------------

DEPTH_WORDS = {
    JointLimits: "{:.4g}",
    ObstacleAvoidance: "{:.3g} mm",
    LinkPairs: "{:.3g} mm",
    Dexterity: "{:.4g}",
    Workspace: "{:.3g} mm",
    Cone: "{:.4g}",
    CloudAvoidance: "{:.3g} mm",
}
"""How a recovery clause writes each kind's depth: lengths in mm, the others as they are."""


def depth_text(kind_type: type, depth: float) -> str:
    scale = 1e3 if DEPTH_WORDS[kind_type].endswith("mm") else 1.0
    return DEPTH_WORDS[kind_type].format(depth * scale)


def test_every_kind_has_its_depth_words():
    assert set(DEPTH_WORDS) == set(KINDS)


def inside_by_name(case: Case, kind_type: type, q: np.ndarray) -> dict[str, float]:
    """The kind's positive row errors at ``q``, the largest per check name."""
    out: dict[str, float] = {}
    for key, (error, _) in kind_run(case, kind_type, q).items():
        if error > 0.0:
            name = kind_type.check_name(key)
            out[name] = max(out.get(name, 0.0), error)
    return out


BACK = 1e-6
"""Back at the threshold: an error at most this fraction of the depth (recovery's rule)."""


@pytest.mark.parametrize("kind_type", KINDS, ids=KIND_IDS)
def test_a_start_inside_gives_one_record_per_constraint(kind_type):
    """One record per key inside its threshold at the start: its depth the kind's rows'
    error (the deepest of the keys its check names alike), its end the first sample its
    rows are out (or its row's release), its clause in its unit; no second record under
    the check's name, no depth 0; both engines alike."""
    case = CASES[kind_type]()
    inside = {k for k, (e, _) in kind_run(case, kind_type, case.q).items() if e > 0.0}
    by_name = inside_by_name(case, kind_type, case.q)
    results = [hold_run(case, engine, duration=0.5) for engine in ("python", "compiled")]
    result, records = results[0], results[0].summary()["recovery"]
    assert records == results[1].summary()["recovery"]
    assert inside and sorted(r["constraint"] for r in records) == sorted(inside)
    for r in records:
        name = kind_type.check_name(r["constraint"])
        depth = by_name[name]
        assert r["depth"] == pytest.approx(depth, rel=1e-6, abs=1e-9), r
        assert r["depth"] > 0.0 and r["t_start"] == result.t[0]
        assert r["recovered"] == (r["t_end"] is not None)
        if r["recovered"]:
            j = int(np.searchsorted(result.t, r["t_end"]))
            assert inside_by_name(case, kind_type, result.q[j - 1]).get(name, 0.0) > BACK * depth
            released = {"t": result.t[j], "action": "release", "constraint": r["constraint"]}
            out = inside_by_name(case, kind_type, result.q[j]).get(name, 0.0) <= BACK * depth
            assert out or any(e == released for e in result.events), r
        clause = f"started inside the threshold of {r['constraint']} "
        clause += f"(depth {depth_text(kind_type, r['depth'])}), "
        clause += f"recovered in {r['duration']:.3g} s" if r["recovered"] else "not back"
        assert clause in recovery_clause(records), recovery_clause(records)
    if "started inside" in result.reason:  # a deadlock's reason says other things
        assert result.reason.endswith(recovery_clause(records))


# -- the words of a crossed limit, and a new shape ------------------------------------------


@pytest.mark.parametrize(
    ("key", "worst", "words"),
    [
        ("joint:j2:upper", 0.0123456, "joint:j2:upper crossed by 0.01235"),
        ("obstacle:ball:l3", 0.0032, "obstacle:ball:l3 penetrated 3.2 mm deep"),
        ("self:l1:l3", 0.0011, "self:l1:l3 penetrated 1.1 mm deep"),
        ("workspace:cell:x:upper", 0.012, "workspace:cell:x:upper crossed by 12 mm"),
        ("cone:up", 0.1, "cone:up crossed by 5.73 deg"),
        ("plane:floor", 0.5, "plane:floor crossed by 0.5"),  # no such kind: as it is
    ],
)
def test_a_crossed_limit_reads_as_its_kind_says(key, worst, words):
    from clik.constraints.violations import ViolationRecord

    record = ViolationRecord(key, "any", 0.25, worst, limit_words(key))
    assert record.describe() == f"{words} at t = 0.25 s"


class Plane(ConstraintKind):
    """A kind the view has never seen: a large thin square and its normal."""

    name = "plane"
    depth_measure = Measure("mm", 1e3, ".3g")
    limit_words = None

    @classmethod
    def check_name(cls, key: str) -> str:
        return f"plane {key.partition(':')[2]!r}"

    @classmethod
    def region(cls, spec):
        from clik.constraints.region import Surface

        c, n = np.asarray(spec["point"], float), np.asarray(spec["normal"], float)
        a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        square = np.array([c + s * a + t * b for s in (-1, 1) for t in (-1, 1)])
        return Region(
            (Surface("square", square, [(0, 1, 3), (0, 3, 2)]), Lines("normal", [c, c + 0.2 * n]))
        )

    def start(self, setup):
        raise NotImplementedError

    def engine_config(self):
        raise NotImplementedError


def test_a_new_shape_needs_no_change_in_the_view(monkeypatch):
    """A registered kind with a new shape is drawn by the view as it is."""
    import clik.constraints.registry as registry

    monkeypatch.setattr(registry, "KINDS", (*KINDS, Plane))
    robot = test_kinds.robot()
    spec = {"name": "plane:floor", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}
    one = Timeline.from_times(np.zeros(1), 30)
    commands, clips = region_layer(robot, [spec], np.zeros((1, robot.nq)), one)
    assert {c["path"] for c in commands} == {
        "/meshcat/regions/plane:floor/square",
        "/meshcat/regions/plane:floor/normal",
    }
    assert clips == {}
