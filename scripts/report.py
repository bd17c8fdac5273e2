#!/usr/bin/env python3
"""metrics.json (docs/design.md) and the figures of a recorded run; the metrics as a table.

    python scripts/report.py BAG [--out DIR] [--scenario NAME] [--ns NS]

BAG: a rosbag2 directory recorded by recorder_node. DIR (default: BAG's parent) receives
metrics.json and the figures (PNG: states, track, wind, residuals, sensitivity,
estimates). NAME defaults to DIR's folder name (demo runs live in runs/<scenario>/). NS: the
namespace the run's nodes had (bringup.sh --ns), e.g. /uav1.

Exit status: 0 written; 2 a recording that is not a rosbag2 folder, cannot be read or
decoded (truncated, empty, damaged) or lacks a stream the metrics need, or an output folder
that cannot be written (one line naming it); 1 the report failed otherwise.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from uav_fault_estimator.recording.project_bag import RecordingError, project_typestore, read_topics
from uav_fault_estimator.reporting import figures, report


def write_report(bag: Path, out: Path, scenario: str,
                 namespace: str = "") -> tuple[dict, list[Path]]:
    """Write metrics.json and the figures of the recording BAG (of the nodes under namespace,
    "" for none) into OUT: (metrics, figures).

    RecordingError (a ValueError, one line naming the bag) when the recording cannot be
    read or lacks a stream; OSError when OUT cannot be written.
    """
    typestore = project_typestore()
    # one pass over the recording for the metrics and the figures; /diagnostics on its own
    # (global, and outside the flight's wall span)
    messages = read_topics(bag, typestore, (*report.TOPICS, *figures.TOPICS), namespace)
    diagnostics = read_topics(bag, typestore, (report.DIAGNOSTICS_TOPIC,))
    statuses = diagnostics[report.DIAGNOSTICS_TOPIC]
    run = report.run_from(messages, bag)
    run = dataclasses.replace(
        run, cpu_s=report.node_cpu_s(statuses, namespace),
        aircraft=report.aircraft(statuses, namespace),
        estimates=dataclasses.replace(
            run.estimates, solver_method=report.solver_method(statuses, namespace)))
    metrics = report.run_metrics(run, scenario)
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    return metrics, figures.plot_run(messages, out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bag", type=Path)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--scenario")
    parser.add_argument("--ns", default="", help="the nodes' namespace, e.g. /uav1")
    arguments = parser.parse_args()
    out = arguments.out or arguments.bag.resolve().parent
    try:
        metrics, written = write_report(
            arguments.bag, out, arguments.scenario or out.resolve().name, arguments.ns)
    except RecordingError as error:
        print(f"report.py: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"report.py: cannot write into {out} "
              f"({error.strerror or type(error).__name__})", file=sys.stderr)
        return 2
    except ValueError as error:
        print(f"report.py: {' '.join(str(error).split())}", file=sys.stderr)
        return 1
    print(report.table(metrics))
    print(f"written to {out}: metrics.json, " + ", ".join(path.name for path in written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
