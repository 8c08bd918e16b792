"""``clik demo``: the paper's case study (docs/method.md), all runs, with a table and figures."""

from __future__ import annotations

import math
from pathlib import Path

from clik.io import prepare_out
from clik.result import TrackingResult, write_outputs
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
    """Run the case-study scenarios; write each run's outputs under ``out/<name>/``."""
    from clik.runner import build

    prepare_out(out, force)
    results = []
    for name in names:
        run = build(scenario_path(name))
        result = run.execute()
        folder = out / name
        folder.mkdir(exist_ok=True)
        write_outputs(result, folder)
        if html:
            from clik.viz import export_html

            export_html(result, out / f"{name}.html")
        results.append(result)
    table = case_study_table(list(names), results)
    written: list[Path] = []
    if plots:
        from clik.plot import case_study_figures

        written = case_study_figures(dict(zip(names, results, strict=True)), out)
    if not quiet:
        print(table)
        print(f"\nwrote {out}/<run>/summary.json and trajectory.npz for {len(names)} runs")
        if html:
            print(f"wrote {len(names)} HTML scenes: {out}/<run>.html")
        if written:
            print("wrote figures: " + ", ".join(str(p) for p in written))
    (out / "table.txt").write_text(table + "\n")
    return 0
