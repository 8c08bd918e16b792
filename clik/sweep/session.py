"""One session of a sweep on a Dask client: the runs submitted in batches, their rows taken once.

The client submits the runs in batches, one Dask task per batch
(:func:`batch_size`: a run takes milliseconds, less than a task's own overhead),
at most a window of batches at a time (two per worker thread), and buffers the
rows as batches come back, writing them in groups
(:class:`~clik.sweep.store.ResultStore`). A failed batch's runs are submitted
again one per task; the runs a worker had no time for go back to the queue; the
first Ctrl-C stops the submissions, a second one stops at once.
"""

from __future__ import annotations

import math
import signal
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from clik.errors import ClikError
from clik.outputs.io import output_errors
from clik.sweep.progress import RunProgress
from clik.sweep.report import RAISED, SweepReport
from clik.sweep.spec import RunSpec, Sweep
from clik.sweep.store import ResultStore
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


class SweepSession:
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
