"""A run's metrics.json (DESIGN.md) from its recording. No ROS here: rosbags reads the
rosbag2 directory, metrics.py computes the figures."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.typesys.store import Typestore

from uav_fault_estimator.metrics import (
    EstimateSeries,
    SeededSeries,
    fault_metrics,
    solver_metrics,
)

ESTIMATE_TOPIC = "/faults/estimate"
SEEDED_TOPIC = "/faults/seeded"
STATE_TOPIC = "/state"


@dataclass(frozen=True)
class Run:
    """What a recording holds for the metrics: estimates, seeded faults, the flight's
    simulated duration [s] and the wall time the recording spans [s]."""

    estimates: EstimateSeries
    seeded: SeededSeries
    duration_s: float
    wall_s: float


def _stamp_s(message) -> float:
    return message.header.stamp.sec + 1e-9 * message.header.stamp.nanosec


def read_run(bag: Path, typestore: Typestore) -> Run:
    """The estimate, seeded-fault and state streams of a recording; ValueError when one
    is missing."""
    rows: dict[str, list] = {ESTIMATE_TOPIC: [], SEEDED_TOPIC: [], STATE_TOPIC: []}
    received_ns: list[int] = []
    with Reader(bag) as reader:
        wanted = [c for c in reader.connections if c.topic in rows]
        for connection, timestamp_ns, raw in reader.messages(connections=wanted):
            rows[connection.topic].append(typestore.deserialize_cdr(raw, connection.msgtype))
            received_ns.append(timestamp_ns)
    missing = [topic for topic, messages in rows.items() if not messages]
    if missing:
        raise ValueError(f"{bag}: no messages on {', '.join(missing)}")
    estimates, seeded = rows[ESTIMATE_TOPIC], rows[SEEDED_TOPIC]
    return Run(
        estimates=EstimateSeries(
            names=list(estimates[0].names),
            stamps_s=np.array([_stamp_s(m) for m in estimates]),
            values_pct=np.array([m.values_pct for m in estimates]),
            statuses=np.array([m.solver_status for m in estimates]),
            solve_times_ms=np.array([m.solve_time_ms for m in estimates]),
        ),
        seeded=SeededSeries(
            names=list(seeded[0].names),
            stamps_s=np.array([_stamp_s(m) for m in seeded]),
            values_pct=np.array([m.values_pct for m in seeded]),
        ),
        duration_s=_stamp_s(rows[STATE_TOPIC][-1]),
        wall_s=1e-9 * (max(received_ns) - min(received_ns)),
    )


def run_metrics(run: Run, scenario: str, update_period_s: float = 0.5,
                settle_s: float = 20.0, threshold_pct: float = 2.0) -> dict:
    """metrics.json as DESIGN.md lays it out."""
    faults, false_alarms = fault_metrics(run.estimates, run.seeded, settle_s, threshold_pct)
    return {
        "scenario": scenario,
        "duration_s": round(run.duration_s, 3),
        "settle_s": settle_s,
        "detection_threshold_pct": threshold_pct,
        "faults": faults,
        "false_alarms": false_alarms,
        "solver": solver_metrics(run.estimates),
        "pipeline": {
            "wall_s": round(run.wall_s, 3),
            "real_time_factor": round(run.duration_s / run.wall_s, 2) if run.wall_s else None,
            "messages_expected": round(run.duration_s / update_period_s),
            "messages_received": len(run.estimates.stamps_s),
        },
    }
