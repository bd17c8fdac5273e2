#!/usr/bin/env python3
"""Soak benchmark: a long flight through the graph with bad messages injected.

    python -m benchmarks.soak [--duration 1800] [--seed 1] [--json FILE]

The default scenario, flown by the core simulator for --duration seconds of sim time, is
replayed (uav_sim/ros/flight_replay.py) into two copies of residual_node, mhe_node and
detector_node, one in /clean and one in /dirty, on a ROS domain of its own. The /dirty copy
gets, every 20-60 s of sim time at random (seeded), one of: a velocity of 1e200 for 2 s or
of 1e6 m/s for 0.5 s, body rates of 1e6 rad/s for 0.5 s, a NaN or an Inf for 1 s, a
duplicate, backwards or 1e6 s stamp, a lost controls message, one north velocity 30 m/s
off (inside the envelope), the air data lost for 30 s, or a residual given to its
mhe_node between two real ones: of 1e300, with S of 1e300, or with an unknown
wind_source. Printed: the estimates each copy published against
the expected count (messages lost), the largest difference of the /dirty estimates from the
/clean ones outside the disturbed windows (each event's span + residual_node's recovery_s +
the estimator's window), inside them, and each /dirty node's memory at start and end.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uav_common.channels import CONTROL_CHANNELS, PAPER_FAULT_NAMES, STATE_CHANNELS
from uav_common.message_fields import stamp_seconds
from uav_common.ros.messages import header
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_domain import reserve_domain_id
from uav_common.ros_processes import RosProcess, ros2_run_argv, stop_all
from uav_fault_estimator.estimation.estimator_settings import EstimatorSettings
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.reporting.report import residual_update_period_s
from uav_fault_msgs.msg import FaultEstimate, Residuals
from uav_sim.ros.flight_replay import FlightSample, Replayer, simulated_flight
from uav_sim.scenario import default_scenario_path, load_scenario

CLEAN, DIRTY = "/clean", "/dirty"
NODES = (("uav_fault_estimator", "residual_node"), ("uav_fault_estimator", "mhe_node"),
         ("uav_fault_estimator", "detector_node"))
EVENT_GAP_S = (20.0, 60.0)
RESIDUAL_PERIOD_S = residual_update_period_s()
INJECTED = ("residual_1e300", "sensitivity_1e300", "wind_source_7")  # residuals to mhe_node
KINDS = ("velocity_1e200", "velocity_1e6", "rates_1e6", "nan", "inf", "duplicate",
         "backwards", "far_ahead", "lost_controls", "glitch_30mps", "air_data_lost",
         *INJECTED)
SPANS_S = {"velocity_1e200": 2.0, "velocity_1e6": 0.5, "rates_1e6": 0.5, "nan": 1.0,
           "inf": 1.0, "air_data_lost": 30.0}  # the others touch one sample
VELOCITY_NORTH = STATE_CHANNELS.index("velocity_north")
RATES = [STATE_CHANNELS.index(name) for name in ("roll_rate", "pitch_rate", "yaw_rate")]
AILERON = CONTROL_CHANNELS.index("aileron")


@dataclass(frozen=True)
class Event:
    kind: str
    start_s: float
    span_s: float


def schedule(duration_s: float, seed: int) -> list[Event]:
    """Events every EVENT_GAP_S from 30 s on, kinds drawn uniformly."""
    rng = np.random.default_rng(seed)
    events, time_s = [], 30.0
    while time_s < duration_s - 10.0:
        kind = str(rng.choice(KINDS))
        start = round(time_s / 0.05) * 0.05  # on a sensor sample
        if kind in INJECTED:  # 0.4 of a residual period past a residual stamp
            start = round((math.floor(time_s / RESIDUAL_PERIOD_S) + 0.8) * RESIDUAL_PERIOD_S, 6)
        events.append(Event(kind, start, SPANS_S.get(kind, 0.05)))
        time_s += rng.uniform(*EVENT_GAP_S)
    return events


class Corruptor:
    """The replayer's corruption of /dirty: the scheduled events, sample by sample."""

    def __init__(self, events: list[Event], residual_publisher, period_s: float,
                 wait_for_estimate: Callable[[float], None]) -> None:
        self.events = events
        self.residual_publisher = residual_publisher
        self.period_s = period_s
        self.wait_for_estimate = wait_for_estimate
        self.previous: dict[str, tuple[float, np.ndarray]] = {}

    def active(self, time_s: float) -> list[Event]:
        return [e for e in self.events if e.start_s - 1e-6 <= time_s < e.start_s + e.span_s - 1e-6]

    def __call__(self, sample: FlightSample, topic: str, values: np.ndarray):
        time_s, out = sample.time_s, [(sample.time_s, values)]
        for event in self.active(time_s):
            altered = values.copy()
            kind = event.kind
            if topic == "state" and kind in ("velocity_1e200", "velocity_1e6", "rates_1e6",
                                             "nan"):
                value = {"velocity_1e200": 1e200, "velocity_1e6": 1e6, "nan": math.nan}.get(kind)
                if kind == "rates_1e6":
                    altered[RATES] = 1e6
                else:
                    altered[VELOCITY_NORTH] = value
                out = [(time_s, altered)]
            elif topic == "controls" and kind == "inf":
                altered[AILERON] = math.inf
                out = [(time_s, altered)]
            elif topic == "controls" and kind == "lost_controls":
                out = []
            elif topic == "state" and kind == "glitch_30mps":
                altered[VELOCITY_NORTH] += 30.0
                out = [(time_s, altered)]
            elif topic == "air_data" and kind == "air_data_lost":
                out = []
            elif kind == "duplicate" and topic in self.previous:
                out.append(self.previous[topic])
            elif kind == "backwards":
                out.append((time_s - 5.0, values))
            elif kind == "far_ahead":
                out.append((1e6, values))
            elif kind in INJECTED and topic == "state":
                stamp_s = injected_stamp(event, self.period_s)
                # in order: after the real residual before it has reached the estimator
                self.wait_for_estimate(stamp_s - 0.5 * self.period_s)
                self.residual_publisher.publish(absurd_residual(stamp_s, kind))
        self.previous[topic] = (time_s, values)
        return out


def injected_stamp(event: Event, period_s: float) -> float:
    """Where an absurd residual goes: half-way between two of residual_node's stamps, after
    the one the replay has passed (events of this kind start 0.4 of a period past it)."""
    return round((math.floor(event.start_s / period_s + 1e-6) + 0.5) * period_s, 6)


def absurd_residual(time_s: float, kind: str) -> Residuals:
    """The residual an INJECTED event sends: y of 1e300, S of 1e300 or wind_source 7."""
    columns = len(PAPER_FAULT_NAMES)
    return Residuals(
        header=header(time_s), residual=[1e300 if kind == "residual_1e300" else 0.0] * 6,
        observed=[0.0] * 6, predicted=[0.0] * 6, valid=[True] * 6,
        wind_source=7 if kind == "wind_source_7" else Residuals.WIND_AIR_DATA,
        fault_names=list(PAPER_FAULT_NAMES),
        sensitivity=[1e300 if kind == "sensitivity_1e300" else 0.0] * 6 * columns)


def rss_mb(pid: int) -> float:
    """Resident memory of a process [MB] (0 if it is gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def disturbed(time_s: float, events: list[Event], settle_s: float) -> bool:
    return any(e.start_s <= time_s <= e.start_s + e.span_s + settle_s for e in events)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1800.0, help="sim time [s]")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=Path)
    arguments = parser.parse_args()
    domain_id, lock = reserve_domain_id()
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    from uav_common.ros.graph_probe import RosGraph  # after the domain is set

    started = time.monotonic()
    flight = simulated_flight(load_scenario(default_scenario_path()), arguments.duration)
    events = schedule(arguments.duration, arguments.seed)
    print(f"flight of {arguments.duration:g} s flown by the core in "
          f"{time.monotonic() - started:.0f} s; {len(events)} events on /dirty; "
          f"ROS domain {domain_id}", flush=True)
    logs = Path(tempfile.mkdtemp(prefix="soak_"))
    processes = {(namespace, executable): RosProcess(
        ros2_run_argv(package, executable, ros_args=["-r", f"__ns:={namespace}"]),
        logs / f"{executable}{namespace.replace('/', '_')}.log")
        for namespace in (CLEAN, DIRTY) for package, executable in NODES}
    graph = RosGraph()
    try:
        estimates = graph.subscribe({f"{n}/faults/estimate": FaultEstimate
                                     for n in (CLEAN, DIRTY)}, STREAM_QOS)
        residual_publisher = graph.node.create_publisher(Residuals, f"{DIRTY}/residuals",
                                                         STREAM_QOS)
        replayer = Replayer(graph, (CLEAN, DIRTY))
        # state and controls: residual_node and detector_node; the others: residual_node
        if not replayer.wait_for_subscribers({"state": 2, "controls": 2}, timeout_s=60):
            print("soak: the nodes did not subscribe within 60 s", file=sys.stderr)
            return 1
        graph.spin(60.0, until=lambda: residual_publisher.get_subscription_count() >= 1)
        memory_start = {executable: rss_mb(processes[(DIRTY, executable)].pid)
                        for _, executable in NODES}
        clean, dirty = estimates[f"{CLEAN}/faults/estimate"], estimates[f"{DIRTY}/faults/estimate"]

        def wait_for_estimate(stamp_s: float) -> None:
            replayer.wait_for_acknowledgements()
            graph.spin(30.0, until=lambda: any(
                abs(stamp_seconds(m.header.stamp) - stamp_s) < 1e-6 for m in dirty[-20:]))

        replayer.play(flight, CLEAN, DIRTY, Corruptor(events, residual_publisher,
                                                      RESIDUAL_PERIOD_S, wait_for_estimate))
        expected = round(arguments.duration / RESIDUAL_PERIOD_S)
        # each answered by an INVALID_DATA estimate; wind_source 7 is dropped unanswered
        injected = {injected_stamp(e, RESIDUAL_PERIOD_S) for e in events
                    if e.kind in ("residual_1e300", "sensitivity_1e300")}
        graph.spin(120.0, until=lambda: len(clean) >= expected
                   and len(dirty) >= expected + len(injected))
        graph.spin(2.0)
        memory_end = {executable: rss_mb(processes[(DIRTY, executable)].pid)
                      for _, executable in NODES}
        wall_s = time.monotonic() - started
    finally:
        stop_all(list(processes.values()))
        graph.close()
        lock.close()
    settle_s = (ResidualSettings().recovery_s
                + EstimatorSettings().horizon * RESIDUAL_PERIOD_S)
    clean_at = {round(stamp_seconds(m.header.stamp), 6): np.array(m.values_pct) for m in clean}
    dirty_at = {round(stamp_seconds(m.header.stamp), 6): np.array(m.values_pct) for m in dirty}
    grid = {round(k * RESIDUAL_PERIOD_S, 6) for k in range(1, expected + 1)}
    common = sorted(set(clean_at) & set(dirty_at) & grid)
    outside = [t for t in common if not disturbed(t, events, settle_s)]
    inside = [t for t in common if disturbed(t, events, settle_s)]

    def largest(stamps: list[float]) -> tuple[float, float] | None:
        """The largest |dirty - clean| estimate [%] over stamps, and its stamp [s]."""
        errors = [(float(np.abs(dirty_at[t] - clean_at[t]).max()), t) for t in stamps]
        return max(errors, default=None)

    summary = {
        "duration_s": arguments.duration, "seed": arguments.seed, "events": len(events),
        "event_kinds": {k: sum(e.kind == k for e in events) for k in KINDS},
        "event_times_s": {k: [round(e.start_s, 2) for e in events if e.kind == k]
                          for k in KINDS},
        "estimates_expected": expected, "estimates_clean": len(clean),
        "estimates_dirty": len(dirty), "residuals_injected": len(injected),
        "estimates_lost_clean": sorted(grid - set(clean_at)),
        "estimates_lost_dirty": sorted((grid | injected) - set(dirty_at)),
        "estimates_unexpected": sorted((set(clean_at) - grid) | (set(dirty_at) - grid - injected)),
        "settle_s": settle_s, "stamps_outside": len(outside), "stamps_inside": len(inside),
        "largest_error_outside_pct_at_s": largest(outside),
        "largest_error_inside_pct_at_s": largest(inside),
        "memory_start_mb": memory_start, "memory_end_mb": memory_end, "wall_s": round(wall_s),
    }
    for key, value in summary.items():
        print(f"{key}: {value}")
    print(f"node logs: {logs}")
    if arguments.json:
        arguments.json.write_text(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
