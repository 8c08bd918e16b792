"""``bench.md``: the report of ``bench.json`` as markdown tables."""

from __future__ import annotations

from typing import Any

import numpy as np

from clik.bench.stats import ratio


def fmt(value: Any, digits: int = 3) -> str:
    """A table cell: ``-`` for None, yes / **no** for booleans, ``digits`` significant digits.

    Args:
        value: The figure.
        digits: Significant digits of a float.
    """
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "**no**"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{value:.{digits}g}"
    return str(value)


def header(report: dict[str, Any]) -> list[str]:
    """Title and the machine line.

    Args:
        report: The report.
    """
    m = report["machine"]
    v = report["versions"]
    return [
        "# clik bench" + (" (quick: a smoke run with tiny counts, not figures)" * report["quick"]),
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, "
        f"load {m.get('load_average_1min_start', '-')} at start, CPU share "
        f"{m.get('cpu_share', '-')} (below 1: other processes ran; figures inflated). "
        f"clik {v['clik']}, pin {v['pin']}, coal {v['coal']}, numpy {v['numpy']}, "
        f"pink {v['pin-pink'] or '-'} ({report['pink']['solver'] or 'not run'}).",
    ]


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
        "| line | median | p10 | p90 | pink / this | real-time factor | law | status | "
        "max task error | active rows (mean) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    pink_median = report["step_us"]["pink_panda_pose"]
    for name, s in report["steps"].items():
        pink_ratio = None if name.startswith("pink_") else ratio(pink_median, s["median_us"])
        lines.append(
            f"| {name} | {s['median_us']:.2f} | {s['p10_us']:.2f} | {s['p90_us']:.2f} | "
            f"{fmt(pink_ratio)} | {s['realtime_factor']:.0f} | {s.get('law', 'pink')} | "
            f"{s['status']} | {fmt(s['max_task_error'])} | {fmt(s.get('active_rows_mean'))} |"
        )
    lines += ["", "Lines:", ""]
    lines += [f"- `{name}`: {s['description']}" for name, s in report["steps"].items()]
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
        f"| clik.solve | {100 * sv['success_rate']:.1f} % | {sv['median_us']:.1f} | "
        f"{sv['p10_us']:.1f} | {sv['p90_us']:.1f} | {sv['mean_us']:.1f} | "
        f"{sv['iterations_median']:.0f} |",
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
    cs, mem, run, sweep = (
        report["case_study"],
        report["memory"],
        report["panda_obstacles_run"],
        report["sweep"],
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


def markdown(report: dict[str, Any]) -> str:
    """``bench.md``: the step, solve, case-study, memory and target tables.

    Args:
        report: The report (``bench.json``'s content).
    """
    lines = [
        *header(report),
        *step_section(report),
        *solve_section(report),
        *case_memory_section(report),
        *targets_section(report),
        "",
        "Reproduce: `clik bench --out out/bench` (or `make bench`).",
        "",
    ]
    return "\n".join(lines)
