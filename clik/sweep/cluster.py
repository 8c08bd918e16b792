"""The Dask cluster a sweep or a reachability map runs on: a local one, or an existing one.

A local cluster is started in this process (worker processes on 127.0.0.1, no
dashboard) and closed at the end; an existing one is reached by its scheduler's
address (``tcp://HOST:PORT``) and left running.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from clik.errors import ClikError, InputError

if TYPE_CHECKING:
    from distributed import Client

LOCAL_WORKER_CONFIG: dict[str, Any] = {"distributed": {"worker": {"profile": {"enabled": False}}}}
"""Dask configuration of the local cluster's workers, over this process's own.

A worker's statistical profiler (every 10 ms it walks the stack of the thread
running a task) feeds only the dashboard, which the local cluster does not
serve, and takes about 5 % of a run's time.
"""


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
