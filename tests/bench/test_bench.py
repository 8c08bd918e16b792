"""`clik bench --quick`: the report's structure (keys, finite positive figures), never a time."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from typing import Any

import pytest

from benchmarks.config import QUICK
from benchmarks.suite import REQUIRED_KEYS
from benchmarks.targets import default_targets_path, evaluate_targets, load_targets
from clik.errors import InputError

HAS_PINK = importlib.util.find_spec("pink") is not None and (
    importlib.util.find_spec("daqp") is not None or importlib.util.find_spec("quadprog") is not None
)
HAS_MINK = all(importlib.util.find_spec(name) is not None for name in ("mink", "mujoco")) and (
    importlib.util.find_spec("daqp") is not None or importlib.util.find_spec("quadprog") is not None
)
MINK_KEYS = {
    "tick_us.mink_panda_pose",
    "tick_us.mink_panda_pose_obstacles",
    "tick_quality.mink_panda_pose",
    "tick_quality.mink_panda_pose_obstacles",
}
PINK_KEYS = {
    "step_us.pink_panda_pose",
    "step_us.pink_panda_pose_obstacles",
    "tick_us.pink_panda_pose",
    "tick_us.pink_panda_pose_obstacles",
    "tick_quality.pink_panda_pose",
    "tick_quality.pink_panda_pose_obstacles",
    "step_us.pink_dual_arm",
    "solve.pink_median_us",
    "ratios.pink_over_panda_pose",
    "ratios.pink_over_panda_pose_obstacles",
    "ratios.pink_over_solve",
}
STEP_LINES = (
    "planar4r",
    "planar4r_case_study_both",
    "panda_pose",
    "panda_pose_transpose",
    "panda_pose_obstacles",
    "panda_pose_obstacles_0_active",
    "panda_pose_obstacles_1_active",
    "panda_pose_obstacles_transpose",
    "dual_arm",
)
PYTHON_STEP_LINES = tuple(f"python_{name}" for name in STEP_LINES)


def lookup(report: dict[str, Any], dotted: str) -> Any:
    node: Any = report
    for part in dotted.split("."):
        assert isinstance(node, dict) and part in node, f"bench.json lacks {dotted!r}"
        node = node[part]
    return node


def positive(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value > 0


def text_of(quick: tuple[Path, dict[str, Any]]) -> str:
    return (quick[0] / "bench.md").read_text()


def test_quick_run_writes_json_and_markdown(quick):
    out, returned = quick
    report = json.loads((out / "bench.json").read_text())
    assert report == json.loads(json.dumps(returned))
    assert report["quick"] is True
    text = (out / "bench.md").read_text()
    for heading in (
        "## Step cost",
        "## Zoo obstacle run",
        "## Single-pose solve",
        "## Ratios",
        "## Case study",
        "## Targets",
    ):
        assert heading in text
    for name in report["steps"]:
        assert f"| {name} |" in text


def test_every_required_key_is_present_and_sane(quick):
    out, _ = quick
    report = json.loads((out / "bench.json").read_text())
    for key in REQUIRED_KEYS:
        value = lookup(report, key)
        if (key in PINK_KEYS and not HAS_PINK) or (key in MINK_KEYS and not HAS_MINK):
            assert value is None, key
        elif key.startswith("tick_quality."):  # a clearance may be negative (inside a sphere)
            assert all(math.isfinite(figure) for figure in value.values()), (key, value)
        elif key.startswith("memory_growth_mb"):
            # Growth of the peak RSS: may be 0 for the quick run's few samples.
            assert isinstance(value, int | float) and math.isfinite(value) and value >= 0, key
        else:
            assert positive(value), (key, value)
    assert 0.0 <= report["solve"]["success_rate"] <= 1.0


def test_step_lines_have_medians_and_percentiles(quick):
    _, report = quick
    for name in STEP_LINES + PYTHON_STEP_LINES:
        assert positive(report["step_us"][name]), name
    for name, line in report["steps"].items():
        for field in ("median_us", "p10_us", "p90_us", "realtime_factor"):
            assert positive(line[field]), (name, field)
        assert line["p10_us"] <= line["median_us"] <= line["p90_us"], name
        assert line["steps_per_run"] >= 1
        assert line["status"] == "completed", (name, line["status"])
        assert line.get("violations", 0) == 0, name  # pink's lines have no such record
    # The obstacle variants do what their names say.
    assert report["steps"]["panda_pose_obstacles_0_active"]["active_rows_mean"] == 0.0
    assert report["steps"]["panda_pose_obstacles_1_active"]["active_rows_mean"] > 0.5
    assert report["steps"]["python_panda_pose_obstacles_0_active"]["active_rows_mean"] == 0.0
    assert report["steps"]["python_panda_pose_obstacles_1_active"]["active_rows_mean"] > 0.5
    assert ("pink_panda_pose" in report["steps"]) == HAS_PINK
    assert ("pink_dual_arm" in report["steps"]) == HAS_PINK
    # The dual-arm lines track both hands (the run's largest hand error).
    assert report["steps"]["dual_arm"]["max_task_error"] <= 1e-5
    assert report["steps"]["python_dual_arm"]["max_task_error"] <= 1e-5


def test_every_clik_line_runs_in_both_engines(quick):
    _, report = quick
    steps = report["steps"]
    compiled = [name for name in steps if not name.startswith(("pink_", "python_"))]
    assert set(compiled) >= set(STEP_LINES) - {"panda_pose_obstacles"}
    for name in compiled:
        assert steps[name]["engine"] == "compiled", name
        twin = steps[f"python_{name}"]
        assert twin["engine"] == "python", name
        assert twin["law"] == steps[name]["law"] and twin["status"] == steps[name]["status"]
        assert twin["steps_per_run"] == steps[name]["steps_per_run"], name
        ratio = report["ratios"]["python_over_compiled_steps"][name]
        assert ratio == pytest.approx(twin["median_us"] / steps[name]["median_us"]), name
    # Each step_us key is its line's median, the keys of the old report kept.
    assert report["step_us"]["planar4r"] == steps["planar4r"]["median_us"]
    assert report["step_us"]["panda_pose"] == steps["panda_pose"]["median_us"]
    obstacles = steps["panda_pose_obstacles_1_active"]["median_us"]
    assert report["step_us"]["panda_pose_obstacles"] == obstacles
    python_pose = steps["python_panda_pose"]["median_us"]
    assert report["step_us"]["python_panda_pose"] == python_pose
    assert report["ratios"]["python_over_panda_pose"] == pytest.approx(
        python_pose / steps["panda_pose"]["median_us"]
    )


def test_zoo_line(quick):
    _, report = quick
    zoo = report["zoo"]
    assert report["step_us"]["zoo_obstacle_median"] == zoo["median_us"]
    assert positive(zoo["median_us"])
    assert zoo["p10_us"] <= zoo["median_us"] <= zoo["p90_us"] <= zoo["max_us"]
    assert QUICK.zoo_robots is not None
    assert zoo["robots_timed"] == len(zoo["per_robot"]) >= 1
    assert zoo["robots_skipped"] == len(zoo["skipped"])
    assert set(zoo["per_robot"]) | set(zoo["skipped"]) == set(QUICK.zoo_robots)
    for name, robot in zoo["per_robot"].items():
        assert positive(robot["median_us"]) and robot["steps"] >= 1, name
        assert robot["status"] in ("completed", "deadlock", "violated"), (name, robot)
    assert f"| {zoo['robots_timed']} |" in text_of(quick)


def test_solve_runs_both_engines(quick):
    _, report = quick
    solve = report["solve"]
    assert 0.0 <= solve["python_success_rate"] <= 1.0
    assert positive(solve["python_median_us"])
    assert report["ratios"]["python_over_solve"] == pytest.approx(
        solve["python_median_us"] / solve["median_us"]
    )
    assert "| clik.solve, Python engine |" in text_of(quick)


def test_case_study_memory_and_meta_sections(quick):
    _, report = quick
    case = report["case_study"]
    assert set(case["per_run_s"]) == set(case["status"])
    assert len(case["per_run_s"]) == 8
    assert all(positive(v) for v in case["per_run_s"].values())
    for mode in ("full", "decimated"):
        mem = report["memory"][mode]
        assert mem["status"] == "completed" and mem["violations"] == 0
        assert mem["samples"] == report["config"]["memory_samples"]
    assert report["memory"]["decimated"]["recorded_samples"] < mem["samples"]
    assert report["versions"]["clik"]
    assert report["machine"]["cores"] >= 1
    assert {t["name"] for t in report["targets"]} >= {"panda_pose [us]", "solve median [us]"}
    for t in report["targets"]:
        assert t["met"] in (True, False, None)


@pytest.mark.skipif(not HAS_PINK, reason="pink not installed: pip install 'clik[bench]'")
def test_pink_lines_and_ratios(quick):
    _, report = quick
    assert positive(report["ratios"]["pink_over_panda_pose"])
    assert report["ratios"]["pink_over_panda_pose_obstacles"] == pytest.approx(
        report["step_us"]["pink_panda_pose_obstacles"] / report["step_us"]["panda_pose_obstacles"]
    )
    assert "SelfCollisionBarrier" in report["steps"]["pink_panda_pose_obstacles"]["description"]
    assert report["ratios"]["pink_over_solve"] == pytest.approx(
        report["solve"]["pink_median_us"] / report["solve"]["median_us"]
    )
    assert 0.0 <= report["solve"]["pink_success_rate"] <= 1.0
    assert report["pink"]["solver"] in ("daqp", "quadprog")


def test_targets_come_from_the_shipped_toml(quick):
    _, report = quick
    path = default_targets_path()
    assert path.name == "targets.toml" and path.is_file()
    shipped = load_targets()
    assert [t["name"] for t in report["targets"]] == [t.name for t in shipped]
    assert [t["target"] for t in report["targets"]] == [t.wanted for t in shipped]
    assert len(shipped) == 32
    by_measure = {(t.measure, t.over): t for t in shipped}
    assert by_measure[("memory_growth_mb.controller_session", None)].bound == 1.0
    assert by_measure[("controller_session.result_ms", None)].bound == 50.0
    assert by_measure[("step_us.dual_arm", None)].bound == 6.0
    assert by_measure[("tick_us.dual_arm", None)].bound == 6.0
    assert by_measure[("tick_us.pink_dual_arm", "tick_us.dual_arm")].bound == 12.0
    assert by_measure[("tick_us.humanoid", None)].bound == 15.0
    assert by_measure[("tick_us.pink_humanoid", "tick_us.humanoid")].bound == 10.0
    assert by_measure[("tick_us.mink_humanoid", "tick_us.humanoid")].bound == 5.0
    assert by_measure[("step_us.humanoid", None)].bound == 8.0
    assert by_measure[("step_us.pink_dual_arm", "step_us.dual_arm")].bound == 30.0
    assert by_measure[("step_us.planar4r", None)].bound == 1.5
    assert by_measure[("step_us.zoo_obstacle_median", None)].bound == 20.0
    assert by_measure[("step_us.panda_pose", None)].bound == 2.5
    # pink with its barrier over clik with its obstacle rows (like against like)
    obstacles = by_measure[("step_us.pink_panda_pose_obstacles", "step_us.panda_pose_obstacles")]
    assert obstacles.name == "pink / panda_pose_obstacles" and obstacles.bound == 20.0
    assert ("step_us.pink_panda_pose", "step_us.panda_pose_obstacles") not in by_measure
    ticks = {
        ("tick_us.panda_pose", None): ("<=", 3.0),
        ("tick_us.pink_panda_pose", "tick_us.panda_pose"): (">=", 40.0),
        ("tick_us.mink_panda_pose", "tick_us.panda_pose"): (">=", 30.0),
        ("tick_us.panda_pose_obstacles", None): ("<=", 8.0),
        ("tick_us.pink_panda_pose_obstacles", "tick_us.panda_pose_obstacles"): (">=", 100.0),
        ("tick_us.mink_panda_pose_obstacles", "tick_us.panda_pose_obstacles"): (">=", 15.0),
        ("tick_error_m.panda_pose", None): ("<=", 1e-6),
    }
    for key, (op, bound) in ticks.items():
        assert (by_measure[key].op, by_measure[key].bound) == (op, bound), key
    for t in report["targets"]:
        if t["met"] is not None:
            assert math.isfinite(t["value"]), t


def test_a_targets_file_is_data(quick, tmp_path):
    _, report = quick
    path = tmp_path / "targets.toml"
    path.write_text(
        '[[target]]\nname = "rate"\nmeasure = "solve.success_rate"\nop = ">="\n'
        'bound = 0\nwanted = "any"\n'
        '[[target]]\nname = "ratio"\nmeasure = "case_study_all_runs_s"\n'
        'over = "case_study_all_runs_s"\nop = "<"\nbound = 0.5\nwanted = "< 0.5"\n'
    )
    rate, one = evaluate_targets(report, load_targets(path))
    assert rate == {
        "name": "rate",
        "target": "any",
        "value": report["solve"]["success_rate"],
        "met": True,
    }
    assert one["value"] == 1.0 and one["met"] is False
    path.write_text('[[target]]\nname = "x"\nmeasure = "a"\nop = "=="\nbound = 1\nwanted = "1"\n')
    with pytest.raises(InputError, match="op"):
        load_targets(path)


def test_markdown_names_no_issue(quick):
    out, _ = quick
    text = (out / "bench.md").read_text()
    assert "## Targets\n" in text
    assert "issue" not in text.lower()


def test_an_out_that_cannot_be_a_folder_is_refused_before_the_bench(tmp_path, capsys):
    """``--out afile/sub`` or a file: exit 2 naming the path, at once (no bench run)."""
    from clik.cli import main

    afile = tmp_path / "afile"
    afile.write_text("mine")
    assert main(["bench", "--quick", "--out", str(afile / "sub")]) == 2
    assert f"cannot write output {afile / 'sub'}: {afile} is a file" in capsys.readouterr().err
    assert main(["bench", "--quick", "--out", str(afile)]) == 2
    assert "--out: expected a folder" in capsys.readouterr().err
    assert afile.read_text() == "mine"
