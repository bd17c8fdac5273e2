"""A recorded run's report: metrics.json (docs/design.md) and the figures, from the bag
recorder_node wrote (scripts/report.py, and demo.py after each run)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from uav_fault_estimator.recording.project_bag import project_typestore, read_topics
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
