"""Sweeps as users write them (issue 27): a plain list of values, and a table reader.

``[vary] "solver.gain" = [500.0, 1000.0]`` reads as ``values``; anything else that is
not a table names ``values``; ``clik sweep --table DIR`` prints the results (Parquet
or CSV) as CSV without pandas.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from clik import ScenarioError
from clik.cli import main
from clik.sweep import load_sweep
from clik.sweep.store import ResultStore
from clik.sweep.table import results_csv


def _write(folder: Path, text: str) -> Path:
    path = folder / "sweep.toml"
    path.write_text(text)
    return path


def test_a_plain_list_is_read_as_values(tmp_path):
    plain = load_sweep(
        _write(tmp_path, 'base = "case_study_both"\n[vary]\n"solver.gain" = [500.0, 1000.0]\n')
    )
    table = load_sweep(
        _write(
            tmp_path, 'base = "case_study_both"\n[vary."solver.gain"]\nvalues = [500.0, 1000.0]\n'
        )
    )
    assert [r.params for r in plain.runs] == [{"solver.gain": 500.0}, {"solver.gain": 1000.0}]
    assert [r.run_id for r in plain.runs] == [r.run_id for r in table.runs]
    assert plain.vary[0].kind == "values"
    assert plain.scenario(plain.runs[1]).solver["gain"] == 1000.0


def test_a_scalar_names_values(tmp_path):
    path = _write(tmp_path, 'base = "case_study_both"\n[vary]\n"solver.gain" = 500.0\n')
    with pytest.raises(ScenarioError) as info:
        load_sweep(path)
    message = str(info.value)
    assert 'vary."solver.gain"' in message
    assert "expected a list of values, or a table with one of values, grid, uniform" in message


def test_an_empty_plain_list_is_refused(tmp_path):
    path = _write(tmp_path, 'base = "case_study_both"\n[vary]\n"solver.gain" = []\n')
    with pytest.raises(ScenarioError, match="a non-empty list of values"):
        load_sweep(path)


def _store(out: Path, fmt: str) -> None:
    manifest = {"fingerprint": "f1", "parameters": ["a.b", "c"]}
    store = ResultStore.open(out, manifest, {"a.b": [[0.0, 1.0]], "c": ["x"]}, fmt=fmt)
    store.append(
        [
            {"run_id": f"id{i}", "a.b": [float(i), 1.0], "c": "x", "status": status}
            | {"steps": i, "min_obstacle_distance": None}
            for i, status in enumerate(("completed", "deadlock"))
        ]
    )
    store.compact()


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_sweep_table_prints_the_results_without_pandas(tmp_path, capsys, fmt):
    out = tmp_path / "out"
    _store(out, fmt)
    assert (out / ("results.parquet" if fmt == "parquet" else "results.csv")).exists()
    assert main(["sweep", "--table", str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed == results_csv(out)
    rows = list(csv.DictReader(io.StringIO(printed)))
    assert [r["run_id"] for r in rows] == ["id0", "id1"]
    assert [r["status"] for r in rows] == ["completed", "deadlock"]
    assert rows[1]["a.b"] == "[1.0, 1.0]" and rows[1]["steps"] == "1"
    assert rows[0]["min_obstacle_distance"] == ""  # missing: empty


def test_sweep_table_of_a_folder_that_is_no_sweep(tmp_path, capsys):
    assert main(["sweep", "--table", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clik: error: --table: expected a sweep's output folder (its --out)")


def test_sweep_without_a_file_or_out_names_the_missing_argument(tmp_path, capsys):
    assert main(["sweep"]) == 2
    assert "clik: error: sweep: expected a sweep file (or --table DIR" in capsys.readouterr().err
    assert main(["sweep", str(tmp_path / "s.toml")]) == 2
    assert "clik: error: --out: expected an output folder" in capsys.readouterr().err
