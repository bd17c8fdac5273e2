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
import sys
from pathlib import Path

from uav_fault_estimator.recording.project_bag import RecordingError
from uav_fault_estimator.reporting import report
from uav_fault_estimator.reporting.recorded_run import write_report


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
