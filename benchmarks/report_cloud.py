"""``bench.md``'s point-cloud section: the far and near ticks, the update, coal's octree."""

from __future__ import annotations

from typing import Any

from benchmarks.cells import fmt

CHECK_WORDS = {
    "far_no_active_row": "far: no row active on any tick",
    "near_two_rows_on_most_ticks": "near: two rows active on most ticks",
    "every_verdict_ok": "every tick's verdict ok (both sessions completed)",
    "min_cloud_distance_nonnegative": "clik's smallest link-cloud distance >= 0",
    "octree_agrees_with_spheres": "coal's octree and clik's spheres agree within a voxel diagonal",
}
"""Each structural check of the cloud lines in words."""


def _objects(names: list[str]) -> str:
    """``a table, a box and a shelf``."""
    words = [f"a {name}" for name in names]
    return " and ".join([", ".join(words[:-1]), words[-1]] if len(words) > 1 else words)


def _tick_rows(cloud: dict[str, Any]) -> list[str]:
    """One row per cloud tick line: timing, rows active, verdicts, quality."""
    rows = []
    for name, line in cloud["lines"].items():
        q = line["quality"]
        links = ", ".join(line["activations"]) or "-"
        rows.append(
            f"| {name} | {line['median_us']:.1f} | {line['p10_us']:.1f} | {line['p90_us']:.1f} | "
            f"{line['realtime_factor']:.1f} | {line['status']} | "
            f"{line['active_rows_median']:g} ({line['ticks_with_2_rows']}/"
            f"{line['ticks_recorded']} ticks with 2) | {links} | "
            f"{fmt(q['max_position_error_m'])} | {fmt(line['min_cloud_distance_m'])} | "
            f"{fmt(q['min_octree_distance_m'])} ({q['min_octree_link']}) |"
        )
    return rows


def cloud_section(report: dict[str, Any]) -> list[str]:
    """The cloud lines: per-tick cost, the update, the octree, the checks, what each is.

    Args:
        report: The report (its ``cloud`` entry; the section says so when it is empty).
    """
    cloud = report.get("cloud") or {}
    lines = ["", "## Point-cloud obstacles (compiled engine)"]
    if not cloud:
        return [*lines, "", "Not measured."]
    s, u, o = cloud["scene"], cloud["update"], cloud["octree"]
    agreement = o["agreement"]
    lines += [
        "",
        f"{s['points']} points (seed {s['seed']}) on {_objects(s['objects'])}; voxel "
        f"{s['voxel_m']:g} m, threshold {s['threshold_m']:g} m; {s['task']} on a "
        f"{s['circle_radius_m']:g} m circle, {s['ticks_per_run']} ticks per run, from the "
        f"joints settled over {s['settle_ticks']} ticks at its first point.",
        "",
        "| line | median [us] | p10 | p90 | real-time factor | status | rows active (median) "
        "| links with a row | max hand error [m] | clik's min distance [m] | "
        "octree min distance [m] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *_tick_rows(cloud),
        "",
        "| line | value |",
        "|---|---|",
        f"| update_cloud, {u['points']} points [ms]: median (p10, p90) of {u['repeats']} | "
        f"{u['median_ms']:.2f} ({u['p10_ms']:.2f}, {u['p90_ms']:.2f}) |",
        f"| coal octree, every link per tick [us]: median (p10, p90) of {o['ticks_timed']} "
        f"ticks | {o['median_us']:.0f} ({o['p10_us']:.0f}, {o['p90_us']:.0f}) |",
        f"| coal octree / cloud_near | {fmt(cloud['octree_over_near'])} |",
        f"| octree build from the points [ms] | {o['build_ms']:.1f} |",
        f"| octree vs spheres: largest difference [m] over {agreement['pairs']} link-tick pairs "
        f"(voxel diagonal {agreement['voxel_diagonal_m']:.4f}) | "
        f"{fmt(agreement['max_abs_difference_m'])} |",
        "",
        "Checks: "
        + "; ".join(f"{CHECK_WORDS[k]}: {fmt(v)}" for k, v in cloud["checks"].items())
        + ".",
        "",
        "clik's min distance is its record's (to the voxel spheres: a lower bound of the "
        "distance to the points; '-' when no link came within reach); the octree's is "
        "coal's to its cells at sampled ticks (a lower bound too, by at most a cell's "
        "diagonal).",
        "",
        "Lines:",
        "",
        *(f"- `{name}`: {line['description']}" for name, line in cloud["lines"].items()),
        f"- `coal_octree_cloud`: {o['description']}",
    ]
    return lines
