"""``clik demo``: the paper's case study (docs/method.md), all runs, with a table and figures."""

from __future__ import annotations

import math
from pathlib import Path

from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_folder
from clik.outputs.result import TrackingResult, write_outputs
from clik.scenarios import CASE_STUDY, scenario_path


def case_study_table(names: list[str], results: list[TrackingResult]) -> str:
    """The demo's table: max tracking error, min link-obstacle distance, max q3, events."""
    lines = [
        f"{'run':30s} {'status':10s} {'max err [m]':>12s} {'min dist [m]':>13s} "
        f"{'max q3 [deg]':>13s}  events",
        "-" * 110,
    ]
    for name, r in zip(names, results, strict=True):
        s = r.summary()
        dist = s.get("min_obstacle_distance")
        events = ", ".join(f"{e['action']} {e['constraint']} {e['t']:.3f}s" for e in r.events)
        lines.append(
            f"{name:30s} {r.status:10s} {r.max_task_error:12.3e} "
            f"{(f'{dist:.4f}' if dist is not None else '-'):>13s} "
            f"{math.degrees(r.joint_max[2]):13.2f}  {events or '-'}"
        )
    return "\n".join(lines)


def run_demo(
    out: Path,
    force: bool = False,
    html: bool = True,
    plots: bool = True,
    quiet: bool = False,
    names: tuple[str, ...] = CASE_STUDY,
) -> int:
    """Run the case-study scenarios; write each run's outputs under ``out/<name>/``.

    ``out`` is written all at once (:func:`clik.outputs.out_folder.output_folder`): a
    stopped demo leaves it as it was.
    """
    from clik.scenarios.runner import build

    out = Path(out)
    with output_folder(out, force) as work:
        results = []
        for name in names:
            result = build(scenario_path(name)).execute()
            with output_errors(out):
                folder = work / name
                folder.mkdir()
                write_outputs(result, folder)
                if html:
                    from clik.viz import export_html

                    export_html(result, work / f"{name}.html")
            results.append(result)
        table = case_study_table(list(names), results)
        with output_errors(out):
            (work / "table.txt").write_text(table + "\n")
            written = _figures(names, results, work) if plots else []
    written = [out / p.relative_to(work) for p in written]
    if not quiet:
        print(table)
        print(f"\nwrote {out}/<run>/summary.json and trajectory.npz for {len(names)} runs")
        if html:
            print(f"wrote {len(names)} HTML scenes: {out}/<run>.html")
        if written:
            print("wrote figures: " + ", ".join(str(p) for p in written))
    return 0


def _figures(names: tuple[str, ...], results: list[TrackingResult], out: Path) -> list[Path]:
    """The paper's figures of the runs, written into ``out``; the files written."""
    from clik.plot import case_study_figures

    return case_study_figures(dict(zip(names, results, strict=True)), out)
