"""The files of a reachability map: its table, its description and its 3-D view."""

from __future__ import annotations

from pathlib import Path

from clik.outputs.io import write_json
from clik.sweep.reach_data import ReachMap

TABLE = "reach.parquet"
"""The map's table in the output folder (``reach.csv`` when written as CSV)."""

INFO = "reach.json"
"""The map's description: its spec, counts (``reachable``, ``blocked``, ``unreachable``)
and time."""

HTML = "reach.html"
"""The map's self-contained 3-D view."""


def write_reach(reach: ReachMap, out: Path, html: bool = True) -> dict[str, Path]:
    """Write ``reach.parquet``, ``reach.json`` and (with ``html``) ``reach.html`` into ``out``.

    Returns:
        The paths written, by kind: ``table``, ``json`` and ``html``.
    """
    written = {"table": reach.write_table(out / TABLE)}
    info = {
        **reach.spec.as_dict(),
        "points": len(reach.points),
        **reach.counts(),
        "reachable_fraction": reach.reachable_fraction,
        "wall_time_s": reach.wall_time_s,
        "table": written["table"].name,
    }
    write_json(out / INFO, info)
    written["json"] = out / INFO
    if html:
        from clik.sweep.reach_view import export_reach_html  # meshcat and the viewer bundle

        written["html"] = export_reach_html(reach, out / HTML)
    return written
