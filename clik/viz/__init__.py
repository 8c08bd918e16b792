"""See a run: meshcat scenes, live in a browser or a notebook, or as one HTML file.

A scene shows the robot (visual meshes, or its collision geometry), the
obstacles (purple) with their threshold shells (translucent cyan), the
reference path (blue), the task frame's trail (dark), the witness segments of
the obstacle rows (red while a row is active; the closest link orange inside
the threshold, green outside), and the links of a joint on its range limit
(magenta; yellow inside the threshold): one colour per legend entry
(:data:`clik.viz.palette.LEGEND`). It plays in real time and loops; meshcat's
"Animations" panel has play, pause and a time slider.

- :func:`export_html`: one self-contained file, no server, opens offline;
- :func:`show`: a live view on a meshcat server bound to 127.0.0.1;
- :func:`show_path`: the same for a scenario file or an output folder (``clik show``).
"""

from clik.viz.html import export_html
from clik.viz.live import show, show_path, stop_server
from clik.viz.scene import Scene, build_scene

__all__ = ["Scene", "build_scene", "export_html", "show", "show_path", "stop_server"]
