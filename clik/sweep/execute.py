"""Run a sweep on Dask: an embedded local cluster, or an existing one by address.

The client (this process) submits the runs in batches, one Dask task per
batch (:func:`~clik.sweep.session.batch_size`: a run takes milliseconds, less
than a task's own overhead), at most a window of batches at a time, and writes
the rows as batches come back (:class:`~clik.sweep.store.ResultStore`), so
results are on disk while the sweep goes on. Exactly-once writing is the
client's job: it writes a run id only if it is not in the folder yet, whatever
Dask does underneath.

- A run that raises comes back as a row with ``status = "error"``.
- The sweep *fails* (:attr:`~clik.sweep.report.SweepReport.failed`, exit code 1
  of ``clik sweep``) when a run in the folder raised, or ended with a status of
  :data:`~clik.sweep.report.FAILED_STATUSES`; resumed runs count as much as
  those computed now.
- A worker that dies: Dask reschedules its tasks (and recomputes results it
  held but the client had not fetched) on the other workers. A task whose
  workers died ``distributed.scheduler.allowed-failures`` times (default 3)
  fails (``KilledWorker``); the runs of a failed batch are submitted again one
  per task, so only the run that failed its task is recorded with
  ``status = "error"`` (:class:`~clik.sweep.session.SweepSession`).
- An interruption (Ctrl-C): no more runs are submitted, the ones submitted
  (at most two batches per worker thread; a worker starts no run of a batch
  after :data:`~clik.sweep.session.MAX_BATCH_SECONDS`) are finished and written
  (a second Ctrl-C stops at once); running the same sweep into the same folder
  again computes only the missing runs, so no run is computed twice.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clik.errors import ScenarioError
from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_lock
from clik.sweep.cluster import dask_client
from clik.sweep.progress import RunProgress
from clik.sweep.report import SweepReport
from clik.sweep.results import read_statuses
from clik.sweep.session import SweepSession
from clik.sweep.spec import RunSpec, Sweep, load_sweep
from clik.sweep.store import CSV, PARQUET, ResultStore, check_folder

if TYPE_CHECKING:
    from distributed import Client


def manifest(sweep: Sweep) -> dict[str, Any]:
    """The manifest written to ``DIR/sweep.json``."""
    return {
        "fingerprint": sweep.fingerprint,
        "name": sweep.name,
        "sweep_file": str(sweep.file.resolve()),
        "base_file": str(sweep.base_file.resolve()),
        "seed": sweep.seed,
        "runs": len(sweep.runs),
        "parameters": sweep.parameters,
        "vary": {v.path: v.kind for v in sweep.vary},
    }


def check_first_run(sweep: Sweep, runs: list[RunSpec]) -> None:
    """Build (not run) the first run here: a bad frame, joint or robot fails before any task."""
    if not runs:
        return
    from clik.scenarios.runner import build

    build(sweep.scenario(runs[0]))


def run_sweep(
    sweep: Sweep | str | Path,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Client | None = None,
    keep_trajectories: bool = False,
    force: bool = False,
    fmt: str = "auto",
    progress: bool | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> SweepReport:
    """Run every run of a sweep not yet in ``out``; write one row per run as they finish.

    Args:
        sweep: A :class:`~clik.sweep.spec.Sweep` or a sweep file.
        out: The output folder (see :mod:`clik.sweep.store`). Rerunning the same
            sweep into it resumes; another sweep needs ``force`` (which starts over).
        workers: Processes of the local cluster (default: one per CPU).
        scheduler: Address of an existing Dask scheduler instead, ``tcp://HOST:PORT``.
        client: An existing :class:`distributed.Client` instead of both.
        keep_trajectories: Also write ``DIR/runs/<run_id>/`` (summary, trajectory).
        force: Start over in a folder holding something else.
        fmt: ``"auto"`` or ``"parquet"`` (Parquet), or ``"csv"``; a resumed folder keeps
            its format.
        progress: Draw the progress bar (default: when stderr is a terminal).
        on_row: Called with each row after it is buffered (tests, notebooks).

    Returns:
        The report (counts, rate, and the statuses of every run in the folder:
        :attr:`SweepReport.failed` tells whether the sweep failed).

    Raises:
        ScenarioError: The sweep file, or its first run's scenario, is invalid.
        SweepOutputExistsError: ``out`` holds something else and ``force`` is false.
        OutputLockedError: Another clik run writes into ``out`` (see
            :mod:`clik.outputs.out_folder`).
    """
    if not isinstance(sweep, Sweep):
        sweep = load_sweep(sweep)
    out = Path(out)
    try:
        check_first_run(sweep, sweep.runs)
    except ScenarioError as exc:
        raise ScenarioError(sweep.file, "base", f"the first run cannot be built: {exc}") from None
    with output_lock(out):  # one writer per folder (resumed in place, not replaced)
        values = {v.path: [r.params[v.path] for r in sweep.runs] for v in sweep.vary}

        def open_store() -> ResultStore:
            with output_errors(out):
                return ResultStore.open(out, manifest(sweep), values, force=force, fmt=fmt)

        # Resuming: read what is there first (no cluster for a finished sweep). Else check the
        # folder, connect, and only then create it (a bad --scheduler leaves nothing behind).
        store = open_store() if check_folder(out, sweep.fingerprint, force) else None
        todo = [r for r in sweep.runs if store is None or r.run_id not in store.ids]
        results = out / (PARQUET if fmt != "csv" else CSV)
        report = SweepReport(out, results, len(sweep.runs), len(sweep.runs) - len(todo))
        if store is not None and not todo:
            with output_errors(out):
                store.compact()
            report.results = store.path
            report.all_statuses = read_statuses(out)
            return report
        bar = RunProgress(sweep.name, len(todo), enabled=progress)
        with nullcontext(client) if client is not None else dask_client(workers, scheduler) as dask:
            if store is None:
                store = open_store()
            report.results = store.path
            SweepSession(dask, sweep, todo, store, report, bar, keep_trajectories, on_row).run()
        if report.complete:
            with output_errors(out):
                store.compact()
        report.all_statuses = read_statuses(out)
        return report
