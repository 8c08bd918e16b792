"""Output files and folders: atomic writes, JSON, and the ``--out`` folder rule.

Everything clik writes goes through :func:`atomic_write`: a run killed midway
leaves the old file or none, never a truncated one.
"""

from __future__ import annotations

import errno
import json
import math
import numbers
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from clik.errors import ClikError, InputError, OutputError


def os_reason(error: OSError) -> str:
    """An OS error in words with its symbol, e.g. ``No space left on device (ENOSPC)``.

    The file the error names is added when there is one.
    """
    code = error.errno
    text = error.strerror or str(error) or type(error).__name__
    if code is not None:
        text += f" ({errno.errorcode.get(code, code)})"
    if error.filename is not None:
        text += f": {os.fsdecode(error.filename)}"
    return text


@contextmanager
def output_errors(path: Path) -> Iterator[None]:
    """Turn any :class:`OSError` raised inside into an :class:`~clik.errors.OutputError`.

    Args:
        path: The output folder (or file) to name in the message.

    Raises:
        OutputError: An OS error (full disk, permission, not a folder, ...) inside.
    """
    try:
        yield
    except ClikError:  # OutputExistsError is an OSError too
        raise
    except OSError as exc:
        raise OutputError(path, os_reason(exc)) from exc


def check_out_path(out: Path) -> None:
    """Refuse an ``--out`` that cannot become a folder, before anything is written.

    Raises:
        InputError: ``out`` is an existing file.
        OutputError: ``out`` is a dangling symbolic link, or a parent is not a folder.
    """
    if out.is_symlink() and not out.exists():
        target = os.readlink(out)
        raise OutputError(out, f"a dangling symbolic link (to {target}, which does not exist)")
    if out.exists() and not out.is_dir():
        raise InputError("--out", "a folder (this is an existing file)", str(out))
    check_parents(out)


def check_parents(out: Path) -> None:
    """Refuse an output path under a file (``--out afile/sub``).

    Raises:
        OutputError: The nearest existing parent of ``out`` is not a folder.
    """
    for parent in out.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputError(out, f"{parent} is a file, not a folder (ENOTDIR)")
            return


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_FILE_MODE = 0o666 & ~_umask()
"""Permissions of a written file: what ``open`` would give (``mkstemp`` gives 0600)."""


def atomic_write(path: Path, write: Callable[[IO[Any]], object], mode: str = "wb") -> None:
    """Write ``path`` through ``write(file)`` into a temporary file, then rename it.

    The temporary file sits in the same folder (a hidden ``.<name>.*.tmp``), is
    flushed to disk, then renamed over ``path``: a run killed midway leaves
    either the old file or none, never a truncated one. On an exception the
    temporary file is removed and ``path`` is untouched.

    Args:
        path: The file to write.
        write: Called once with the open temporary file; its result is ignored.
        mode: Mode the temporary file is opened with: ``"wb"`` or ``"w"``.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode) as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _FILE_MODE)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def json_safe(data: Any, where: str = "") -> tuple[Any, list[str]]:
    """``data`` with every number that is not finite replaced by ``None`` (JSON ``null``).

    JSON has no ``inf`` nor ``nan``: ``json.dumps(..., allow_nan=False)`` raises on
    them. Dicts, lists and tuples are copied (tuples become lists); other values
    are kept as they are.

    Args:
        data: A JSON-like value.
        where: Key path of ``data`` itself (used in the list returned).

    Returns:
        The copy, and the key paths replaced (``min_obstacle_distance``,
        ``velocity[0].max_ratio``, ...).
    """
    if isinstance(data, dict):
        replaced: list[str] = []
        safe: dict[Any, Any] = {}
        for key, value in data.items():
            safe[key], found = json_safe(value, f"{where}.{key}" if where else str(key))
            replaced += found
        return safe, replaced
    if isinstance(data, list | tuple):
        items = [json_safe(value, f"{where}[{i}]") for i, value in enumerate(data)]
        return [v for v, _ in items], [p for _, found in items for p in found]
    real = isinstance(data, numbers.Real) and not isinstance(data, numbers.Integral)
    if real and not math.isfinite(float(data)):
        return None, [where]
    return data, []


def json_text(data: Any) -> str:
    """``data`` as indented JSON text and a final newline; raises on ``inf`` or ``nan``."""
    return json.dumps(data, indent=2, allow_nan=False) + "\n"


def write_json(path: Path, data: Any) -> None:
    """Write ``data`` as indented JSON, atomically."""
    text = json_text(data)
    atomic_write(path, lambda f: f.write(text), mode="w")
