"""``bench.md``'s tick section: per-tick cost and tracking quality of clik, pink and mink."""

from __future__ import annotations

from typing import Any

from benchmarks.cells import fmt
from benchmarks.tick import TICK_LINES
from benchmarks.tick_quality import CLEARANCE_EVERY

PEERS = ("pink", "mink")


def _tool(name: str) -> tuple[str, str]:
    """``(tool, clik's matching line)`` of a tick line."""
    for peer in PEERS:
        if name.startswith(f"{peer}_"):
            return peer, name[len(peer) + 1 :]
    return "clik", name


def _skipped(report: dict[str, Any]) -> list[str]:
    """One line per library whose tick lines did not run, with why."""
    return [
        f"Skipped: {peer}'s tick lines ({report[peer]['reason']})."
        for peer in PEERS
        if not report[peer]["available"]
    ]


def tick_section(report: dict[str, Any]) -> list[str]:
    """The tick-cost table, its quality columns, clik's final error and what each line is.

    Args:
        report: The report.
    """
    lines = [
        "",
        f"## Tick cost [us per tick] (one Python call per 1 ms tick; medians over "
        f"{report['config']['rounds']} interleaved rounds of the per-tick mean)",
        "",
        "| line | tool | median | p10 | p90 | this / clik | real-time factor | status | "
        "max position error [m] | max orientation error [rad] | min clearance [m] | "
        "max qdot / vmax |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    ticks, quality, ratios = report["ticks"], report["tick_quality"], report["tick_ratios"]
    for name in TICK_LINES:
        if name not in ticks:
            continue
        t, q = ticks[name], quality[name]
        tool, clik_line = _tool(name)
        over = ratios.get(f"{tool}_over_{clik_line}") if tool != "clik" else None
        lines.append(
            f"| {name} | {tool} | {t['median_us']:.1f} | {t['p10_us']:.1f} | {t['p90_us']:.1f} | "
            f"{fmt(over)} | {t['realtime_factor']:.1f} | {t['status']} | "
            f"{fmt(q['max_position_error_m'])} | {fmt(q['max_orientation_error_rad'])} | "
            f"{fmt(q.get('min_clearance_m'))} | {fmt(q['velocity_ratio'])} |"
        )
    lines += [
        "",
        f"clik's position error at its last tick: {fmt(report['tick_error_m']['panda_pose'])} m.",
        "",
        "Quality from each line's recorded joints alone: the pose errors of q(t_k) against "
        "x_d(t_k) (Pinocchio's forward kinematics), the clearance between the link geometries' "
        f"convex hulls and the three spheres (coal, every {CLEARANCE_EVERY}th tick; negative: "
        "inside a sphere; also on the lines that ignore the spheres), and the largest joint "
        "speed over its URDF limit (joint differences over dt).",
        *(["", *_skipped(report)] if _skipped(report) else []),
        "",
        "Lines:",
        "",
    ]
    lines += [f"- `{name}`: {t['description']}" for name, t in ticks.items()]
    return lines
