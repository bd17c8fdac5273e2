#!/usr/bin/env python3
"""metrics.json (DESIGN.md) and the figures of a recorded run; the metrics as a table.

    python scripts/report.py BAG [--out DIR] [--scenario NAME]

BAG: a rosbag2 directory recorded by recorder_node. DIR (default: BAG's parent) receives
metrics.json and the figures (PNG: states, track, wind, residuals, sensitivity,
estimates). NAME defaults to DIR's folder name (demo runs live in runs/<scenario>/).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from uav_fault_estimator import figures, report
from uav_fault_estimator.recording import project_typestore, read_topics


def table(metrics: dict) -> str:
    """The per-fault figures and the run's, as aligned text."""
    lines = [f"scenario {metrics['scenario']}: {metrics['duration_s']:g} s, settle "
             f"{metrics['settle_s']:g} s, threshold {metrics['detection_threshold_pct']:g} %",
             f"{'fault':<26}{'seeded':>8}{'final':>9}{'estimate':>10}{'rmse':>8}"
             f"{'max err':>9}{'delay s':>9}"]
    for name, fault in metrics["faults"].items():
        delay = fault["detection_delay_s"]
        lines.append(
            f"{name:<26}{'yes' if fault['seeded'] else 'no':>8}"
            f"{fault['seeded_final_pct']:>9.2f}{fault['estimate_final_pct']:>10.2f}"
            f"{fault['rmse_pct']:>8.2f}{fault['max_abs_error_pct']:>9.2f}"
            f"{'-' if delay is None else f'{delay:.1f}':>9}")
    solver, pipeline = metrics["solver"], metrics["pipeline"]
    lines += [
        f"false alarms: {', '.join(metrics['false_alarms']) or 'none'}",
        f"solver: {solver['solves']} solves, {solver['failures']} failures, median "
        f"{solver['median_ms']} ms, p99 {solver['p99_ms']} ms, max {solver['max_ms']} ms",
        f"pipeline: {pipeline['messages_received']}/{pipeline['messages_expected']} estimates,"
        f" {pipeline['wall_s']} s wall, real-time factor {pipeline['real_time_factor']}",
    ]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bag", type=Path)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--scenario")
    arguments = parser.parse_args()
    out = arguments.out or arguments.bag.resolve().parent
    typestore = project_typestore(
        [Path(get_package_share_directory("uav_fault_msgs")) / "msg"])
    try:  # one pass over the recording for the metrics and the figures
        messages = read_topics(arguments.bag, typestore, (*report.TOPICS, *figures.TOPICS))
        run = report.run_from(messages, arguments.bag)
    except (ValueError, FileNotFoundError) as error:
        print(f"report.py: {error}", file=sys.stderr)
        return 1
    metrics = report.run_metrics(run, arguments.scenario or out.resolve().name)
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    written = figures.plot_run(messages, out)
    print(table(metrics))
    print(f"written to {out}: metrics.json, " + ", ".join(path.name for path in written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
