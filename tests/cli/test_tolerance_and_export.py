"""``[solver] tolerance`` / ``settling_time`` in a scenario, and ``clik solve --export``.

The case study with the law (10) (``case_study_unconstrained_pinv``, 3 s): its
tolerance reaches the run, a bad one is refused naming its key; ``--export`` may be
given several times.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from clik.cli import main
from clik.errors import ScenarioError
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.scenarios.scenario import parse_scenario

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

BASE = scenario_path("case_study_unconstrained_pinv")


def scenario(solver_lines: str):
    text = BASE.read_text().replace("[solver]\n", f"[solver]\n{solver_lines}\n", 1)
    return parse_scenario(tomllib.loads(text), BASE)


def test_defaults_and_given_values_reach_the_run():
    assert scenario("").solver["tolerance"] == (0.01, 0.05)
    assert scenario("").solver["settling_time"] == 0.5
    given = scenario("tolerance = { orientation = 0.1 }\nsettling_time = 0.2")
    assert given.solver["tolerance"] == (0.01, 0.1) and given.solver["settling_time"] == 0.2
    assert scenario("tolerance = 0.002").solver["tolerance"] == (0.002, 0.05)
    result = build(scenario("tolerance = { position = 0.004 }\nsettling_time = 0.3")).execute()
    assert result.info["tolerance"] == {
        "position": 0.004,
        "orientation": 0.05,
        "settling_time": 0.3,
    }
    assert result.status == "completed"


def test_a_tight_tolerance_makes_the_law_9_case_study_off_track():
    """Law (9)'s 0.6 mm error (``case_study_unconstrained``) is above a 0.1 mm tolerance."""
    path = scenario_path("case_study_unconstrained")
    text = path.read_text().replace("[solver]\n", "[solver]\ntolerance = 1e-4\n", 1)
    result = build(parse_scenario(tomllib.loads(text), path)).execute()
    assert result.status == "off_track"
    assert "above the tolerance 0.0001 m" in result.reason


@pytest.mark.parametrize(
    ("lines", "key"),
    [
        ("tolerance = { position = 0.0 }", "solver.tolerance.position"),
        ("tolerance = { orientation = -1 }", "solver.tolerance.orientation"),
        ("tolerance = { position = nan }", "solver.tolerance.position"),
        ("tolerance = { speed = 1.0 }", "solver.tolerance.speed"),
        ("tolerance = 'tight'", "solver.tolerance"),
        ("tolerance = -0.01", "solver.tolerance"),
        ("settling_time = 0", "solver.settling_time"),
        ("settling_time = inf", "solver.settling_time"),
    ],
)
def test_bad_values_are_refused_naming_the_key(lines, key):
    with pytest.raises(ScenarioError) as info:
        scenario(lines)
    assert info.value.key == key


def solve(out: Path, *options: str) -> int:
    return main(["solve", str(BASE), "--out", str(out), "--quiet", *options])


@pytest.mark.parametrize(
    "options",
    [
        ("--export", "csv", "--export", "json"),
        ("--export", "csv", "json"),
        ("--export", "json", "--export", "csv", "json"),
    ],
)
def test_export_flags_accumulate(tmp_path, options):
    out = tmp_path / "out"
    assert solve(out, *options) == 0
    assert (out / "trajectory.csv").is_file() and (out / "trajectory.json").is_file()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_one_format_twice_is_written_once(tmp_path):
    out = tmp_path / "out"
    assert solve(out, "--export", "csv", "--export", "csv") == 0
    assert (out / "trajectory.csv").is_file() and not (out / "trajectory.json").exists()


def test_off_track_exits_3_with_its_outputs(tmp_path):
    path = tmp_path / "tight.toml"
    text = scenario_path("case_study_unconstrained").read_text()
    path.write_text(text.replace("[solver]\n", "[solver]\ntolerance = 1e-4\n", 1))
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out), "--quiet"]) == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "off_track"
    assert summary["info"]["tolerance"]["position"] == 1e-4
    assert {"speed_limited", "speed_limited_time", "max_acceleration_ratio", "recovery"} <= set(
        summary
    )
