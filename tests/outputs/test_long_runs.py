"""Long runs and outputs: a million steps in bounded memory; outputs written atomically.

- A 10^6-step run of the planar arm with ``record_every=1000`` completes, keeps
  1001 samples and its exact scalars, and its memory stays bounded: the peak
  resident size of the process grows by less than 50 MB (measured in a new
  process, whose peak is its own).
- ``atomic_write`` (used by ``result.save``, ``write_json`` and so by
  ``clik solve``) leaves the old file or none, never a truncated one: when the
  writer fails, when the process is killed in the middle of a write, and when
  the command is killed or interrupted (Ctrl-C) in the middle of a run.

Covered elsewhere, not repeated here: an existing output folder needs
``--force`` (``tests/cli/test_cli.py``); Meshcat servers stop with their parent
and listen on loopback only (``tests/viz/test_viz.py``).
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.cli import main
from clik.outputs.io import atomic_write, write_json
from clik.outputs.result import TrackingResult
from clik.scenarios import scenario_path

STEPS = 1_000_000
RECORD_EVERY = 1000
RSS_GROWTH_MB = 50.0
WALL_S = 40.0

LONG_RUN = textwrap.dedent(
    f"""
    import json, resource, time
    import numpy as np
    import clik
    from clik.trajectory import Line

    def peak_mb():  # this process's own peak: VmHWM starts anew at exec, while ru_maxrss
        # keeps the high-water mark of the (large) pytest process this one was forked from
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux

    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    clik.track(task, Line(p0, [0.8, -0.2, 0.0], duration=1.0), q0=q0, record_every=10)  # warm up
    before = peak_mb()
    line = Line(p0, [0.8, -0.2, 0.0], duration={(STEPS - 1) * 1e-3})
    start = time.perf_counter()
    result = clik.track(task, line, q0=q0, dt=1e-3, record_every={RECORD_EVERY})
    wall = time.perf_counter() - start
    print(json.dumps({{
        "status": result.status, "steps": result.steps, "samples": len(result.t),
        "violations": result.violations,
        "joint_min": result.joint_min.tolist(), "joint_max": result.joint_max.tolist(),
        "t_step": float(np.diff(result.t).max()), "last_t": float(result.t[-1]),
        "max_task_error": result.max_task_error, "final_task_error": result.final_task_error,
        "recorded_max_error": float(result.task_error_norm.max()),
        "growth_mb": peak_mb() - before, "wall_s": wall,
    }}))
    """
)


@pytest.fixture(scope="module")
def long_run() -> dict:
    """The 10^6-step run, in its own process (its peak memory is its own)."""
    proc = subprocess.run(
        [sys.executable, "-c", LONG_RUN], capture_output=True, text=True, check=True, timeout=600
    )
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_million_steps_complete_with_decimated_recording(long_run):
    assert long_run["status"] == "completed" and long_run["violations"] == []
    robot = clik.Robot.load("planar4r")  # every step's joints inside the URDF limits
    assert np.all(np.asarray(long_run["joint_min"]) >= robot.lower)
    assert np.all(np.asarray(long_run["joint_max"]) <= robot.upper)
    assert long_run["steps"] == STEPS  # N = duration / dt + 1 samples
    assert long_run["samples"] == STEPS // RECORD_EVERY + 1
    assert long_run["t_step"] == pytest.approx(RECORD_EVERY * 1e-3)
    assert long_run["last_t"] == pytest.approx((STEPS - 1) * 1e-3)
    # scalars see every step; a slow line is tracked to a few micrometres by law (9)
    assert long_run["recorded_max_error"] <= long_run["max_task_error"] < 1e-5
    assert long_run["wall_s"] < WALL_S


@pytest.mark.slow
def test_a_million_steps_run_in_bounded_memory(long_run):
    assert long_run["growth_mb"] < RSS_GROWTH_MB


# ------------------------------------------------------------------ atomic outputs


def hidden_leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def half_then_fail(f) -> None:
    f.write(b'{"status": "compl')
    raise RuntimeError("disk full")


def test_a_failed_write_leaves_no_file(tmp_path):
    path = tmp_path / "summary.json"
    with pytest.raises(RuntimeError, match="disk full"):
        atomic_write(path, half_then_fail)
    assert not path.exists()
    assert hidden_leftovers(tmp_path) == []


def test_a_failed_write_keeps_the_old_file(tmp_path):
    path = tmp_path / "summary.json"
    write_json(path, {"status": "completed"})
    with pytest.raises(RuntimeError):
        atomic_write(path, half_then_fail)
    with pytest.raises(ValueError, match="Out of range float values"):
        write_json(path, {"max_task_error": float("nan")})  # JSON has no NaN: refused whole
    assert json.loads(path.read_text()) == {"status": "completed"}
    assert hidden_leftovers(tmp_path) == []


def test_a_failed_save_leaves_no_npz(tmp_path, monkeypatch, planar4r):
    import clik
    from clik.trajectory import Hold

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    result = clik.track(task, Hold(position=[0.0, 1.2, 0.0], duration=0.01), gain=500.0)

    def broken_savez(f, **arrays):
        f.write(b"PK\x03\x04 half a zip")
        raise OSError("no space left on device")

    monkeypatch.setattr(np, "savez_compressed", broken_savez)
    with pytest.raises(OSError, match="no space left"):
        result.save(tmp_path / "trajectory.npz")
    assert list(tmp_path.iterdir()) == []


def test_written_files_get_the_usual_permissions(tmp_path):
    """``mkstemp`` makes 0600 files; the renamed file has what ``open`` would give."""
    write_json(tmp_path / "summary.json", {"a": 1})
    (tmp_path / "plain.json").write_text("{}")
    mode = stat.S_IMODE((tmp_path / "summary.json").stat().st_mode)
    assert mode == stat.S_IMODE((tmp_path / "plain.json").stat().st_mode)


KILLED_MID_WRITE = textwrap.dedent(
    """
    import os, signal, sys
    from pathlib import Path
    from clik.outputs.io import atomic_write

    def write(f):
        f.write('{"status": "compl')
        f.flush()
        os.kill(os.getpid(), signal.SIGKILL)

    atomic_write(Path(sys.argv[1]), write, mode="w")
    """
)


def test_a_process_killed_mid_write_leaves_no_truncated_file(tmp_path):
    path = tmp_path / "summary.json"
    proc = subprocess.run(
        [sys.executable, "-c", KILLED_MID_WRITE, str(path)], capture_output=True, timeout=120
    )
    assert proc.returncode == -signal.SIGKILL
    assert not path.exists()  # at most a hidden .summary.json.*.tmp remains
    assert all(name.startswith(".summary.json.") for name in hidden_leftovers(tmp_path))


def long_scenario(tmp_path: Path) -> Path:
    text = scenario_path("case_study_unconstrained").read_text()
    text = text.replace("duration = 3.0\ncruise_speed = 0.12", "duration = 600.0")
    path = tmp_path / "long.toml"
    path.write_text(text)
    return path


def start_solve(tmp_path: Path) -> tuple[subprocess.Popen, Path]:
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "clik.cli",
            "solve",
            str(long_scenario(tmp_path)),
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C reaches it as from a terminal even where this test runs with SIGINT
        # ignored (a shell's background job): the child would inherit SIG_IGN.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 60.0
    while not out.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)  # the folder is made once the scenario is built, before the run
    time.sleep(0.3)
    assert proc.poll() is None, proc.communicate()
    return proc, out


@pytest.mark.parametrize(
    ("sig", "code"),
    [(signal.SIGKILL, -signal.SIGKILL), (signal.SIGINT, 130)],
    ids=["kill", "ctrl-c"],
)
def test_a_run_stopped_midway_leaves_no_outputs(tmp_path, sig, code):
    proc, out = start_solve(tmp_path)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code
    assert not (out / "summary.json").exists() and not (out / "trajectory.npz").exists()
    assert [p.name for p in out.iterdir() if not p.name.startswith(".")] == []
    assert "Traceback" not in err
    if sig == signal.SIGINT:
        assert "clik: interrupted" in err


def test_a_file_in_place_of_the_output_folder_is_refused(tmp_path, capsys):
    target = tmp_path / "out"
    target.write_text("mine")
    scenario = str(scenario_path("case_study_unconstrained"))
    assert main(["solve", scenario, "--out", str(target), "--quiet"]) == 2
    assert "--out: expected a folder (this is an existing file)" in capsys.readouterr().err
    assert target.read_text() == "mine"


def test_force_does_not_turn_a_file_into_a_folder(tmp_path, capsys):
    target = tmp_path / "out"
    target.write_text("mine")
    scenario = str(scenario_path("case_study_unconstrained"))
    assert main(["solve", scenario, "--out", str(target), "--quiet", "--force"]) == 2
    assert target.read_text() == "mine"


def test_saved_results_read_back(tmp_path, planar4r):
    """The atomic path still writes a result that loads back, with its metadata."""
    import clik
    from clik.trajectory import Hold

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    result = clik.track(task, Hold(position=[0.0, 1.2, 0.0], duration=0.05), gain=500.0)
    back = TrackingResult.load(result.save(tmp_path / "r.npz"))
    np.testing.assert_array_equal(back.q, result.q)
    assert back.status == result.status and back.steps == result.steps
    assert os.listdir(tmp_path) == ["r.npz"]
