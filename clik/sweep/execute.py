"""Run a sweep on Dask: an embedded local cluster, or an existing one by address.

The client (this process) submits the runs in batches, one Dask task per
batch (:func:`batch_size`: a run takes milliseconds, less than a task's own
overhead), at most a window of batches at a time, and writes the rows as
batches come back (:class:`~clik.sweep.store.ResultStore`), so results are on
disk while the sweep goes on. Exactly-once writing is the client's job: it
writes a run id only if it is not in the folder yet, whatever Dask does
underneath.

- A run that raises comes back as a row with ``status = "error"``.
- The sweep *fails* (:attr:`SweepReport.failed`, exit code 1 of ``clik
  sweep``) when a run in the folder raised, or ended with a status of
  :data:`FAILED_STATUSES`; resumed runs count as much as those computed now.
- A worker that dies: Dask reschedules its tasks (and recomputes results it
  held but the client had not fetched) on the other workers. A task whose
  workers died ``distributed.scheduler.allowed-failures`` times (default 3)
  fails (``KilledWorker``); the runs of a failed batch are submitted again one
  per task, so only the run that failed its task is recorded with
  ``status = "error"``.
- An interruption (Ctrl-C): no more runs are submitted, the ones submitted
  (at most two batches per worker thread; a worker starts no run of a batch
  after :data:`MAX_BATCH_SECONDS`) are finished and written (a second Ctrl-C
  stops at once); running the same sweep into the same folder again computes
  only the missing runs, so no run is computed twice.
"""

from __future__ import annotations

import logging
import math
import os
import signal
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clik.errors import ClikError, InputError, ScenarioError
from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_lock
from clik.sweep.progress import RunProgress
from clik.sweep.results import read_statuses
from clik.sweep.spec import RunSpec, Sweep, load_sweep
from clik.sweep.store import CSV, PARQUET, ResultStore, check_folder
from clik.sweep.worker import run_batch

if TYPE_CHECKING:
    from distributed import Client

FLUSH_SECONDS = 2.0
"""Longest time a finished row waits in memory before it is written [s]."""

FLUSH_ROWS = 256
"""Most rows kept in memory before they are written."""

BATCHES_PER_THREAD = 2
"""The runs not submitted yet are cut into at least this many batches per worker thread."""

MIN_BATCH_SECONDS = 0.05
"""Least work of a batch [s] (estimated): enough to outweigh a Dask task's overhead."""

MAX_BATCH_SECONDS = 0.5
"""Most work of a batch [s]: estimated, and a worker starts no run of a batch after it
(progress and Ctrl-C stay responsive, however long the runs are)."""

MAX_BATCH = 64
"""Most runs in a batch."""

BATCHES_PER_WORKER_THREAD = 2
"""Batches kept submitted per worker thread: one running, the next one queued on the worker."""

THREADS_SECONDS = 2.0
"""Least time between two looks at the cluster's worker threads (workers may join or leave) [s]."""

RAISED = "error"
"""The ``status`` of a run that raised (or whose task failed, e.g. ``KilledWorker``)."""

FAILED_STATUSES = frozenset({"violated", "velocity_limit", "diverged"})
"""Run statuses that fail a sweep, as do runs that raised (:data:`RAISED`)."""

STATUS_ORDER = ("completed", "deadlock", "diverged", "violated", "velocity_limit")
"""The order of the statuses in :func:`status_line` (others follow, sorted)."""


LOCAL_WORKER_CONFIG: dict[str, Any] = {"distributed": {"worker": {"profile": {"enabled": False}}}}
"""Dask configuration of the local cluster's workers, over this process's own.

A worker's statistical profiler (every 10 ms it walks the stack of the thread
running a task) feeds only the dashboard, which the local cluster does not
serve, and takes about 5 % of a run's time.
"""


def status_line(counts: Counter[str]) -> str:
    """Counts per status, e.g. ``completed 118, deadlock 1, violated 1, raised 0``.

    Statuses with runs are listed in :data:`STATUS_ORDER`, then any other
    status (sorted); runs that raised come last as ``raised``, always shown.
    """
    shown = [s for s in STATUS_ORDER if counts.get(s)]
    shown += sorted(s for s, n in counts.items() if n and s != RAISED and s not in STATUS_ORDER)
    return ", ".join([*(f"{s} {counts[s]}" for s in shown), f"raised {counts.get(RAISED, 0)}"])


@dataclass
class SweepReport:
    """What one call of :func:`run_sweep` did.

    Attributes:
        out: The output folder.
        results: The results table (``results.parquet`` folder or ``results.csv``).
        total: Runs in the sweep.
        skipped: Runs already in the folder (resume), not computed again.
        computed: Runs computed and written now.
        lost: Runs neither written nor failed (cancelled by the cluster); a rerun computes them.
        statuses: Status counts of the runs written now.
        all_statuses: Status counts of every run in the folder at the end (those
            written now and those resumed), read back from the results table.
        wall_time_s: From the first submission to the last write [s].
        interrupted: The sweep was stopped before its end (Ctrl-C).
    """

    out: Path
    results: Path
    total: int
    skipped: int
    computed: int = 0
    lost: int = 0
    statuses: Counter[str] = field(default_factory=Counter)
    all_statuses: Counter[str] = field(default_factory=Counter)
    wall_time_s: float = 0.0
    interrupted: bool = False

    @property
    def rate(self) -> float:
        """Runs computed per second [1/s]."""
        return self.computed / self.wall_time_s if self.wall_time_s > 0 else 0.0

    @property
    def complete(self) -> bool:
        """Every run of the sweep is in the folder."""
        return self.skipped + self.computed == self.total

    @property
    def failed(self) -> int:
        """Runs in the folder that raised or ended with a status of :data:`FAILED_STATUSES`."""
        return sum(n for s, n in self.all_statuses.items() if s == RAISED or s in FAILED_STATUSES)


def check_address(scheduler: str) -> str:
    """A scheduler address ``tcp://HOST:PORT`` (also ``tls://``, ``ws://``...)."""
    scheme, sep, rest = scheduler.partition("://")
    host, colon, port = rest.rpartition(":")
    if not sep or not scheme or not colon or not host or not port.isdigit():
        raise InputError(
            "--scheduler", "a Dask scheduler address like tcp://127.0.0.1:8786", scheduler
        )
    return scheduler


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None) -> Iterator[Client]:
    """A Dask client: on the scheduler at ``scheduler``, else on a new local cluster.

    The local cluster has ``workers`` worker processes (default: one per CPU),
    one thread each, every server on 127.0.0.1 and no dashboard; it is closed
    on exit. Its workers do not sample their threads for the dashboard's
    profile (:data:`LOCAL_WORKER_CONFIG`). An existing cluster is left running.

    Raises:
        InputError: Both or a bad ``workers``/``scheduler``, or no scheduler answers.
    """
    try:
        import dask.config
        from distributed import Client, LocalCluster
    except ImportError:
        raise ClikError(
            "sweeps and reachability maps run on Dask: pip install 'dask[distributed]'"
        ) from None
    if scheduler is not None and workers is not None:
        raise InputError("--workers", "either --workers or --scheduler, not both", workers)
    if scheduler is not None:
        check_address(scheduler)
        try:
            client = Client(scheduler, timeout="10s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise InputError(
                "--scheduler", "the address of a running Dask scheduler", f"{scheduler} ({exc})"
            ) from None
        try:
            yield client
        finally:
            client.close()
        return
    n = (os.cpu_count() or 1) if workers is None else workers
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise InputError("--workers", "an integer >= 1", workers)
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        scheduler_port=0,
        dashboard_address=None,  # no dashboard; its HTTP server (health checks) on a free
        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},  # loopback port, not 8787
        silence_logs=logging.ERROR,
        config=dask.config.merge(dask.config.config, LOCAL_WORKER_CONFIG),  # to each worker
    )
    try:
        client = Client(cluster, set_as_default=False)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()


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
            _Session(dask, sweep, todo, store, report, bar, keep_trajectories, on_row).run()
        if report.complete:
            with output_errors(out):
                store.compact()
        report.all_statuses = read_statuses(out)
        return report


def batch_size(remaining: int, threads: int, run_seconds: float | None) -> int:
    """Runs in the next batch (Dask task), from the runs left and the time a run takes.

    ``remaining / (BATCHES_PER_THREAD * threads)`` rounded up: the batches
    shrink as the sweep goes on (guided self-scheduling), so every worker
    thread stays busy to the end and they finish together. Once the time of a
    run is known, at least :data:`MIN_BATCH_SECONDS` of work (worth a task) and
    at most :data:`MAX_BATCH_SECONDS`; always at most :data:`MAX_BATCH` runs and
    ``remaining``. (A worker also stops a batch once :data:`MAX_BATCH_SECONDS`
    have passed, whatever the estimate: see :func:`~clik.sweep.worker.run_batch`.)

    Args:
        remaining: Runs not submitted yet (>= 1).
        threads: Worker threads of the cluster.
        run_seconds: Mean time a run took on a worker so far [s], or None.
    """
    size = math.ceil(remaining / (BATCHES_PER_THREAD * max(threads, 1)))
    if run_seconds is not None:
        run_seconds = max(run_seconds, 1e-6)
        least = math.ceil(MIN_BATCH_SECONDS / run_seconds)
        size = min(max(size, least), math.floor(MAX_BATCH_SECONDS / run_seconds))
    return max(1, min(size, MAX_BATCH, remaining))


def _threads(client: Client, default: int = 1) -> int:
    """Worker threads of the cluster (at least 1); ``default`` if the scheduler does not answer."""
    try:
        threads = sum(client.nthreads().values())
    except (OSError, ClikError):  # pragma: no cover
        threads = default
    return max(threads, 1)


class _Session:
    """One session of a sweep on a client: the runs to do, submitted in batches.

    At most a window of batches (two per worker thread: one running, one
    queued) is submitted at once. Each finished run is taken once
    (:meth:`take`), buffered and written in groups (:meth:`flush`); the first
    Ctrl-C stops the submissions (:meth:`on_sigint`), a second one stops at once.
    """

    def __init__(
        self,
        client: Client,
        sweep: Sweep,
        todo: list[RunSpec],
        store: ResultStore,
        report: SweepReport,
        bar: RunProgress,
        keep_trajectories: bool,
        on_row: Callable[[dict[str, Any]], None] | None,
    ) -> None:
        self.client = client
        self.sweep = sweep
        self.store = store
        self.report = report
        self.bar = bar
        self.keep_trajectories = keep_trajectories
        self.on_row = on_row
        self.queue = deque(todo)
        self.retry: deque[RunSpec] = deque()  # runs of failed batches, one per task now
        self.threads = _threads(client)
        self.threads_at = time.perf_counter()
        self.base_file = str(sweep.base_file.resolve())
        self.by_key: dict[str, list[RunSpec]] = {}
        self.buffer: list[dict[str, Any]] = []
        self.taken: set[str] = set()
        self.run_seconds = 0.0  # worker time of the runs taken, to size the batches
        self.runs_timed = 0
        self.last_flush = time.perf_counter()
        self.stopping = threading.Event()

    @property
    def window(self) -> int:
        """Batches kept submitted at once: one running and one queued per worker thread."""
        return BATCHES_PER_WORKER_THREAD * self.threads

    def next_batch(self) -> list[RunSpec]:
        """The runs of the next task: a failed batch's run alone, else a batch of the queue."""
        if self.retry:
            return [self.retry.popleft()]
        if not self.queue:
            return []
        mean = self.run_seconds / self.runs_timed if self.runs_timed else None
        n = min(batch_size(len(self.queue), self.threads, mean), len(self.queue))
        return [self.queue.popleft() for _ in range(n)]

    def submit(self) -> Any:
        """Submit the next batch as a Dask task; its future, or None when no run is left."""
        batch = self.next_batch()
        if not batch:
            return None
        key = f"clik-runs-{self.sweep.fingerprint}-{batch[0].run_id}-{len(batch)}"
        self.by_key[key] = batch
        return self.client.submit(
            run_batch,
            self.sweep.base_data,
            self.base_file,
            [(run.run_id, run.params) for run in batch],
            self.keep_trajectories,
            MAX_BATCH_SECONDS,
            key=key,
            pure=False,
            retries=0,
        )

    def flush(self) -> None:
        """Write the buffered rows (those of run ids not in the folder yet)."""
        with output_errors(self.store.out):
            self.report.computed += self.store.append(self.buffer)
        self.buffer.clear()
        self.last_flush = time.perf_counter()

    def take(self, future: Any, result: Any) -> None:
        """Take a finished batch: buffer its rows, or queue its runs again one by one.

        The runs a worker had no time for (the first ones are done, see
        :func:`~clik.sweep.worker.run_batch`) go back to the front of the
        queue. A batch whose task failed (e.g. ``KilledWorker``) and had
        several runs goes to :attr:`retry`, so that only a run that fails on its
        own is recorded as an error; a cancelled batch's runs are lost (a rerun
        computes them).
        """
        batch = self.by_key.pop(future.key, None)
        if batch is None:
            return
        if future.status == "finished":
            rows = result
        elif future.status == "error" and len(batch) > 1:
            self.retry.extend(batch)
            return
        elif future.status == "error":
            rows = [_error_row(batch[0].run_id, future.exception())]
        else:  # cancelled (e.g. the scheduler restarted): not recorded, a rerun computes them
            self.report.lost += sum(1 for run in batch if not self.done(run))
            return
        for run, row in zip(batch, rows, strict=False):
            self.take_row(run, row)
        self.queue.extendleft(reversed(batch[len(rows) :]))  # out of time: submitted again

    def done(self, run: RunSpec) -> bool:
        """The run was taken in this session or is in the folder."""
        return run.run_id in self.taken or run.run_id in self.store.ids

    def take_row(self, run: RunSpec, row: dict[str, Any]) -> None:
        """Buffer a finished run's row, once per run id whatever the cluster did."""
        if self.done(run):
            return
        if row.get("run_wall_time_s") is not None:
            self.run_seconds += row["run_wall_time_s"]
            self.runs_timed += 1
        row = {"run_id": run.run_id, **run.params, **_without_id(row)}
        summary, trajectory = row.pop("_summary", None), row.pop("_trajectory_npz", None)
        if summary is not None and trajectory is not None:
            with output_errors(self.store.out):
                self.store.write_run_files(run.run_id, summary, trajectory)
        self.taken.add(run.run_id)
        self.buffer.append(row)
        self.report.statuses[row["status"]] += 1
        self.bar.update(1, failed=int(row["status"] == RAISED))
        if self.on_row is not None:
            self.on_row(row)

    def on_sigint(self, signum: int, frame: Any) -> None:
        """The first Ctrl-C: stop submitting; a second one: stop now."""
        if self.stopping.is_set():
            raise KeyboardInterrupt
        self.stopping.set()
        self.bar.note("stopping: finishing the runs submitted (Ctrl-C again to stop now)")

    def run(self) -> None:
        """Compute the runs; Ctrl-C raises KeyboardInterrupt once the submitted ones are written.

        The first Ctrl-C only sets a flag: no more runs are submitted, and every
        run already submitted (at most two batches per worker thread) is
        finished and written, so none is computed and then lost (and computed
        again on resume).
        """
        start = time.perf_counter()
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, self.on_sigint) if main else None
        try:
            self._drain()
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
            self.flush()
            self.report.wall_time_s = time.perf_counter() - start
            self.bar.close()

    def _fill(self, pending: Any) -> None:
        """Submit the runs of failed batches, then batches up to the window (unless stopping)."""
        if time.perf_counter() - self.threads_at >= THREADS_SECONDS:
            self.threads, self.threads_at = _threads(self.client, self.threads), time.perf_counter()
        while self.retry:  # runs submitted already: finished even when stopping
            pending.add(self.submit())
        while not self.stopping.is_set() and pending.count() < self.window:
            future = self.submit()
            if future is None:
                return
            pending.add(future)

    def _drain(self) -> None:
        """Take finished batches and submit more as they finish, until none is pending."""
        from distributed import as_completed

        # Results are fetched in the background as tasks finish, not one round trip each here.
        pending = as_completed(loop=self.client.loop, with_results=True, raise_errors=False)
        try:
            self._fill(pending)
            for future, result in pending:
                self.take(future, result)
                self._fill(pending)
                due = time.perf_counter() - self.last_flush >= FLUSH_SECONDS
                if len(self.buffer) >= FLUSH_ROWS or (self.buffer and due):
                    self.flush()
            if self.stopping.is_set():
                raise KeyboardInterrupt
        except BaseException:
            self.report.interrupted = True
            self.client.cancel(list(pending.futures))
            raise


def _error_row(run_id: str, exc: BaseException | None) -> dict[str, Any]:
    """The row of a run whose task failed (e.g. ``KilledWorker``)."""
    message = f"{type(exc).__name__}: {exc}"
    return {"run_id": run_id, "status": RAISED, "reason": message, "error": message}


def _without_id(row: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in row.items() if k != "run_id"}
