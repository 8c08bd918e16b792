"""``bench.md``: the report of ``bench.json`` as markdown tables."""

from __future__ import annotations

from typing import Any

from benchmarks.cells import fmt
from benchmarks.report_cloud import cloud_section
from benchmarks.report_ticks import tick_section
from benchmarks.stats import ratio


def header(report: dict[str, Any]) -> list[str]:
    """Title and the machine line.

    Args:
        report: The report.
    """
    m = report["machine"]
    v = report["versions"]
    share = m.get("cpu_share")
    busy = ""
    if share is not None and share < 1:
        busy = ", below 1: other processes took the CPU, figures inflated"
    return [
        "# clik bench" + (" (quick: a smoke run with tiny counts, not figures)" * report["quick"]),
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, "
        f"load {m.get('load_average_1min_start', '-')} at start, CPU share "
        f"{m.get('cpu_share', '-')}{busy} (the bench's CPU time over its wall time). "
        f"clik {v['clik']}, pin {v['pin']}, coal {v['coal']}, numpy {v['numpy']}, "
        f"pink {v['pin-pink'] or '-'} ({report['pink']['solver'] or 'not run'}), "
        f"mink {v.get('mink') or '-'} on MuJoCo {v.get('mujoco') or '-'} "
        f"({report['mink']['solver'] or 'not run'}).",
    ]


def _engine_of(name: str, line: dict[str, Any]) -> str:
    """``compiled``, ``python`` or ``pink``: what ran a step line."""
    return "pink" if name.startswith("pink_") else str(line.get("engine", "-"))


def step_section(report: dict[str, Any]) -> list[str]:
    """The step-cost table and what each line is.

    Args:
        report: The report.
    """
    lines = [
        "",
        f"## Step cost [us per sample] (medians over {report['config']['rounds']} interleaved "
        "rounds of whole runs)",
        "",
        "| line | engine | median | p10 | p90 | pink / this (with its barrier on obstacle "
        "lines) | python / compiled | "
        "real-time factor | law | status | max task error | active rows (mean) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    python_ratio = report["ratios"]["python_over_compiled_steps"]
    for name, s in report["steps"].items():
        engine = _engine_of(name, s)
        pink_line = "pink_panda_pose" + ("_obstacles" if "obstacles" in name else "")
        pink_median = report["step_us"][pink_line]
        pink_ratio = None if engine == "pink" else ratio(pink_median, s["median_us"])
        lines.append(
            f"| {name} | {engine} | {s['median_us']:.2f} | {s['p10_us']:.2f} | "
            f"{s['p90_us']:.2f} | {fmt(pink_ratio)} | {fmt(python_ratio.get(name))} | "
            f"{s['realtime_factor']:.0f} | {s.get('law', 'pink')} | {s['status']} | "
            f"{fmt(s['max_task_error'])} | {fmt(s.get('active_rows_mean'))} |"
        )
    lines += ["", "Lines:", ""]
    lines += [f"- `{name}`: {s['description']}" for name, s in report["steps"].items()]
    return lines


def zoo_section(report: dict[str, Any]) -> list[str]:
    """The zoo's obstacle run: the median over robots, how many ran, which were refused.

    Args:
        report: The report.
    """
    z = report["zoo"]
    skipped = ", ".join(f"{name} ({x['refused']})" for name, x in z["skipped"].items())
    slowest = sorted(z["per_robot"].items(), key=lambda item: -item[1]["median_us"])[:5]
    return [
        "",
        f"## Zoo obstacle run [us per sample] (compiled engine, each robot's median over "
        f"{z['rounds']} runs)",
        "",
        "| robots timed | median over robots | p10 | p90 | min | max | robots refused |",
        "|---|---|---|---|---|---|---|",
        f"| {z['robots_timed']} | {z['median_us']:.2f} | {z['p10_us']:.2f} | "
        f"{z['p90_us']:.2f} | {z['min_us']:.2f} | {z['max_us']:.2f} | {z['robots_skipped']} |",
        "",
        "Slowest: "
        + ", ".join(f"{name} {x['median_us']:.1f} ({x['status']})" for name, x in slowest)
        + ". Refused before running: "
        + (skipped or "none")
        + ".",
    ]


def ratios_section(report: dict[str, Any]) -> list[str]:
    """The ratios of medians: pink over clik, clik's Python engine over its compiled one.

    Args:
        report: The report.
    """
    r = report["ratios"]
    rows = (
        ("pink / compiled, Panda pose step", r["pink_over_panda_pose"]),
        ("pink with its barrier / compiled, Panda pose step with obstacles (1 row active)",
         r["pink_over_panda_pose_obstacles"]),
        ("python / compiled, Panda pose step", r["python_over_panda_pose"]),
        ("pink solve / clik solve (compiled)", r["pink_over_solve"]),
        ("python solve / compiled solve", r["python_over_solve"]),
    )  # fmt: skip
    lines = ["", "## Ratios (of medians)", "", "| ratio | value |", "|---|---|"]
    lines += [f"| {name} | {fmt(value)} |" for name, value in rows]
    return lines


def solve_section(report: dict[str, Any]) -> list[str]:
    """The single-pose solve table, clik and (when it ran) pink.

    Args:
        report: The report.
    """
    sv = report["solve"]
    lines = [
        "",
        f"## Single-pose solve ({sv['targets']} random reachable Panda poses, "
        f"{sv['tolerance_m']:g} m / {sv['tolerance_rad']:g} rad, from the reference)",
        "",
        "| solver | success | median [us] | p10 [us] | p90 [us] | mean [us] | iterations "
        "(median) |",
        "|---|---|---|---|---|---|---|",
        f"| clik.solve, compiled engine | {100 * sv['success_rate']:.1f} % | "
        f"{sv['median_us']:.1f} | {sv['p10_us']:.1f} | {sv['p90_us']:.1f} | {sv['mean_us']:.1f} | "
        f"{sv['iterations_median']:.0f} |",
        f"| clik.solve, Python engine | {100 * sv['python_success_rate']:.1f} % | "
        f"{sv['python_median_us']:.1f} | {sv['python_p10_us']:.1f} | {sv['python_p90_us']:.1f} | "
        f"{sv['python_mean_us']:.1f} | {sv['python_iterations_median']:.0f} |",
    ]
    if sv["pink_median_us"] is not None:
        lines.append(
            f"| pink (cap {sv['pink_max_iterations']}) | {100 * sv['pink_success_rate']:.1f} % | "
            f"{sv['pink_median_us']:.1f} | {sv['pink_p10_us']:.1f} | {sv['pink_p90_us']:.1f} | "
            f"{sv['pink_mean_us']:.1f} | {sv['pink_iterations_median']:.0f} |"
        )
        lines += ["", f"pink: {sv['pink_setup']}. Speed-up: {fmt(sv['speedup_vs_pink'])}x."]
    return lines


def case_memory_section(report: dict[str, Any]) -> list[str]:
    """Case study, the Panda obstacle run, memory and sweep figures.

    Args:
        report: The report.
    """
    cs, mem, run, sweep, session = (
        report["case_study"],
        report["memory"],
        report["panda_obstacles_run"],
        report["sweep"],
        report["controller_session"],
    )
    return [
        "",
        "## Case study and memory",
        "",
        "| line | value |",
        "|---|---|",
        f"| case study, 8 runs, execute() [s] (median of {cs['rounds']}) | "
        f"{cs['all_runs_s']:.3f} (p10 {cs['all_runs_p10_s']:.3f}, p90 "
        f"{cs['all_runs_p90_s']:.3f}) |",
        f"| case study, 8 runs, build + execute [s] | {cs['all_runs_with_build_s']:.3f} |",
        f"| case study, 8 runs, loop only (sum of wall_time_s) [s] | "
        f"{cs['all_runs_loop_only_s']:.3f} |",
        f"| Panda {run['duration_s']:g} s run, 3 obstacles, 1 row "
        "active: wall [s], real-time factor | "
        f"{run['wall_s']:.3f}, {run['realtime_factor']:.1f} |",
        f"| memory growth, {mem['full']['samples']} samples, full recording [MB] | "
        f"{mem['full']['growth_mb']:.1f} |",
        f"| memory growth, {mem['decimated']['samples']} samples, record_every = "
        f"{mem['decimated']['record_every']} [MB] | {mem['decimated']['growth_mb']:.1f} |",
        f"| controller session, {session['ticks']} ticks, {session['events']} events: memory "
        f"growth after 10 % [MB], result() [ms] | {session['growth_after_10pct_mb']:.2f}, "
        f"{session['result_ms']:.1f} |",
        "",
        f"| sweep, {sweep['runs']} runs, local Dask cluster [runs/s]: 1 worker, "
        f"2 workers, speed-up | {sweep['runs_per_s_1_worker']:.2f}, "
        f"{sweep['runs_per_s_2_workers']:.2f}, {sweep['speedup_2_workers']:.2f}x |",
    ]


def targets_section(report: dict[str, Any]) -> list[str]:
    """Every target: measured figure, what is wanted, whether it is met.

    Args:
        report: The report.
    """
    lines = [
        "",
        "## Targets",
        "",
        "| target | measured | wanted | met |",
        "|---|---|---|---|",
    ]
    for t in report["targets"]:
        lines.append(f"| {t['name']} | {fmt(t['value'])} | {t['target']} | {fmt(t['met'])} |")
    return lines


def ros_section(report: dict[str, Any]) -> list[str]:
    """The ROS 2 loop's line, or why it did not run."""
    ros = report.get("ros") or {}
    if not ros or ros.get("skipped"):
        return ["", "## ROS 2 loop", "", f"Not run: {ros.get('skipped', 'no measurement')}."]
    rtt = ros["rtt_ms"] or {}
    return [
        "",
        "## ROS 2 loop",
        "",
        f"{ros['text']}: {ros['answered']} of {ros['sent']} targets answered, round trip "
        f"{rtt.get('median', float('nan')):.3g} ms median, {rtt.get('p99', float('nan')):.3g} ms "
        f"p99; the hand on the robot's joints {1e3 * ros['max_error_m']:.3g} mm at most from "
        "the circle.",
    ]


def markdown(report: dict[str, Any]) -> str:
    """``bench.md``: the step, tick, cloud, zoo, solve, ratio, case-study, memory and target tables.

    Args:
        report: The report (``bench.json``'s content).
    """
    lines = [
        *header(report),
        *step_section(report),
        *tick_section(report),
        *cloud_section(report),
        *zoo_section(report),
        *solve_section(report),
        *ratios_section(report),
        *case_memory_section(report),
        *ros_section(report),
        *targets_section(report),
        "",
        "Reproduce: `clik bench --out out/bench` (or `make bench`).",
        "",
    ]
    return "\n".join(lines)
