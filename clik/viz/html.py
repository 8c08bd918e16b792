"""One self-contained HTML file per scene: no server, no network.

The file inlines meshcat's viewer (``meshcat/viewer/dist/main.min.js``) and
the scene's commands, each packed with msgpack as the viewer's websocket
would deliver it, base64-encoded. A small script decodes and applies them in
order, synchronously, opens meshcat's controls panel and its Animations
folder (the play controls in view, not behind "Open Controls"), then sets
``window.clikSceneReady = true`` (tests wait for it). The commands are
recorded by a stand-in for meshcat's window object (:class:`Recorder`), so
nothing listens on any port.
"""

from __future__ import annotations

import base64
import html
import importlib.util
import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from clik.outputs.io import atomic_write
from clik.viz import palette
from clik.viz.commands import Command, color_int, pack
from clik.viz.scene import Geometry, build_scene

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.tasks.goal import Goal


def _viewer_js() -> Path:
    """Meshcat's viewer bundle, found without importing meshcat (which imports IPython)."""
    spec = importlib.util.find_spec("meshcat")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("meshcat is not installed: pip install meshcat")
    return Path(next(iter(spec.submodule_search_locations))) / "viewer" / "dist" / "main.min.js"


VIEWER_JS = _viewer_js()
"""meshcat's viewer bundle (three.js, msgpack, the viewer)."""


class _MeshcatCommand(Protocol):
    """A ``meshcat.commands`` object: it lowers itself to the map the viewer decodes."""

    def lower(self) -> Command: ...


class Recorder:
    """Collects viewer commands as the bytes a meshcat websocket would carry.

    It has the ``send(command)`` method of meshcat's ``ViewerWindow``, so it can
    also stand in for one: ``meshcat.Visualizer(window=Recorder())``.
    """

    def __init__(self) -> None:
        self.messages: list[bytes] = []

    def send(self, command: Command | _MeshcatCommand) -> None:
        """Record a command: a dict, or a meshcat command object (with ``lower()``).

        Args:
            command: The command.
        """
        data = command if isinstance(command, dict) else command.lower()
        self.messages.append(pack(data))

    def extend(self, commands: Iterable[Command]) -> Recorder:
        """Record several commands; returns ``self``."""
        for command in commands:
            self.send(command)
        return self


_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
  body {{ margin: 0; }}
  #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
  #clik-caption {{ position: absolute; left: 8px; bottom: 8px; padding: 4px 8px;
    font: 12px/1.4 sans-serif; color: #222; background: rgba(255, 255, 255, 0.75);
    border-radius: 4px; pointer-events: none; }}
  #clik-caption span {{ display: inline-block; width: 10px; height: 10px; margin: 0 3px 0 8px; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="clik-caption">{caption}</div>
<script>
{viewer_js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
(function () {{
  var commands = {commands};
  for (var i = 0; i < commands.length; i++) {{
    var text = atob(commands[i]);
    var bytes = new Uint8Array(text.length);
    for (var j = 0; j < text.length; j++) {{ bytes[j] = text.charCodeAt(j); }}
    viewer.handle_command_bytearray(bytes);
  }}
  // the play controls in view: meshcat starts with its panel closed ("Open Controls")
  viewer.gui.open();
  if (viewer.animator && viewer.animator.folder) {{ viewer.animator.folder.open(); }}
  window.clikSceneReady = true;
}})();
</script>
</body>
</html>
"""

_LEGEND = palette.LEGEND
"""Colour swatches of the caption."""


def page(
    messages: list[bytes],
    title: str,
    caption: str = "",
    legend: Sequence[tuple[Any, str]] | None = None,
) -> str:
    """The HTML text of a scene from its packed commands.

    Args:
        messages: msgpack-packed viewer commands, applied in order.
        title: Page title.
        caption: Text shown at the bottom left (escaped here), followed by a legend.
        legend: ``(colour, label)`` swatches (default: the tracking scene's).
    """
    encoded = [base64.b64encode(m).decode("ascii") for m in messages]
    swatches = "".join(
        f'<span style="background:#{color_int(c):06x}"></span>{html.escape(n)}'
        for c, n in (_LEGEND if legend is None else legend)
    )
    return _PAGE.format(
        title=html.escape(title),
        caption=f"{html.escape(caption)}{swatches}",
        viewer_js=VIEWER_JS.read_text(encoding="utf-8"),
        commands=json.dumps(encoded, separators=(",", ":")),
    )


def scene_title(result: TrackingResult) -> tuple[str, str]:
    """Page title and caption of a result: scenario (or robot), status."""
    info = result.info
    name = str(info.get("scenario") or info.get("robot") or "run")
    return f"clik: {name}", f"{name}: {result.status}"


def export_html(
    result: TrackingResult,
    path: str | os.PathLike[str],
    geometry: Geometry = "visual",
    fps: float = 30.0,
    robot: Robot | None = None,
    tasks: Sequence[Goal] | None = None,
) -> Path:
    """Write a result's animated 3-D scene as one self-contained HTML file.

    The file opens from ``file://`` in any browser with WebGL, offline: the
    viewer and the scene are inlined. The animation plays in real time and
    loops; the meshcat panel (top right, "Animations") has play, pause and a
    time slider. The file is written atomically (temporary file, then rename).

    Args:
        result: A tracking result, with its ``robot`` (or pass ``robot``).
        path: The ``.html`` file to write (its folder is created).
        geometry: ``"visual"`` meshes or the lighter ``"collision"`` geometry.
        fps: Animation frames per second of run time [1/s]; fewer frames make
            smaller files.
        robot: The robot, when ``result.robot`` is not set (e.g. a result read
            with :meth:`~clik.outputs.result.TrackingResult.load`).
        tasks: The goals of a several-task run: each task's reference and path are
            drawn and named in the legend (see :func:`~clik.viz.scene.build_scene`).

    Returns:
        The path written.

    Raises:
        InputError: See :func:`clik.viz.scene.build_scene`.
    """
    path = Path(path)
    scene = build_scene(result, robot=robot, geometry=geometry, fps=fps, tasks=tasks)
    title, caption = scene_title(result)
    text = page(Recorder().extend(scene.commands).messages, title, caption, scene.legend)
    atomic_write(path, lambda f: f.write(text), mode="w")
    path.chmod(0o644)  # the temporary file was private; a scene is meant to be shared
    return path
