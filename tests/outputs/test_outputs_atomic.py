"""Outputs are all-or-nothing: the ``--out`` folder is replaced whole, under a lock.

- Ctrl-C or SIGTERM during a ``--force`` rerun of ``clik solve`` leaves the old
  folder byte-identical and no temporary folder (:mod:`clik.outputs.out_folder`).
- ``--force`` removes the files of an earlier run (a stale ``scene.html``).
- Two runs into one ``--out``: one succeeds, the other is refused at once
  (``OutputLockedError``); a sweep takes the same lock.
- OS errors on the output (a dangling symbolic link, a file as a parent, a full
  disk) are ``OutputError`` (exit 2) naming the path and the reason.
- A summary value that is not finite is written as ``null``, listed under
  ``non_finite``; ``clik robots`` into a closed pipe stops quietly.

Every subprocess runs under a timeout and the module under ``pytest-timeout``:
a hang fails its test, not the suite.
"""

from __future__ import annotations

import errno
import json
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import clik
import clik.demo
from clik.cli import BROKEN_PIPE, main
from clik.errors import OutputError, OutputLockedError
from clik.model.robot import Robot
from clik.outputs.out_folder import output_lock
from clik.outputs.result import write_outputs
from clik.scenarios import scenario_path
from tests.limits_check import assert_summary_within_limits

pytestmark = pytest.mark.timeout(240)

QUICK = str(scenario_path("case_study_unconstrained"))
"""A run of about a second (3 s of trajectory at dt = 1 ms)."""

PROC_TIMEOUT = 120.0
"""Longest wait for a ``clik`` subprocess [s]."""


def scenario_of_duration(tmp_path: Path, duration: float) -> Path:
    """The unconstrained case study stretched to ``duration`` [s] of trajectory."""
    text = Path(QUICK).read_text()
    text = text.replace("duration = 3.0\ncruise_speed = 0.12", f"duration = {duration}")
    path = tmp_path / f"long_{duration:g}.toml"
    path.write_text(text)
    return path


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` by relative path, with its bytes."""
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def leftovers(out: Path) -> list[str]:
    """Hidden siblings of ``out`` left by a run: temporary, old or lock files."""
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


def start_solve(scenario: Path, out: Path, *flags: str) -> subprocess.Popen:
    """``clik solve`` in a subprocess; returns once its run has started (temporary folder made)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "clik.cli", "solve", str(scenario), "--out", str(out), *flags],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C reaches it as from a terminal even where this test runs with SIGINT
        # ignored (a shell's background job): the child would inherit SIG_IGN.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    work = out.parent / f".{out.name}.tmp-{proc.pid}"
    deadline = time.monotonic() + PROC_TIMEOUT
    while not work.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    time.sleep(0.3)
    if proc.poll() is not None or not work.exists():
        proc.kill()
        pytest.fail(f"the run did not start: {proc.communicate(timeout=PROC_TIMEOUT)}")
    return proc


def first_run(tmp_path: Path) -> tuple[Path, dict[str, bytes]]:
    """A finished ``clik solve`` into ``tmp_path/out``, and its files."""
    out = tmp_path / "out"
    assert main(["solve", QUICK, "--out", str(out), "--quiet"]) == 0
    return out, snapshot(out)


def check_completed(out: Path) -> None:
    """``out`` holds a ``completed`` run whose joints and distances stayed in their limits."""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed", summary["reason"]
    assert_summary_within_limits(summary, Robot.load("planar4r"))


@pytest.mark.parametrize(
    ("sig", "code", "word"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")],
    ids=["ctrl-c", "sigterm"],
)
def test_a_stopped_force_rerun_leaves_the_old_folder_byte_identical(tmp_path, sig, code, word):
    out, before = first_run(tmp_path)
    (out / "mine.txt").write_text("kept")
    before = snapshot(out)
    proc = start_solve(scenario_of_duration(tmp_path, 600.0), out, "--force")
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=PROC_TIMEOUT)
    assert proc.returncode == code, err
    assert f"clik: {word}" in err and "Traceback" not in err
    assert snapshot(out) == before
    assert leftovers(out) == []


def test_force_replaces_the_folder_whole(tmp_path):
    out, _ = first_run(tmp_path)
    (out / "scene.html").write_text("<html>another scenario</html>")
    (out / "sub").mkdir()
    (out / "sub" / "old.csv").write_text("1,2")
    assert main(["solve", QUICK, "--out", str(out), "--quiet", "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["summary.json", "trajectory.npz"]
    assert leftovers(out) == []
    check_completed(out)


def test_two_runs_into_one_folder_one_succeeds_the_other_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    proc = start_solve(scenario_of_duration(tmp_path, 200.0), out, "--quiet")
    for flags in ([], ["--force"]):
        assert main(["solve", QUICK, "--out", str(out), "--quiet", *flags]) == 2
        err = capsys.readouterr().err
        assert "another clik run is writing there" in err and str(out) in err, err
    _, err = proc.communicate(timeout=PROC_TIMEOUT)
    assert proc.returncode == 0, err
    check_completed(out)
    assert leftovers(out) == []


def test_a_held_lock_refuses_solve_demo_reach_and_sweep(tmp_path, capsys):
    from clik.sweep import parse_sweep, run_sweep

    out = tmp_path / "out"
    with output_lock(out) as lock:
        assert lock.exists()
        assert main(["solve", QUICK, "--out", str(out), "--quiet"]) == 2
        assert "another clik run is writing there" in capsys.readouterr().err
        with pytest.raises(OutputLockedError, match="another clik run"):
            clik.demo.run_demo(out, quiet=True, html=False, plots=False, names=())
        data = {"name": "s", "base": QUICK, "vary": {"solver.gain": {"values": [500.0]}}}
        sweep = parse_sweep(data, tmp_path / "s.toml")
        with pytest.raises(OutputLockedError, match=str(out)):
            run_sweep(sweep, out, workers=1, progress=False)
    assert not lock.exists()
    assert not out.exists() or list(out.iterdir()) == []


def test_a_dangling_symlink_as_out_is_an_output_error(tmp_path, capsys):
    out = tmp_path / "out"
    out.symlink_to(tmp_path / "nowhere")
    assert main(["solve", QUICK, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"cannot write output {out}: a dangling symbolic link" in err
    assert "internal error" not in err and not (tmp_path / "nowhere").exists()


def test_a_symlink_to_a_folder_is_followed(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    out = tmp_path / "out"
    out.symlink_to(real)
    assert main(["solve", QUICK, "--out", str(out), "--quiet"]) == 0
    assert out.is_symlink() and (real / "summary.json").exists()
    check_completed(real)


def test_a_file_as_parent_is_an_output_error(tmp_path, capsys):
    (tmp_path / "afile").write_text("mine")
    out = tmp_path / "afile" / "sub"
    assert main(["solve", QUICK, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"cannot write output {out}: {tmp_path / 'afile'} is a file" in err
    assert "ENOTDIR" in err and (tmp_path / "afile").read_text() == "mine"


@pytest.mark.parametrize("failing", ["npz", "summary"])
def test_a_full_disk_during_a_force_rerun_is_an_output_error(
    tmp_path, capsys, monkeypatch, failing
):
    out, before = first_run(tmp_path)
    full = OSError(errno.ENOSPC, "No space left on device")

    def no_space(*args, **kwargs):
        raise full

    if failing == "npz":
        monkeypatch.setattr(clik.outputs.result.TrackingResult, "save", no_space)
    else:
        monkeypatch.setattr(clik.outputs.result, "atomic_write", no_space)
    assert main(["solve", QUICK, "--out", str(out), "--quiet", "--force"]) == 2
    err = capsys.readouterr().err
    assert f"cannot write output {out}: No space left on device (ENOSPC)" in err, err
    assert snapshot(out) == before
    assert leftovers(out) == []


def test_an_output_error_keeps_its_fields():
    error = OutputError("/x/out", "No space left on device (ENOSPC)")
    assert isinstance(error, clik.ClikError) and isinstance(error, OSError)
    assert (error.path, error.exit_code) == ("/x/out", 2)
    assert str(error) == "cannot write output /x/out: No space left on device (ENOSPC)"


def test_a_summary_value_that_is_not_finite_is_written_as_null(tmp_path, planar4r):
    from clik.trajectory import Hold

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    result = clik.track(task, Hold(position=[0.0, 1.2, 0.0], duration=0.05), gain=500.0)
    result.info["summary_extra"] = {"min_obstacle_distance": math.inf, "spread": [1.0, -math.nan]}
    summary = write_outputs(result, tmp_path)
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written == summary
    assert written["min_obstacle_distance"] is None and written["spread"] == [1.0, None]
    assert written["non_finite"] == ["min_obstacle_distance", "spread[1]"]
    assert written["status"] == result.status == "completed"
    assert_summary_within_limits(written, planar4r)
    assert (tmp_path / "trajectory.npz").exists()


def test_a_summary_that_cannot_be_written_leaves_no_trajectory(tmp_path, planar4r, monkeypatch):
    from clik.trajectory import Hold

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    result = clik.track(task, Hold(position=[0.0, 1.2, 0.0], duration=0.05), gain=500.0)
    calls = []
    real = clik.outputs.result.atomic_write

    def full_on_summary(path, write, mode="wb"):
        calls.append(path.name)
        if path.name == "summary.json":
            raise OSError(errno.ENOSPC, "No space left on device")
        real(path, write, mode)

    (tmp_path / "summary.json").write_text("{}")  # an earlier run's
    monkeypatch.setattr(clik.outputs.result, "atomic_write", full_on_summary)
    with pytest.raises(OSError, match="No space"):
        write_outputs(result, tmp_path)
    assert calls == ["trajectory.npz", "summary.json"]
    assert list(tmp_path.iterdir()) == []


def test_a_closed_stdout_stops_quietly():
    proc = subprocess.Popen(
        [sys.executable, "-m", "clik.cli", "robots"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    proc.stdout.close()  # the reader is gone before clik writes: like `clik robots | head -0`
    _, err = proc.communicate(timeout=PROC_TIMEOUT)
    assert proc.returncode in (0, BROKEN_PIPE), err
    assert "internal error" not in err and "Traceback" not in err and "Exception" not in err


def test_robots_piped_into_head_prints_no_internal_error():
    proc = subprocess.run(
        f"{sys.executable} -m clik.cli robots | head -1",
        shell=True,
        capture_output=True,
        text=True,
        timeout=PROC_TIMEOUT,
    )
    assert proc.returncode == 0 and len(proc.stdout.splitlines()) == 1
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
