"""An output folder written as one transaction, under a lock.

A run (``clik solve``, ``clik demo``, ``clik reach``) writes into a temporary
folder beside ``DIR`` (``.DIR.tmp-<pid>``: same parent, so same file system),
and renames it into place once complete (:func:`output_folder`):

- without ``force``, an existing non-empty ``DIR`` is refused before the run
  (:class:`~clik.errors.OutputExistsError`);
- with ``force``, the old ``DIR`` is replaced whole: renamed aside
  (``.DIR.old-<pid>``), the new one renamed in, the old one deleted, with
  Ctrl-C and SIGTERM held off meanwhile. Files of an earlier run do not stay.

A run stopped before that (Ctrl-C; SIGTERM, raised as :class:`Terminated`; an
exception; a full disk) leaves ``DIR`` byte-identical and removes its temporary
folder. A missing ``DIR`` is created empty at the start, so a stopped first run
leaves an empty folder. A run killed outright (SIGKILL) can leave its temporary
folder behind: the next run into ``DIR`` removes it.

The lock is ``.DIR.lock`` beside ``DIR``, held (``flock``) for the whole run and
removed after it: a second writer fails at once with
:class:`~clik.errors.OutputLockedError`. Sweeps resume into their folder rather
than replace it; they take the same lock (:func:`output_lock`).
"""

from __future__ import annotations

import fcntl
import os
import shutil
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from types import FrameType

from clik.errors import OutputError, OutputExistsError, OutputLockedError
from clik.outputs.io import check_out_path, check_parents, os_reason, output_errors


class Terminated(KeyboardInterrupt):
    """SIGTERM during a run, raised in the main thread so that cleanups run.

    Attributes:
        exit_code: ``128 + SIGTERM`` (143), what a shell reports for a process it killed.
    """

    exit_code = 128 + signal.SIGTERM


def _siblings(out: Path, kind: str) -> list[Path]:
    """The hidden ``.DIR.<kind>-<pid>`` folders beside ``out``, oldest name first."""
    prefix = f".{out.name}.{kind}-"
    return sorted(p for p in out.parent.iterdir() if p.name.startswith(prefix))


def _acquire(out: Path, lock: Path) -> int:
    """Open and ``flock`` the lock file; the open file descriptor.

    Raises:
        OutputLockedError: Another process holds the lock.
        OutputError: The lock file cannot be created.
    """
    while True:
        with output_errors(out):
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise OutputLockedError(out, lock) from None
        except OSError as exc:
            os.close(fd)
            raise OutputError(out, os_reason(exc)) from exc
        try:
            current = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            current = False
        if current:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
            return fd
        os.close(fd)  # its holder removed it meanwhile: lock the new one


@contextmanager
def output_lock(out: Path) -> Iterator[Path]:
    """Hold ``.DIR.lock`` beside ``out`` (created, with its parents) while inside.

    Args:
        out: The output folder.

    Yields:
        The lock file.

    Raises:
        OutputLockedError: Another run holds the lock of ``out``.
        OutputError: A parent of ``out`` is a file, or the lock cannot be created.
    """
    out = Path(out).absolute()
    check_parents(out)
    with output_errors(out):
        out.parent.mkdir(parents=True, exist_ok=True)
    lock = out.parent / f".{out.name}.lock"
    fd = _acquire(out, lock)
    try:
        yield lock
    finally:
        with suppress(OSError):
            lock.unlink()  # while still held: a later opener sees another inode and retries
        os.close(fd)


@contextmanager
def _signals_held() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM back while inside; they are delivered after."""
    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextmanager
def _sigterm_raises() -> Iterator[None]:
    """While inside, SIGTERM raises :class:`Terminated` (main thread only; else nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        raise Terminated

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _recover(out: Path) -> None:
    """Undo what a run killed outright left beside ``out`` (the lock is held: none runs).

    Killed between the two renames of :func:`_swap`, ``out`` is missing: the old
    folder comes back. Temporary and old folders left are removed.
    """
    olds = _siblings(out, "old")
    if olds and not out.exists():
        os.rename(olds.pop(), out)
    for stale in [*olds, *_siblings(out, "tmp")]:
        shutil.rmtree(stale, ignore_errors=True)


def _swap(work: Path, out: Path) -> None:
    """Put the complete folder ``work`` in place of ``out``; the old one is deleted."""
    old = out.parent / f".{out.name}.old-{os.getpid()}"
    os.rename(out, old)
    try:
        os.rename(work, out)
    except OSError:
        os.rename(old, out)
        raise
    shutil.rmtree(old, ignore_errors=True)


@contextmanager
def output_folder(out: Path, force: bool = False) -> Iterator[Path]:
    """Write a run's output folder all at once: yields the folder to write into.

    See the module's docstring for the rules. On leaving without an exception
    the folder written replaces ``out``; on an exception (or Ctrl-C, SIGTERM)
    it is removed and ``out`` is untouched.

    Args:
        out: The output folder (``--out``); a symbolic link to a folder is followed.
        force: Replace a non-empty ``out``.

    Yields:
        The temporary folder ``.DIR.tmp-<pid>`` beside ``out``.

    Raises:
        InputError: ``out`` is an existing file.
        OutputExistsError: ``out`` is a non-empty folder and ``force`` is false.
        OutputLockedError: Another run writes into ``out``.
        OutputError: Any OS error on the folders (named with its reason).
    """
    out = Path(out)
    check_out_path(out)
    out = out.resolve()
    with output_lock(out), _sigterm_raises():
        work = out.parent / f".{out.name}.tmp-{os.getpid()}"
        with output_errors(out):
            _recover(out)
            if out.is_dir() and any(out.iterdir()) and not force:
                raise OutputExistsError(out)
            out.mkdir(exist_ok=True)
            work.mkdir()
        try:
            yield work
            with _signals_held(), output_errors(out):
                _swap(work, out)
        finally:
            with _signals_held():
                shutil.rmtree(work, ignore_errors=True)
