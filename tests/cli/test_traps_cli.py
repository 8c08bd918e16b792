"""The command line's rough edges of issue 27: warnings, the wrote-line, shipped names, help.

Each test gives the message or behaviour the user now gets.
"""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import pytest

import clik
import clik.cli
from clik.cli import main, parser
from clik.commands import solve as solve_command
from clik.commands.solve import wrote_line
from clik.commands.warning_lines import cli_warnings, warning_line
from clik.model.mimic import MimicJointWarning
from clik.outputs.result import FAILED_STATUSES
from clik.scenarios import scenario_path
from clik.sweep import report
from tests.limits_check import assert_summary_within_limits

# -- (e) warnings: one clean line, once -----------------------------------------------------


def _warn_twice_from_two_places() -> None:
    warnings.warn(MimicJointWarning("panda: a mimic joint locked", {}), stacklevel=1)
    warnings.warn(MimicJointWarning("panda: a mimic joint locked", {}), stacklevel=1)
    warnings.warn("something else\n  on two lines", RuntimeWarning, stacklevel=1)


def test_warning_line_format():
    assert (
        warning_line(MimicJointWarning("m", {}), MimicJointWarning)
        == "clik: warning: m [MimicJointWarning]"
    )
    assert warning_line("a\n  b", UserWarning) == "clik: warning: a; b"


def test_cli_prints_each_warning_once_as_one_line(monkeypatch, capsys):
    def fake_solve(args: object) -> int:
        _warn_twice_from_two_places()
        _warn_twice_from_two_places()  # again, from the same places
        return 0

    monkeypatch.setattr(solve_command, "cmd_solve", fake_solve)
    before = warnings.showwarning
    assert main(["solve", "x.toml", "--out", "unused"]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == [
        "clik: warning: panda: a mimic joint locked [MimicJointWarning]",
        "clik: warning: something else; on two lines [RuntimeWarning]",
    ]
    assert ".py:" not in err and "warnings.warn" not in err  # no source file, no source line
    # Python API users keep normal warnings: the hook is gone after the command.
    assert warnings.showwarning is before
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_twice_from_two_places()
    assert [w.category for w in caught] == [MimicJointWarning, MimicJointWarning, RuntimeWarning]


def test_cli_warnings_leave_error_filters_in_force():
    with warnings.catch_warnings():
        warnings.simplefilter("error", MimicJointWarning)
        with pytest.raises(MimicJointWarning), cli_warnings():
            _warn_twice_from_two_places()


def test_reach_prints_the_workers_warning_once(tmp_path, capsys):
    """Worker processes warned in Python's raw format, once each, besides the main process."""
    code = main(
        [
            "reach", "panda", "--frame", "panda_hand", "--box", "0.4", "0", "0.5", "0.4", "0",
            "0.5", "--step", "0.1", "--out", str(tmp_path / "reach"), "--no-html", "--quiet",
            "--workers", "1",
        ]
    )  # fmt: skip
    assert code == 0
    lines = capsys.readouterr().err.splitlines()
    assert lines, "the panda warns when loaded (its mimic finger): nothing left to check"
    assert all(line.startswith("clik: warning: ") for line in lines), lines  # no raw format
    assert len(set(lines)) == len(lines), lines  # each once, from the workers too


def test_worker_warnings_travel_back_and_are_warned_once(monkeypatch):
    """A Dask task's warnings come back with its columns; the map warns each one once."""
    from clik.sweep import reach

    def warns(spec: object, points: object) -> dict:
        warnings.warn(MimicJointWarning("worker: finger locked", {"f": ("g", 0.0)}), stacklevel=1)
        warnings.warn(MimicJointWarning("worker: finger locked", {}), stacklevel=1)
        return {"x": [0.0]}

    monkeypatch.setattr(reach, "_solve_points", warns)
    with warnings.catch_warnings(record=True) as outside:
        warnings.simplefilter("always")
        part = reach.solve_points(None, None)
    assert outside == []  # nothing printed by the worker
    assert part[reach.WARNINGS] == [(MimicJointWarning, "worker: finger locked")]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        shown = reach._rewarn(part[reach.WARNINGS] * 2, {"already shown"})
    assert [(w.category, str(w.message)) for w in caught] == part[reach.WARNINGS]
    assert shown == {"already shown", "worker: finger locked"}


# -- (f) + (h): a shipped name runs, the wrote-line lists every file -------------------------


def test_wrote_line_lists_every_file():
    files = [Path("o/summary.json"), Path("o/trajectory.npz"), Path("o/scene.html")]
    assert wrote_line(files) == "wrote o/summary.json, o/trajectory.npz and o/scene.html"
    assert wrote_line(files[:1]) == "wrote o/summary.json"


def test_solve_a_shipped_name_with_html_and_plots(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no file of that name here: the shipped scenario runs
    out = tmp_path / "out"
    code = main(["solve", "case_study_unconstrained", "--out", str(out), "--html", "--plots"])
    printed = capsys.readouterr().out
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["max_task_error"] < 1e-3  # [m]
    assert_summary_within_limits(summary, clik.Robot.load("planar4r"))
    (line,) = [s for s in printed.splitlines() if s.strip().startswith("wrote ")]
    written = sorted(p.name for p in out.iterdir())
    assert {"scene.html", "summary.json", "trajectory.npz", "joints.png"} <= set(written)
    listed = sorted(Path(p).name for p in re.split(r", | and ", line.strip()[len("wrote ") :]))
    assert listed == written  # every file written, on the one line


def test_solve_unknown_name_lists_the_shipped_ones(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["solve", "panda_circel", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clik: error: scenario: expected a scenario file or a shipped")
    assert "panda_circle" in err and "got 'panda_circel'" in err
    assert not (tmp_path / "o").exists()


def test_a_file_wins_over_a_shipped_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "panda_circle").write_text("not toml [")
    with pytest.raises(clik.ScenarioError, match="not valid TOML"):
        solve_command.cmd_solve(parser().parse_args(["solve", "panda_circle", "--out", "o"]))
    assert solve_command.scenario_file("panda_circle.toml") == scenario_path("panda_circle")


def _help(*command: str) -> str:
    sub = parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    assert isinstance(sub, dict)
    return " ".join(sub[command[0]].format_help().split())  # one line, wrapping undone


def test_solve_help_names_the_shipped_scenarios():
    text = _help("solve")
    assert "shipped scenario" in text
    for name in ("panda_circle", "case_study_both", "baxter_two_hands"):
        assert name in text


# -- (i) help and docs list every status, from the code's tables -----------------------------


def test_sweep_help_lists_every_failed_status():
    text = _help("sweep")
    sentence = text[text.index("Exit code 1") :]
    sentence = sentence[: sentence.index("written)")]
    assert set(re.findall(r"[a-z_]+", sentence)) >= set(report.FAILED_STATUSES) | {report.RAISED}
    assert "deadlock" not in sentence  # a deadlocked run does not fail a sweep


def test_solve_help_and_cli_docstring_list_every_infeasible_status():
    text = _help("solve")
    sentence = text[text.index("Exit code 3") :]
    for status in FAILED_STATUSES:
        assert status in sentence[: sentence.index("2 on bad input")]
    doc = " ".join(clik.cli.__doc__.split())
    infeasible = doc[doc.index("3 infeasible") :]
    infeasible = infeasible[: infeasible.index(")")]
    assert all(status in infeasible for status in FAILED_STATUSES), infeasible
    failed_sweep = doc[doc.index("1 a sweep") :]
    failed_sweep = failed_sweep[: failed_sweep.index(")")]
    assert all(status in failed_sweep for status in report.FAILED_STATUSES), failed_sweep


def test_readme_statuses_match_the_code():
    """The README's statuses table lists every status the code knows (and exit codes, if any)."""
    readme = Path(__file__).parents[2] / "README.md"
    rows = {
        m.group(1): line
        for line in readme.read_text().splitlines()
        if (m := re.match(r"^\| `([a-z_]+)` \|", line))
    }
    known = set(FAILED_STATUSES) | {"completed"}
    if not set(rows) & known:
        pytest.skip("the README has no statuses table")
    assert known <= set(rows), sorted(known - set(rows))
    for status in known:  # a last column of exit codes, when the table has one
        code = re.search(r"\| *(\d+) *\|$", rows[status])
        assert code is None or code.group(1) == ("0" if status == "completed" else "3")
