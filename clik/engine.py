"""The compiled engine, ``clik._engine``, loaded only with the versions it was built for.

The engine is compiled against the Pinocchio and coal that ``pip install`` found
(``pyproject.toml`` pins them). A module built against one Pinocchio loads
silently into a process running another and then misreads its objects, so the
versions are compared here, before the first use, and a mismatch is a
:class:`~clik.errors.EngineError` that says what to reinstall.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from clik.errors import EngineError

ENGINES = ("compiled", "python")
"""``"compiled"``: the per-sample loop in C++ (default); ``"python"``: the readable
loop of :mod:`clik.loop.tracking`, the engine's specification."""

_loaded: ModuleType | None = None


def check_versions(built: dict[str, str], running: dict[str, str]) -> None:
    """Refuse an engine built for other library versions than the running ones.

    Args:
        built: ``{"pinocchio": ..., "coal": ...}`` the engine was compiled against.
        running: The same, of the modules loaded in this process.

    Raises:
        EngineError: A version differs.
    """
    wrong = [
        f"{name} {built[name]} (built) but {running[name]} (running)"
        for name in built
        if built[name] != running.get(name)
    ]
    if wrong:
        raise EngineError(
            "built against other library versions: " + "; ".join(wrong) + ". Reinstall clik "
            "in this environment (pip install --force-reinstall --no-deps clik, or make "
            "test/demo from a clean .venv), or install the versions it was built with"
        )


def check_installed() -> None:
    """At ``import clik``: an engine that is there must match the running libraries.

    A missing engine is not an error here (``engine="python"`` still works); it is
    one at its first use, from :func:`load`.

    Raises:
        EngineError: The installed engine was built against other versions.
    """
    try:
        load()
    except EngineError as exc:
        if "not built" not in exc.problem:
            raise


def load() -> ModuleType:
    """The compiled module, after its versions are checked (once per process).

    Raises:
        EngineError: The module is missing (clik was not built) or mismatched.
    """
    global _loaded
    if _loaded is not None:
        return _loaded
    import coal
    import pinocchio

    try:
        module = importlib.import_module("clik._engine")
    except ImportError as exc:
        raise EngineError(
            f"clik._engine is not built ({exc}); install clik with pip (it compiles the "
            "engine: a C++17 compiler is needed) or pass engine='python'"
        ) from None
    check_versions(
        {"pinocchio": module.PINOCCHIO_VERSION, "coal": module.COAL_VERSION},
        {"pinocchio": pinocchio.__version__, "coal": coal.__version__},
    )
    _loaded = module
    return module
