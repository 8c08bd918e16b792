"""Output files and folders: atomic writes, JSON, and the ``--out`` folder rule.

Everything clik writes goes through :func:`atomic_write`: a run killed midway
leaves the old file or none, never a truncated one.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from clik.errors import InputError, OutputExistsError


def prepare_out(out: Path, force: bool) -> Path:
    """Create the output folder; an existing non-empty one needs ``force``."""
    if out.exists() and not out.is_dir():
        raise InputError("--out", "a folder (this is an existing file)", str(out))
    if out.exists() and any(out.iterdir()) and not force:
        raise OutputExistsError(out)
    out.mkdir(parents=True, exist_ok=True)
    return out


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


def write_json(path: Path, data: Any) -> None:
    """Write ``data`` as indented JSON, atomically."""
    text = json.dumps(data, indent=2, allow_nan=False)
    atomic_write(path, lambda f: f.write(text + "\n"), mode="w")
