"""The sweep line of ``clik bench``: runs per second on a local cluster of N workers."""

from __future__ import annotations

import tempfile
from pathlib import Path

from clik.errors import InputError

BENCH_SWEEP = """\
base = "case_study_both"
seed = {seed}

[vary."obstacles.pin.position"]
uniform = {{ low = [0.66, -0.32, 0.0], high = [0.74, -0.24, 0.0], samples = {samples} }}
"""
"""The fixed sweep: the case study (law (9), both constraints, 3 s at 1 ms, about 0.25 s a
run on one core), the pin at uniform positions around the paper's."""


def sweep_rate(workers: int, runs: int) -> float:
    """Runs per second of a fixed sweep on a :class:`~distributed.LocalCluster` of ``workers``.

    The cluster is started and warmed up first (each worker imports clik and
    loads the robot with one run), so the rate is the steady one: ``runs``
    divided by the time from the first submission to the last row written.

    Args:
        workers: Worker processes (one thread each).
        runs: Runs of the timed sweep (a few per worker at least).

    Returns:
        Runs per second [1/s].
    """
    from clik.sweep.execute import dask_client, run_sweep

    for name, value in (("workers", workers), ("runs", runs)):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise InputError(name, "an integer >= 1", value)
    with tempfile.TemporaryDirectory(prefix="clik_sweep_rate_") as folder:
        root = Path(folder)
        warm = root / "warm.toml"
        warm.write_text(BENCH_SWEEP.format(seed=1, samples=2 * workers))
        timed = root / "timed.toml"
        timed.write_text(BENCH_SWEEP.format(seed=0, samples=runs))
        with dask_client(workers=workers) as client:
            client.wait_for_workers(workers)
            run_sweep(warm, root / "warm", client=client, progress=False)
            report = run_sweep(timed, root / "timed", client=client, progress=False)
    return report.rate
