"""Sweeps: expansion of sweep files, the results store, and runs on real Dask clusters.

The cluster tests start real processes on 127.0.0.1 only (a scheduler and two
workers, or ``clik sweep --workers 2``) and stop every one of them. Runs use a
short case study (law (9), ``dt = 2 ms``, ``alpha = 400``: about 0.1 s each).
"""

from __future__ import annotations

import errno
import io
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import clik
from clik import InputError, ScenarioError
from clik.cli import main
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.sweep import keypath, load_sweep, read_results, run_id, run_sweep
from clik.sweep.progress import RunProgress
from clik.sweep.spec import tomllib
from clik.sweep.store import ResultStore, SweepOutputExistsError, read_manifest
from clik.sweep.worker import TRACE_ENV, robot_loads, run_batch, run_one
from tests.limits_check import assert_summary_within_limits, assert_within_limits

distributed = pytest.importorskip("distributed", reason="pip install 'dask[distributed]'")

PYTHON = sys.executable
CLIK = [PYTHON, "-m", "clik.cli"]
TIMEOUT = 180.0
"""Longest wait for one phase of a cluster test [s].

A phase takes a few seconds on an idle machine; the bound is generous for a
loaded one (a shared 2-core CI box) and, with :data:`STARTUP`, keeps a test
well under pytest's ``--timeout=600``.
"""

STARTUP = 120.0
"""Longest wait for a scheduler and its workers to start and connect [s]."""

SHORT_CASE = (
    scenario_path("case_study_both")
    .read_text()
    .replace("dt = 0.001", "dt = 0.002")
    .replace("gain = 1000.0", 'gain = 400.0\nengine = "python"\ntolerance = 0.02')
)
"""The case study, both constraints, at half the samples, on the Python engine: about
0.1 s a run, long enough for the tests that interrupt a sweep midway (the compiled
engine runs it in a few milliseconds).

``dt alpha = 0.8`` keeps explicit Euler stable (``dt alpha lambda_max(J_e J_e^T) < 2``)
over the whole obstacle grid: every run of :func:`obstacle_grid` completes (at
``alpha = 500`` a few runs near (0.78, -0.22) reach 2, which a stability check
may stop as ``diverged``, and a diverged run fails ``clik sweep``). ``tolerance = 0.02``
m: at this gain, where the pin sits on the tip's path, the rows hold the tip up to
1.18 cm off its line for over half a second (measured over the 10 x 8 grid), which the
default 1 cm tolerance calls ``off_track``, also a failed run.
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def obstacle_grid(nx: int, ny: int) -> str:
    """A sweep of the pin's position over an nx-by-ny grid around the paper's (0.7, -0.28)."""
    return (
        'base = "short.toml"\n'
        '[vary."obstacles.pin.position"]\n'
        "grid = { start = [0.62, -0.34, 0.0], stop = [0.78, -0.22, 0.0], "
        f"num = [{nx}, {ny}, 1] }}\n"
    )


@pytest.fixture
def short_sweep(tmp_path: Path):
    """A factory: (nx, ny) -> sweep file on the short case study, in tmp_path."""
    write(tmp_path, "short.toml", SHORT_CASE)

    def make(nx: int, ny: int, name: str = "sweep.toml") -> Path:
        return write(tmp_path, name, obstacle_grid(nx, ny))

    return make


def sweep_text(vary: str, base: str = "case_study_both", head: str = "") -> str:
    return f'base = "{base}"\n{head}\n{vary}'


# -- expansion ------------------------------------------------------------------------


def test_grid_values_and_product(tmp_path):
    path = write(
        tmp_path,
        "s.toml",
        sweep_text(
            '[vary."obstacles.pin.position"]\n'
            "grid = { start = [0.6, -0.3, 0.0], stop = [0.7, -0.2, 0.0], num = [3, 2, 1] }\n"
            '[vary."solver.gain"]\nvalues = [500.0, 1000.0]\n'
        ),
    )
    sweep = load_sweep(path)
    assert len(sweep.runs) == 3 * 2 * 2
    assert sweep.parameters == ["obstacles.pin.position", "solver.gain"]
    positions = sweep.vary[0].values
    assert positions == [
        [0.6, -0.3, 0.0],
        [0.6, -0.2, 0.0],
        [0.65, -0.3, 0.0],
        [0.65, -0.2, 0.0],
        [0.7, -0.3, 0.0],
        [0.7, -0.2, 0.0],
    ]  # 12 significant digits: 0.65, not 0.6499999999999999
    # A product, the first table varying slowest.
    assert [r.params["solver.gain"] for r in sweep.runs[:4]] == [500.0, 1000.0, 500.0, 1000.0]
    assert sweep.runs[2].params["obstacles.pin.position"] == [0.6, -0.2, 0.0]
    assert len({r.run_id for r in sweep.runs}) == len(sweep.runs)
    # The run's scenario is the base with the values substituted.
    scenario = sweep.scenario(sweep.runs[7])
    assert scenario.obstacles[0]["position"] == [0.65, -0.2, 0.0]
    assert scenario.solver["gain"] == 1000.0
    assert scenario.file == scenario_path("case_study_both")


def test_scalar_grid_keeps_integers(tmp_path):
    path = write(
        tmp_path,
        "s.toml",
        sweep_text('[vary."solver.record_every"]\ngrid = { start = 1, stop = 5, num = 3 }\n'),
    )
    assert load_sweep(path).vary[0].values == [1, 3, 5]


def test_uniform_tables_vary_jointly_and_reproducibly(tmp_path):
    vary = (
        '[vary."obstacles.pin.position"]\n'
        "uniform = { low = [0.65, -0.3, 0.0], high = [0.75, -0.26, 0.0], samples = 7 }\n"
        '[vary."solver.gain"]\nuniform = { low = 400.0, high = 900.0, samples = 7 }\n'
        '[vary."solver.law"]\nvalues = ["transpose", "pseudoinverse"]\n'
    )
    sweep = load_sweep(write(tmp_path, "a.toml", sweep_text(vary, head="seed = 3")))
    assert len(sweep.runs) == 2 * 7  # the list times the joint uniform block
    positions = np.array(sweep.vary[0].values)
    assert positions.shape == (7, 3)
    assert np.all(positions >= [0.65, -0.3, 0.0]) and np.all(positions <= [0.75, -0.26, 0.0])
    gains = sweep.vary[1].values
    assert all(400.0 <= g <= 900.0 for g in gains)
    # Jointly: sample i of each table in the same run.
    first = [r for r in sweep.runs if r.params["solver.law"] == "transpose"]
    assert [r.params["solver.gain"] for r in first] == gains
    assert [r.params["obstacles.pin.position"] for r in first] == sweep.vary[0].values
    # Seeded: the same file gives the same samples; another seed, others.
    again = load_sweep(write(tmp_path, "b.toml", sweep_text(vary, head="seed = 3")))
    assert [r.run_id for r in again.runs] == [r.run_id for r in sweep.runs]
    other = load_sweep(write(tmp_path, "c.toml", sweep_text(vary, head="seed = 4")))
    assert other.vary[1].values != gains
    # A table's samples do not depend on the other tables.
    alone = load_sweep(
        write(
            tmp_path,
            "d.toml",
            sweep_text(
                '[vary."solver.gain"]\nuniform = { low = 400.0, high = 900.0, samples = 7 }\n',
                head="seed = 3",
            ),
        )
    )
    assert alone.vary[0].values == gains


def test_run_ids_are_stable_hashes_of_the_parameters():
    params = {"obstacles.pin.position": [0.7, -0.28, 0.0], "solver.gain": 1000.0}
    assert run_id(params) == run_id(dict(reversed(params.items())))
    assert run_id(params) == run_id(json.loads(json.dumps(params)))  # survives JSON
    assert run_id(params) != run_id({**params, "solver.gain": 1000.5})
    assert len(run_id(params)) == 16 and int(run_id(params), 16) >= 0
    assert run_id({"solver.gain": 1.0}) == "0e68160686de389b"  # pinned: ids name results on disk


def test_base_relative_to_the_sweep_file(tmp_path):
    (tmp_path / "cases").mkdir()
    write(tmp_path / "cases", "mine.toml", SHORT_CASE)
    sweep = load_sweep(
        write(
            tmp_path,
            "s.toml",
            sweep_text('[vary."solver.gain"]\nvalues = [1.0]', "cases/mine.toml"),
        )
    )
    assert sweep.base_file == tmp_path / "cases" / "mine.toml"
    shipped = load_sweep(
        write(
            tmp_path,
            "t.toml",
            sweep_text('[vary."solver.gain"]\nvalues = [1.0]', "panda_circle.toml"),
        )
    )
    assert shipped.base_file == scenario_path("panda_circle")


def test_keys_the_base_lacks_and_whole_tables(tmp_path):
    sweep = load_sweep(
        write(
            tmp_path,
            "s.toml",
            sweep_text(
                '[vary."solver.damping"]\nvalues = [0.0, 0.01]\n'
                '[vary."constraints.joint_limits.override.joint2.lower"]\nvalues = [-60.0]\n'
                '[vary."trajectory"]\nvalues = [{ kind = "hold", duration = 0.5 }]\n'
            ),
        )
    )
    scenario = sweep.scenario(sweep.runs[1])
    assert scenario.solver["damping"] == 0.01
    assert scenario.trajectory["kind"] == "hold"
    assert scenario.constraints["joint_limits"]["override"]["joint2"]["lower"] == pytest.approx(
        np.radians(-60.0)
    )


@pytest.mark.parametrize(
    ("vary", "key", "message"),
    [
        (
            '[vary."obstacles.pin.postion"]\nvalues = [[0.7, -0.28, 0.0]]',
            'vary."obstacles.pin.postion"',
            "unknown key path; valid key paths of case_study_both.toml: name, robot.source, "
            "initial.q,",
        ),
        (
            '[vary."solver.gian"]\nvalues = [1.0]',
            'vary."solver.gian"',
            "unknown key path; valid key paths",
        ),
        (
            '[vary."obstacles.peg.position"]\nvalues = [[0.7, -0.28, 0.0]]',
            'vary."obstacles.peg.position"',
            "no obstacle named 'peg'; obstacles: ['pin']",
        ),
        (
            '[vary."solver.gain.x"]\nvalues = [1.0]',
            'vary."solver.gain.x"',
            "solver.gain is a value, not a table",
        ),
        (
            '[vary."solver..gain"]\nvalues = [1.0]',
            'vary."solver..gain"',
            "expected dot-separated key names",
        ),
        (
            '[vary."solver.gain"]\nvalues = [100.0, -1.0]',
            'vary."solver.gain"',
            "the run with solver.gain = -1.0 is not a valid scenario: solver.gain: expected a "
            "number > 0 [1/s], got -1.0",
        ),
        (
            '[vary."obstacles.pin.radius"]\nvalues = [-0.1]',
            'vary."obstacles.pin.radius"',
            "obstacles.pin.radius: expected a number >= 0 [m]",
        ),
        (
            '[vary."solver.gain"]\nvalues = []',
            'vary."solver.gain".values',
            "expected a non-empty list of values",
        ),
        (
            '[vary."solver.gain"]\nvalues = [1.0]\ngrid = { start = 1, stop = 2, num = 2 }',
            'vary."solver.gain"',
            "expected exactly one of values, grid, uniform, got ['values', 'grid']",
        ),
        (
            '[vary."solver.gain"]\ngrid = { start = 1.0, stop = 2.0 }',
            'vary."solver.gain".grid.num',
            "required key is missing",
        ),
        (
            '[vary."solver.gain"]\ngrid = { start = [1.0], stop = 2.0, num = 2 }',
            'vary."solver.gain".grid.stop',
            "expected the same shape as start (1 numbers)",
        ),
        (
            '[vary."solver.gain"]\ngrid = { start = 1.0, stop = 2.0, num = 0 }',
            'vary."solver.gain".grid.num',
            "expected an integer >= 1",
        ),
        (
            '[vary."solver.gain"]\nuniform = { low = 2.0, high = 1.0, samples = 3 }',
            'vary."solver.gain".uniform.high',
            "expected values >= low",
        ),
        (
            '[vary."solver.gain"]\nuniform = { low = 1.0, high = 2.0, samples = 3 }\n'
            '[vary."solver.dt"]\nuniform = { low = 1e-3, high = 2e-3, samples = 4 }',
            "vary",
            'uniform tables vary jointly: expected equal samples, got "solver.gain": 3, '
            '"solver.dt": 4',
        ),
        (
            '[vary."solver.gain"]\nvalues = [1.0]\nsteps = 3',
            'vary."solver.gain".steps',
            "unknown key; valid keys here: values",
        ),
        (
            '[vary."solver.gain"]\ngrid = { start = 1.0, stop = 2.0, num = 1001 }\n'
            '[vary."solver.dt"]\ngrid = { start = 1e-3, stop = 2e-3, num = 1001 }',
            "vary",
            "expected at most 1000000 runs, got 1002001",
        ),
    ],
)
def test_bad_sweep_files_name_the_file_and_key_path(tmp_path, vary, key, message):
    path = write(tmp_path, "bad.toml", sweep_text(vary))
    with pytest.raises(ScenarioError) as info:
        load_sweep(path)
    assert info.value.file == str(path)
    assert info.value.key == key
    assert message in info.value.expected


def test_bad_top_level(tmp_path):
    with pytest.raises(ScenarioError, match=r"base: no scenario file .* and no shipped scenario"):
        load_sweep(
            write(tmp_path, "a.toml", sweep_text('[vary."solver.gain"]\nvalues = [1.0]', "x"))
        )
    with pytest.raises(ScenarioError, match=r"vary: required key is missing"):
        load_sweep(write(tmp_path, "b.toml", 'base = "case_study_both"\n'))
    with pytest.raises(ScenarioError, match=r"vary: expected at least one"):
        load_sweep(write(tmp_path, "c.toml", 'base = "case_study_both"\n[vary]\n'))
    with pytest.raises(ScenarioError, match=r"repeat: unknown key; valid keys here: base, name"):
        load_sweep(
            write(
                tmp_path,
                "d.toml",
                sweep_text('[vary."solver.gain"]\nvalues = [1.0]', head="repeat = 2"),
            )
        )
    with pytest.raises(ScenarioError, match="no such sweep file"):
        load_sweep(tmp_path / "missing.toml")
    # The base's own errors name the base file.
    write(tmp_path, "broken.toml", SHORT_CASE.replace("dt = 0.002", "dt = -1.0"))
    with pytest.raises(ScenarioError) as info:
        load_sweep(
            write(
                tmp_path,
                "e.toml",
                sweep_text('[vary."solver.gain"]\nvalues = [1.0]', "broken.toml"),
            )
        )
    assert info.value.file == str(tmp_path / "broken.toml") and info.value.key == "solver.dt"


def test_keypath_get_substitute_leaves():
    data = tomllib.loads(scenario_path("case_study_both").read_text())
    assert keypath.get(data, "obstacles.pin.position") == [0.7, -0.28, 0.0]
    assert keypath.get(data, "constraints.joint_limits.override.joint3.upper") == -80.0
    changed = keypath.substitute(data, {"obstacles.pin.position": [0.0, 0.0, 0.0]})
    assert changed["obstacles"][0]["position"] == [0.0, 0.0, 0.0]
    assert data["obstacles"][0]["position"] == [0.7, -0.28, 0.0]  # a copy
    assert "obstacles.pin.radius" in keypath.leaves(data)
    assert keypath.from_scenario_key(data, "obstacles[0].radius") == "obstacles.pin.radius"
    with pytest.raises(keypath.KeyPathError, match="not in the base scenario"):
        keypath.get(data, "solver.damping")


# -- one run on a worker, in this process ---------------------------------------------------


def test_run_one_matches_the_api_and_loads_the_robot_once(tmp_path):
    path = write(tmp_path, "short.toml", SHORT_CASE)
    sweep = load_sweep(
        write(tmp_path, "s.toml", obstacle_grid(2, 1).replace("short.toml", str(path)))
    )
    before = robot_loads()
    rows = [run_one(sweep.base_data, str(sweep.base_file), r.run_id, r.params) for r in sweep.runs]
    assert robot_loads() - before <= 1  # cached per worker thread (0 if cached already)
    api = build(sweep.scenario(sweep.runs[1])).execute()
    assert rows[1]["status"] == api.status == "completed"
    assert_within_limits(api, api.robot)
    assert rows[1]["steps"] == api.steps
    assert rows[1]["max_task_error"] == pytest.approx(api.max_task_error, rel=1e-12)
    assert rows[1]["min_obstacle_distance"] == pytest.approx(
        float(np.min(api.min_obstacle_distance)), rel=1e-12
    )
    assert rows[0]["run_id"] == sweep.runs[0].run_id and rows[0]["error"] is None


def test_run_batch_starts_no_run_once_its_time_is_spent(tmp_path):
    path = write(tmp_path, "short.toml", SHORT_CASE)
    sweep = load_sweep(
        write(tmp_path, "s.toml", obstacle_grid(3, 1).replace("short.toml", str(path)))
    )
    runs = [(r.run_id, r.params) for r in sweep.runs]
    first = run_batch(sweep.base_data, str(sweep.base_file), runs, budget_s=0.0)
    assert [row["run_id"] for row in first] == [runs[0][0]]  # at least one run
    rows = run_batch(sweep.base_data, str(sweep.base_file), runs[1:])
    assert [row["run_id"] for row in rows] == [rid for rid, _ in runs[1:]]  # all, in order
    assert {row["status"] for row in [*first, *rows]} == {"completed"}


def test_a_run_that_raises_is_a_row(tmp_path):
    data = tomllib.loads(SHORT_CASE)
    row = run_one(data, str(tmp_path / "short.toml"), "x", {"task.frame": "nope"})
    assert row["status"] == "error"
    assert "frame 'nope' not found" in row["error"] and row["reason"].startswith("ScenarioError")


# -- the store -------------------------------------------------------------------------------


def _manifest(fingerprint: str = "f1") -> dict:
    return {"fingerprint": fingerprint, "parameters": ["a.b", "c"]}


def _row(i: int) -> dict:
    return {
        "run_id": f"id{i}",
        "a.b": [float(i), 1.0],
        "c": "x",
        "status": "completed",
        "steps": i,
        "joint_min": [0.0, 1.0],
        "min_obstacle_distance": None,
    }


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_store_appends_resumes_and_writes_each_id_once(tmp_path, fmt):
    out = tmp_path / "out"
    values = {"a.b": [[0.0, 1.0]], "c": ["x"]}
    store = ResultStore.open(out, _manifest(), values, fmt=fmt)
    assert store.append([_row(0), _row(1)]) == 2
    assert store.append([_row(1), _row(2)]) == 1  # id1 is there already
    again = ResultStore.open(out, _manifest(), values, fmt="auto")
    assert again.fmt == fmt and again.ids == {"id0", "id1", "id2"}
    assert again.append([_row(2)]) == 0
    again.compact()
    rows = read_results(out)
    assert [r["run_id"] for r in rows] == ["id0", "id1", "id2"]
    assert rows[2]["a.b"] == [2.0, 1.0] and rows[2]["c"] == "x" and rows[2]["steps"] == 2
    assert rows[0]["joint_min"] == [0.0, 1.0] and rows[0]["min_obstacle_distance"] is None
    assert read_manifest(out)["format"] == fmt
    # Another sweep into the same folder needs force, which starts over.
    (out / "notes.txt").write_text("mine")
    with pytest.raises(SweepOutputExistsError, match="holds the results of another sweep"):
        ResultStore.open(out, _manifest("f2"), values)
    fresh = ResultStore.open(out, _manifest("f2"), values, force=True)
    assert fresh.ids == set() and (out / "notes.txt").read_text() == "mine"


def test_store_parquet_is_a_dataset_folder_and_survives_an_interrupted_compaction(tmp_path):
    import pyarrow.parquet as pq

    out = tmp_path / "out"
    values = {"a.b": [[0.0, 1.0]], "c": ["x"]}
    store = ResultStore.open(out, _manifest(), values, fmt="parquet")
    for i in range(3):
        store.append([_row(i)])
    assert len(list((out / "results.parquet").glob("part-*.parquet"))) == 3
    assert pq.read_table(out / "results.parquet").num_rows == 3  # any reader sees one table
    # A compaction that wrote its file but died before deleting the parts: duplicates.
    table = pq.read_table(out / "results.parquet")
    pq.write_table(table, out / "results.parquet" / "part-000009-deadbeef.parquet")
    assert [r["run_id"] for r in read_results(out)] == ["id0", "id1", "id2"]
    ResultStore.open(out, _manifest(), values)  # reopening finishes the compaction
    assert len(list((out / "results.parquet").glob("part-*.parquet"))) == 1
    assert pq.read_table(out / "results.parquet").num_rows == 3


def test_store_format_auto_is_parquet(tmp_path):
    out = tmp_path / "out"
    values = {"a.b": [[0.0, 1.0]], "c": ["x"]}
    store = ResultStore.open(out, _manifest(), values)
    assert store.fmt == "parquet" and store.path == out / "results.parquet"
    assert read_manifest(out)["format"] == "parquet" and not (out / "results.csv").exists()
    with pytest.raises(InputError, match="format: expected 'auto', 'parquet' or 'csv'"):
        ResultStore.open(tmp_path / "other", _manifest(), values, fmt="xlsx")
    assert not (tmp_path / "other").exists()


def test_store_csv_cuts_a_partial_last_line(tmp_path):
    out = tmp_path / "out"
    values = {"a.b": [[0.0, 1.0]], "c": ["x"]}
    store = ResultStore.open(out, _manifest(), values, fmt="csv")
    store.append([_row(0)])
    with open(out / "results.csv", "a") as f:
        f.write('id9,"[9.0, 1.0]",')  # a crash in the middle of a row
    reopened = ResultStore.open(out, _manifest(), values)
    assert reopened.ids == {"id0"}
    reopened.append([_row(1)])
    assert [r["run_id"] for r in read_results(out)] == ["id0", "id1"]


def test_non_empty_folder_needs_force(tmp_path, short_sweep, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code = main(["sweep", str(short_sweep(2, 1)), "--out", str(out), "--workers", "1", "--quiet"])
    assert code == 2
    assert "exists already and holds no sweep results" in capsys.readouterr().err


def test_a_full_disk_during_a_sweep_is_an_output_error(tmp_path, short_sweep, capsys, monkeypatch):
    """An OS error writing the results is exit 2 naming the folder, not an internal error."""

    def no_space(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(ResultStore, "append", no_space)
    out = tmp_path / "out"
    code = main(["sweep", str(short_sweep(2, 1)), "--out", str(out), "--workers", "1", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"cannot write output {out}: No space left on device (ENOSPC)" in err, err


def test_cli_names_the_bad_key_path(tmp_path, capsys):
    path = write(tmp_path, "bad.toml", sweep_text('[vary."solver.gian"]\nvalues = [1.0]'))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f'{path}: vary."solver.gian": unknown key path; valid key paths' in err
    assert not (tmp_path / "out").exists()


# -- the progress bar ------------------------------------------------------------------------


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_shows_counts_failures_rate_and_notes():
    stream = Terminal()
    bar = RunProgress("sweep", 3, stream=stream, interval=0.0)
    assert bar.enabled  # a terminal: drawn by default
    bar.update()
    bar.update(1, failed=1)
    bar.note("stopping: finishing the runs submitted")
    bar.update()
    bar.close()
    assert (bar.done, bar.failed) == (3, 1)
    text = stream.getvalue()
    # The note replaces the bar's line (cleared), then the bar is drawn again below it.
    before, note, after = text.partition("\rsweep: stopping: finishing the runs submitted\n")
    assert note and before.rstrip(" ").endswith("\r") and after.startswith("\rsweep:  67%")
    last = text.rstrip("\n").rsplit("\r", 1)[-1]
    assert last.startswith("sweep: 100%") and "3/3 [" in last
    assert "runs/s, 1 failed]" in last
    assert text.endswith("\n")
    assert "sweep: 100%" in bar.line() and "3/3" in bar.line() and "1 failed" in bar.line()


def test_progress_bar_counts_points_and_ends_its_line_when_interrupted():
    stream = Terminal()
    bar = RunProgress(
        "reach", 128, stream=stream, interval=0.0, unit="points", failed_label="unreachable"
    )
    bar.update(64, failed=10)
    bar.close()  # stopped before the total
    last = stream.getvalue().rstrip("\n").rsplit("\r", 1)[-1]
    assert last.startswith("reach:  50%") and "64/128 [" in last
    assert "points/s, 10 unreachable]" in last
    assert stream.getvalue().endswith("\n")


def test_progress_bar_is_silent_off_a_terminal_or_when_disabled():
    for bar in (
        RunProgress("sweep", 2, stream=io.StringIO()),  # not a terminal
        RunProgress("sweep", 2, enabled=False, stream=Terminal()),  # --quiet
    ):
        assert not bar.enabled
        bar.update(1, failed=1)
        bar.note("stopping")
        bar.update(1)
        bar.close()
        assert (bar.done, bar.failed) == (2, 1)  # still counted
        assert bar.stream.getvalue() == ""
        assert "2/2" in bar.line() and "1 failed" in bar.line()


# -- a local cluster in this process ----------------------------------------------------------


@pytest.fixture(scope="module")
def local_client():
    from clik.sweep.cluster import dask_client

    with dask_client(workers=2) as client:
        client.wait_for_workers(2, timeout=60)
        yield client


def test_local_cluster_sweep_with_trajectories_errors_and_csv(tmp_path, local_client):
    write(tmp_path, "short.toml", SHORT_CASE)
    path = write(
        tmp_path,
        "s.toml",
        'base = "short.toml"\n[vary."obstacles.pin.position"]\n'
        "values = [[0.7, -0.28, 0.0], [0.66, -0.3, 0.0]]\n"
        '[vary."trajectory.goal"]\nvalues = [[0.8, -0.2, 0.0], [9.0, 0.0, 0.0]]\n',
    )
    out = tmp_path / "out"
    report = run_sweep(path, out, client=local_client, keep_trajectories=True, fmt="csv")
    assert report.complete and report.computed == 4 and report.skipped == 0
    rows = {
        (tuple(r["obstacles.pin.position"]), tuple(r["trajectory.goal"])): r
        for r in read_results(out)
    }
    assert len(rows) == 4 and (out / "results.csv").is_file()
    bad = rows[(0.7, -0.28, 0.0), (9.0, 0.0, 0.0)]
    assert bad["status"] == "error" and "trajectory" in bad["error"]  # recorded, sweep went on
    good = rows[(0.7, -0.28, 0.0), (0.8, -0.2, 0.0)]
    assert good["status"] == "completed" and good["error"] is None
    folder = out / "runs" / good["run_id"]
    summary = json.loads((folder / "summary.json").read_text())
    assert_summary_within_limits(summary, clik.Robot.load("planar4r"))
    assert summary["max_task_error"] == pytest.approx(good["max_task_error"], rel=1e-12)
    with np.load(folder / "trajectory.npz") as npz:
        assert npz["q"].shape == (good["steps"], 4)
    assert not (out / "runs" / bad["run_id"]).exists()
    statuses = Counter(r["status"] for r in rows.values())
    assert report.all_statuses == statuses and statuses["error"] == 2 and report.failed == 2
    # Everything is there: a rerun computes nothing and starts no task.
    again = run_sweep(path, out, client=local_client)
    assert again.skipped == 4 and again.computed == 0
    assert again.all_statuses == statuses and again.failed == 2  # read back from the CSV


def test_sweep_progress_bar_goes_to_stderr(tmp_path, short_sweep, local_client, capsys):
    report = run_sweep(short_sweep(2, 1), tmp_path / "out", client=local_client, progress=True)
    assert report.computed == 2
    printed = capsys.readouterr()
    last = printed.err.rstrip("\n").rsplit("\r", 1)[-1]
    assert last.startswith("sweep: 100%") and "2/2 [" in last and "0 failed]" in last
    assert printed.out == ""
    again = run_sweep(short_sweep(2, 2), tmp_path / "quiet", client=local_client)
    assert again.computed == 4 and capsys.readouterr().err == ""  # not a terminal: no bar


def test_workers_load_the_robot_once(tmp_path, short_sweep, local_client):
    report = run_sweep(short_sweep(4, 3), tmp_path / "out", client=local_client)
    assert report.computed == 12
    loads = local_client.run(robot_loads)
    assert set(loads.values()) <= {0, 1}, loads  # one robot per worker, whatever the runs


def test_batch_size_follows_the_runs_left_and_is_bounded_in_time():
    from clik.sweep.session import MAX_BATCH, batch_size

    assert batch_size(120, 2, None) == 30  # a quarter of what is left, on 2 threads
    assert batch_size(10_000, 2, None) == MAX_BATCH  # no run timed yet: the worker's budget
    assert batch_size(116, 2, 0.006) == 29
    assert batch_size(20, 2, 0.006) == 9  # at least 0.05 s of work: worth a task
    assert batch_size(5, 2, 0.006) == 5  # never more than is left
    assert batch_size(10_000, 2, 0.001) == MAX_BATCH
    assert batch_size(10_000, 2, 0.1) == 5  # at most 0.5 s of work: Ctrl-C and progress
    assert batch_size(10_000, 2, 3.0) == 1  # long runs: one per task
    # A whole sweep: batches shrink to the end, and every thread gets several.
    sizes, left = [], 120
    while left:
        sizes.append(batch_size(left, 2, 0.006))
        left -= sizes[-1]
    assert sizes == sorted(sizes, reverse=True) and len(sizes) >= 4 * 2
    assert sizes[0] == 120 // 4 and max(sizes[-3:]) <= 9


def test_short_runs_go_in_batches_with_the_rows_of_single_runs(tmp_path, local_client, monkeypatch):
    """The compiled engine runs the case study in milliseconds: a task computes several."""
    from clik.sweep import execute

    path = write(
        tmp_path,
        "s.toml",
        'base = "case_study_both"\n[vary."obstacles.pin.position"]\n'
        "uniform = { low = [0.66, -0.32, 0.0], high = [0.74, -0.24, 0.0], samples = 24 }\n",
    )
    sweep = load_sweep(path)
    batches: list[int] = []

    class Counting(execute.SweepSession):
        def next_batch(self):
            batch = super().next_batch()
            if batch:
                batches.append(len(batch))
            return batch

    monkeypatch.setattr(execute, "SweepSession", Counting)
    report = run_sweep(sweep, tmp_path / "out", client=local_client, progress=False)
    assert report.complete and report.computed == 24 and sum(batches) >= 24
    assert len(batches) < 24 and max(batches) > 1, batches
    rows = {r["run_id"]: r for r in read_results(tmp_path / "out")}
    for run in sweep.runs[::7]:  # the same row as the run alone, in this process
        alone = run_one(sweep.base_data, str(sweep.base_file), run.run_id, run.params)
        row = rows[run.run_id]
        assert row["obstacles.pin.position"] == run.params["obstacles.pin.position"]
        assert (row["status"], row["steps"]) == (alone["status"], alone["steps"])
        assert row["max_task_error"] == pytest.approx(alone["max_task_error"], rel=1e-12)


def test_a_failed_batch_is_retried_run_by_run(tmp_path, short_sweep, local_client, monkeypatch):
    """A task that fails (unlike a run that raises, which is a row) fails its whole batch:
    its runs go again one per task, and only the one that fails its task is an error."""
    from clik.sweep import session

    sweep = load_sweep(short_sweep(4, 2))
    culprit = sweep.runs[5].run_id
    monkeypatch.setattr(session, "batch_size", lambda remaining, threads, seconds: 4)

    def poison(run_id: str) -> None:
        from clik.sweep import worker

        real = worker.run_one

        def run_one(base_data, base_file, rid, params, keep=False):
            if rid == run_id:
                raise RuntimeError(f"poisoned {rid}")  # escapes run_batch: the task fails
            return real(base_data, base_file, rid, params, keep)

        worker._real_run_one = real
        worker.run_one = run_one

    def cure() -> None:
        from clik.sweep import worker

        worker.run_one = worker.__dict__.pop("_real_run_one", worker.run_one)

    local_client.run(poison, culprit)
    try:
        report = run_sweep(sweep, tmp_path / "out", client=local_client)
    finally:
        local_client.run(cure)
    rows = {r["run_id"]: r for r in read_results(tmp_path / "out")}
    assert report.complete and set(rows) == {r.run_id for r in sweep.runs}
    assert rows[culprit]["status"] == "error"
    assert rows[culprit]["error"] == f"RuntimeError: poisoned {culprit}"
    assert Counter(r["status"] for r in rows.values()) == {"completed": 7, "error": 1}
    assert report.statuses == {"completed": 7, "error": 1} and report.failed == 1


def test_local_workers_do_not_profile(local_client):
    import dask.config

    flags = local_client.run(lambda: dask.config.get("distributed.worker.profile.enabled"))
    assert set(flags.values()) == {False}
    sizes = local_client.run(lambda: dask.config.get("distributed.worker.memory.target"))
    assert set(sizes.values()) == {dask.config.get("distributed.worker.memory.target")}


def test_status_line_and_what_fails_a_sweep(tmp_path):
    from clik.sweep.report import FAILED_STATUSES, SweepReport, status_line

    assert FAILED_STATUSES == {"violated", "velocity_limit", "off_track", "diverged"}
    counts = Counter({"violated": 1, "completed": 118, "deadlock": 1})
    assert status_line(counts) == "completed 118, deadlock 1, violated 1, raised 0"
    assert status_line(Counter({"error": 2, "diverged": 1})) == "diverged 1, raised 2"
    assert status_line(Counter()) == "raised 0"

    def failed(**statuses: int) -> int:
        return SweepReport(tmp_path, tmp_path, 0, 0, all_statuses=Counter(statuses)).failed

    assert failed(completed=5, deadlock=2) == 0
    assert failed(completed=5, violated=1) == 1
    assert failed(completed=5, diverged=2) == 2
    assert failed(completed=5, error=1, violated=1, diverged=1) == 3


def test_cli_exits_1_when_a_run_raised_or_diverged(tmp_path, local_client, capsys):
    """Four runs: completed, raised (unreachable goal), diverged (gain 1e6), raised."""
    write(tmp_path, "short.toml", SHORT_CASE)
    path = write(
        tmp_path,
        "s.toml",
        'base = "short.toml"\n[vary."solver.gain"]\nvalues = [400.0, 1e6]\n'
        '[vary."trajectory.goal"]\nvalues = [[0.8, -0.2, 0.0], [9.0, 0.0, 0.0]]\n',
    )
    out = tmp_path / "out"
    command = ["sweep", str(path), "--out", str(out), "--scheduler", local_client.scheduler.address]
    assert main(command) == 1
    printed = capsys.readouterr()
    assert printed.out.splitlines()[-1] == "completed 1, diverged 1, raised 2"
    assert "3 of 4 runs failed (completed 1, diverged 1, raised 2)" in printed.err
    statuses = Counter(r["status"] for r in read_results(out))
    assert statuses == {"completed": 1, "diverged": 1, "error": 2}  # every row written
    # Resuming a finished sweep computes nothing and still fails: it counts the folder.
    assert main([*command, "--quiet"]) == 1
    printed = capsys.readouterr()
    assert printed.out == "" and "3 of 4 runs failed" in printed.err


def test_cli_exits_0_when_no_run_failed(tmp_path, local_client, capsys):
    write(tmp_path, "short.toml", SHORT_CASE)
    vary = '[vary."solver.gain"]\nvalues = [300.0, 400.0]\n'
    path = write(tmp_path, "s.toml", f'base = "short.toml"\n{vary}')
    out = tmp_path / "out"
    command = ["sweep", str(path), "--out", str(out), "--scheduler", local_client.scheduler.address]
    assert main(command) == 0
    printed = capsys.readouterr()
    assert printed.out.splitlines()[-1] == "completed 2, raised 0"
    assert "failed" not in printed.err
    assert main([*command, "--quiet"]) == 0  # resumed: the same folder, the same verdict
    assert capsys.readouterr().out == ""


# -- real processes: a scheduler and workers, and the CLI --------------------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop(process: subprocess.Popen) -> None:
    """Stop a process started with its own session, and anything it started."""
    if process.poll() is None:
        try:
            os.killpg(process.pid, signal.SIGTERM)
            process.wait(timeout=10)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            pass
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait(timeout=10)


@contextmanager
def dask_processes(workers: int, env: dict[str, str]) -> Iterator[tuple[str, list]]:
    """A ``dask scheduler`` and ``workers`` ``dask worker`` processes on 127.0.0.1."""
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    started: list[subprocess.Popen] = []
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "start_new_session": True}
    try:
        started.append(
            subprocess.Popen(
                [
                    PYTHON,
                    "-m",
                    "distributed.cli.dask_scheduler",
                    *f"--host 127.0.0.1 --port {port} --no-dashboard".split(),
                ],
                env=env,
                **quiet,
            )
        )
        for i in range(workers):
            started.append(
                subprocess.Popen(
                    [
                        PYTHON,
                        "-m",
                        "distributed.cli.dask_worker",
                        address,
                        *"--host 127.0.0.1 --nworkers 1 --nthreads 1 --no-nanny --no-dashboard"
                        f" --death-timeout {STARTUP:.0f}".split(),
                        "--name",
                        f"w{i}",
                    ],
                    env=env,
                    **quiet,
                )
            )
        with distributed.Client(address, timeout=f"{STARTUP:.0f}s", set_as_default=False) as c:
            c.wait_for_workers(workers, timeout=STARTUP)
        yield address, started[1:]
    finally:
        for process in reversed(started):
            stop(process)


def traced(folder: Path) -> Counter:
    """Run ids computed, with how many times (the workers' CLIK_SWEEP_TRACE logs)."""
    ids: Counter = Counter()
    for log in folder.glob("*.log"):
        ids.update(log.read_text().split())
    return ids


def wait_until(
    condition, timeout: float, process: subprocess.Popen | None = None, what: str = "condition"
) -> None:
    """Poll ``condition`` until it holds; fail after ``timeout`` [s] or if ``process`` ends."""
    deadline = time.monotonic() + timeout
    while not condition():
        if process is not None and process.poll() is not None:
            raise AssertionError(f"the sweep ended early ({process.returncode}) waiting for {what}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(0.05)


def lines(path: Path) -> int:
    """Run ids in one worker's trace log (0 before its first run ends)."""
    try:
        return len(path.read_text().split())
    except FileNotFoundError:
        return 0


def env_with(**extra: str) -> dict[str, str]:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env.update(extra)
    return env


@pytest.mark.slow
def test_a_dead_worker_loses_no_run(tmp_path, short_sweep):
    """80 runs on a scheduler and two workers; one worker is killed midway.

    The kill waits on conditions, not on time (both workers have computed runs,
    a quarter of the runs are done), so a slow machine only makes it later;
    every wait is bounded (:data:`TIMEOUT`).
    """
    sweep = short_sweep(10, 8)
    expected = {r.run_id for r in load_sweep(sweep).runs}
    assert len(expected) == 80
    out, trace = tmp_path / "out", tmp_path / "trace"
    env = env_with(**{TRACE_ENV: str(trace)})
    with dask_processes(2, env) as (address, workers):
        # No nanny: each worker runs in its `dask worker` process, which names its trace log.
        victim, survivor = (trace / f"{w.pid}.log" for w in workers)
        cli = subprocess.Popen(
            [*CLIK, "sweep", str(sweep), "--out", str(out), "--scheduler", address, "--quiet"],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        try:
            wait_until(
                lambda: (
                    lines(victim) >= 5
                    and lines(survivor) >= 5
                    and sum(traced(trace).values()) >= len(expected) // 4
                ),
                TIMEOUT,
                cli,
                "both workers to compute 5 runs and a quarter of the sweep to be done",
            )
            workers[0].send_signal(signal.SIGKILL)  # no nanny: the worker is gone
            workers[0].wait(timeout=30)
            before, before_survivor = traced(trace), lines(survivor)  # the victim's log is final
            _, err = cli.communicate(timeout=TIMEOUT)
        finally:
            stop(cli)
        assert cli.returncode == 0, err.decode()
    assert len(before) < len(expected)  # killed midway: runs were left to compute
    rows = read_results(out)
    ids = Counter(r["run_id"] for r in rows)
    assert set(ids) == expected
    assert max(ids.values()) == 1  # exactly once
    import pyarrow.parquet as pq

    raw = pq.read_table(out / "results.parquet").column("run_id").to_pylist()
    assert sorted(raw) == sorted(expected)  # on disk too, after the compaction
    statuses = Counter(r["status"] for r in rows)
    assert statuses["error"] == 0, statuses
    assert len({r["worker"] for r in rows}) == 2  # both workers wrote rows before the kill
    computed = traced(trace)
    assert set(computed) == expected  # and each run was computed at least once
    assert lines(survivor) > before_survivor  # the survivor computed what was left


@pytest.mark.slow
def test_an_interrupted_sweep_resumes_without_computing_a_run_twice(tmp_path, short_sweep):
    """Ctrl-C a `clik sweep --workers 2` once rows are on disk; rerun; count computations."""
    sweep = short_sweep(10, 8)
    out, first, second = tmp_path / "out", tmp_path / "trace1", tmp_path / "trace2"
    command = [*CLIK, "sweep", str(sweep), "--out", str(out), "--workers", "2", "--quiet"]
    cli = subprocess.Popen(
        command,
        env=env_with(**{TRACE_ENV: str(first)}),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        parts = out / "results.parquet"
        wait_until(lambda: parts.is_dir() and any(parts.glob("part-*.parquet")), TIMEOUT, cli)
        cli.send_signal(signal.SIGINT)  # the CLI only, as a terminal's Ctrl-C would
        _, err = cli.communicate(timeout=TIMEOUT)
    finally:
        stop(cli)
    assert cli.returncode == 130, err.decode()
    assert "run the same command again" in err.decode()
    expected = {r.run_id for r in load_sweep(sweep).runs}
    kept = {r["run_id"] for r in read_results(out)}
    assert 0 < len(kept) < len(expected)
    assert kept <= set(traced(first))

    rerun = subprocess.run(
        command, env=env_with(**{TRACE_ENV: str(second)}), capture_output=True, timeout=TIMEOUT
    )
    assert rerun.returncode == 0, rerun.stderr.decode()
    again = traced(second)
    assert not kept & set(again)  # nothing written before was computed again
    assert set(again) == expected - kept and max(again.values()) == 1  # the others, once each
    ids = Counter(r["run_id"] for r in read_results(out))
    assert set(ids) == expected and max(ids.values()) == 1
    # The first session finished its running runs before it stopped: all it computed is kept.
    assert set(traced(first)) == kept and max(traced(first).values()) == 1
