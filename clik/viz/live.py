"""Live views: a result in a browser through a local meshcat server, or inline in Jupyter.

One server process per Python process, started on first use and reused by
later calls (each call replaces the scene); it listens on 127.0.0.1 only (see
:mod:`clik.viz.server`) and stops at interpreter exit.
"""

from __future__ import annotations

import html
import os
import time
import webbrowser
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from clik.viz.html import Recorder, page, scene_title
from clik.viz.scene import Geometry, build_scene
from clik.viz.server import MeshcatServer
from clik.viz.target import load_target

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.tasks.goal import Goal

_server: MeshcatServer | None = None

INLINE_HEIGHT_PX = 480
"""Height of the inline view in a notebook [px]."""


def live_server() -> MeshcatServer:
    """The process's meshcat server, started if none runs."""
    global _server
    if _server is None or not _server.alive:
        _server = MeshcatServer.start()
    return _server


def stop_server() -> None:
    """Stop the live server, if one runs."""
    global _server
    if _server is not None:
        _server.stop()
        _server = None


def in_notebook() -> bool:
    """True inside a Jupyter kernel."""
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and type(shell).__name__ == "ZMQInteractiveShell"


def show(
    result: TrackingResult,
    open_browser: bool = False,
    geometry: Geometry = "visual",
    fps: float = 30.0,
    robot: Robot | None = None,
    inline: bool | None = None,
    tasks: Sequence[Goal] | None = None,
) -> str:
    """Show a result live: robot, obstacles, paths, witness segments, animated.

    Starts (or reuses) a meshcat server bound to 127.0.0.1 on free ports,
    replaces its scene with this result's and prints the viewer's URL. In a
    Jupyter notebook the scene is also displayed inline, as a self-contained
    page in an iframe (it works when the kernel runs on another machine; the
    notebook grows by the scene's size, a few MB for a meshed robot).

    Args:
        result: A tracking result, with its ``robot`` (or pass ``robot``).
        open_browser: Also open the URL in the default browser.
        geometry: ``"visual"`` meshes or the lighter ``"collision"`` geometry.
        fps: Animation frames per second of run time [1/s].
        robot: The robot, when ``result.robot`` is not set.
        inline: Display inline; default: when running in a notebook.
        tasks: The goals of a several-task run: each task's reference and path are
            drawn and named in the legend (see :func:`~clik.viz.scene.build_scene`).

    Returns:
        The viewer's URL (``http://127.0.0.1:<port>/static/``).

    Raises:
        InputError: See :func:`clik.viz.scene.build_scene`.
        ServerError: The server could not be started or did not answer.
    """
    scene = build_scene(result, robot=robot, geometry=geometry, fps=fps, tasks=tasks)
    server = live_server()
    server.send_all(scene.commands)
    url = server.web_url
    print(f"clik: live view at {url} (Ctrl-C or the end of this process stops it)")
    if open_browser:
        webbrowser.open(url, new=2)
    if inline if inline is not None else in_notebook():
        from IPython.display import HTML, display

        title, caption = scene_title(result)
        text = page(Recorder().extend(scene.commands).messages, title, caption, scene.legend)
        display(
            HTML(
                f'<div style="width: 100%; height: {INLINE_HEIGHT_PX}px">'
                f'<iframe srcdoc="{html.escape(text, quote=True)}" '
                'style="width: 100%; height: 100%; border: none"></iframe></div>'
            )
        )
    return url


def show_path(
    target: str | os.PathLike[str],
    block: bool = True,
    open_browser: bool = False,
    geometry: Geometry = "visual",
    fps: float = 30.0,
) -> str:
    """Show a scenario file (run now) or an output folder (``trajectory.npz``) live.

    Args:
        target: A scenario ``.toml`` file or an output folder of ``clik solve``/``clik demo``.
        block: Wait until Ctrl-C, then stop the server.
        open_browser: Also open the URL in the default browser.
        geometry: ``"visual"`` meshes or the lighter ``"collision"`` geometry.
        fps: Animation frames per second of run time [1/s].

    Returns:
        The viewer's URL.

    Raises:
        InputError: ``target`` is neither, or its robot cannot be rebuilt
            (see :func:`clik.viz.target.load_target`).
    """
    result = load_target(Path(target))
    url = show(result, open_browser=open_browser, geometry=geometry, fps=fps, inline=False)
    if block:
        try:
            while _server is not None and _server.alive:
                time.sleep(0.25)
        except KeyboardInterrupt:
            pass
        finally:
            stop_server()
            print("clik: live view stopped")
    return url
