#!/usr/bin/env python3
"""The onboard graph's cost behind an autopilot's MAVLink link: CPU seconds per flight
second and peak memory of each node.

    python -m benchmarks.bench_onboard [SCENARIO.yaml] [--stack ardupilot|px4]
                                       [--duration S] [--json FILE]

Flies demo.sh --via-mavlink's graph (uav_fault_estimator.chain.demo_run: sim_node and the
autopilot_node that plays the stack, mavlink_node on the loopback link, residual_node,
mhe_node, detector_node, recorder_node) for --duration seconds of the scenario, and reads
every node process's /proc entries every POLL_S while it runs (the nodes are those whose
ROS_LOG_DIR is the run's): its CPU time (user + system) spent while the aircraft flies (start-
up and shutdown left out) and its peak resident memory (VmHWM). Printed and written: per
node, CPU-s per flight second and peak MB, and the bridge's
(mavlink_node) CPU against residual_node's (the aim: at most a quarter). sim_node and
autopilot_node stand for the aircraft: they do not run on the companion computer. The
simulator runs at the stack's node_graph.LINK_REAL_TIME_FACTOR times real time, so the
link's rates per wall second are that many times an aircraft's: the figures per flight
second are what an aircraft's companion computer would spend, its timers' idle polling
aside (mavlink_node reads the link every 5 ms of wall time, at most 200 reads a second
whatever the rate).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from uav_fault_estimator.chain import node_graph
from uav_fault_estimator.chain.demo_run import EXIT_TARGET_MISSED
from uav_sim.scenario import default_scenario_path

DEMO = Path(__file__).resolve().parent.parent / "scripts" / "demo.py"

POLL_S = 0.2  # how often /proc is read [s, wall time]
NODES = ("sim_node", "autopilot_node", "mavlink_node", "residual_node", "mhe_node",
         "detector_node", "recorder_node")
ON_THE_AIRCRAFT = ("sim_node", "autopilot_node")  # the aircraft played, not the companion's
TICKS_PER_S = os.sysconf("SC_CLK_TCK")


def node_of(pid: int, logs: Path) -> str | None:
    """The node a process runs, when it is one of the run's (its ROS_LOG_DIR is logs)."""
    try:
        environ = Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return None
    if f"ROS_LOG_DIR={logs}".encode() not in environ:
        return None
    words = {Path(word.decode(errors="replace")).name for word in cmdline}
    return next((node for node in NODES if node in words), None)


def usage(pid: int) -> tuple[float, float] | None:
    """A process's CPU time [s] (user + system) and peak resident memory [MB], or None
    once it has gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    cpu_s = (int(fields[11]) + int(fields[12])) / TICKS_PER_S  # utime, stime (fields 14, 15)
    peak_kb = next((int(line.split()[1]) for line in status.splitlines()
                    if line.startswith("VmHWM:")), 0)
    return cpu_s, peak_kb / 1024


def node_usage(logs: Path, seen: dict[int, str]) -> dict[str, tuple[float, float]]:
    """Each running node's CPU time [s] and peak memory [MB] now (a node of several
    processes: their sum and largest); seen: pid -> node, kept across calls."""
    nodes: dict[str, tuple[float, float]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        pid = int(entry.name)
        if pid not in seen:
            node = node_of(pid, logs)
            if node is None:
                continue
            seen[pid] = node
        measured = usage(pid)
        if measured is not None:
            cpu_s, peak_mb = nodes.get(seen[pid], (0.0, 0.0))
            nodes[seen[pid]] = (cpu_s + measured[0], max(peak_mb, measured[1]))
    return nodes


def fly(scenario: Path, stack: str, duration_s: float, out: Path) -> dict[str, dict]:
    """Run the demo through the link; per node, the CPU time [s] it spent while the aircraft
    flew (from demo_run's "flying" line to its "flown in" line: start-up, imports and
    shutdown left out) and its peak memory [MB]."""
    logs = out / "logs"
    demo = subprocess.Popen(
        [sys.executable, str(DEMO), str(scenario), "--via-mavlink", stack,
         "--duration", f"{duration_s:g}", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(demo.stdout or []), daemon=True)
    reader.start()
    seen: dict[int, str] = {}
    at: dict[str, dict[str, tuple[float, float]]] = {}  # marker -> node usage then
    peak_mb: dict[str, float] = {}
    last: dict[str, tuple[float, float]] = {}  # each node's last usage seen (sim_node ends
    while demo.poll() is None:                 # with the flight, before "flown in")
        now = node_usage(logs, seen)
        last.update(now)
        for node, (_, peak) in now.items():
            peak_mb[node] = max(peak_mb.get(node, 0.0), peak)
        for marker in ("flying", "flown in"):
            if marker not in at and any(line.startswith(marker) for line in lines):
                at[marker] = dict(last)
        time.sleep(POLL_S)
    reader.join()
    output = "".join(lines)
    if demo.returncode not in (0, EXIT_TARGET_MISSED) or len(at) < 2:
        raise SystemExit(f"bench_onboard: the demo failed ({demo.returncode}):\n{output}")
    print(output.rstrip())
    return {node: {"cpu_s": at["flown in"][node][0] - at["flying"][node][0],
                   "peak_mb": peak_mb[node]}
            for node in at["flown in"] if node in at["flying"]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", type=Path, default=default_scenario_path())
    parser.add_argument("--stack", choices=tuple(node_graph.LINK_REAL_TIME_FACTOR),
                        default="ardupilot")
    parser.add_argument("--duration", type=float, default=120.0, metavar="S")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    arguments = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_onboard_") as folder:
        nodes = fly(arguments.scenario, arguments.stack, arguments.duration,
                    Path(folder) / "run")
    missing = sorted(set(NODES) - set(nodes))
    if missing:
        print(f"bench_onboard: no process seen of {', '.join(missing)}", file=sys.stderr)
        return 1
    for figures in nodes.values():
        figures["cpu_s_per_flight_s"] = figures["cpu_s"] / arguments.duration
    bridge_share = nodes["mavlink_node"]["cpu_s"] / nodes["residual_node"]["cpu_s"]
    print(f"{'node':<16} {'CPU-s per flight s':>19} {'peak MB':>8}")
    for node in NODES:
        figures = nodes[node]
        note = "  (the aircraft, played)" if node in ON_THE_AIRCRAFT else ""
        print(f"{node:<16} {figures['cpu_s_per_flight_s']:>19.4f} {figures['peak_mb']:>8.1f}"
              f"{note}")
    print(f"mavlink_node's CPU is {bridge_share:.1%} of residual_node's (aim: at most 25 %)")
    if arguments.json:
        arguments.json.write_text(json.dumps({
            "scenario": arguments.scenario.name, "stack": arguments.stack,
            "duration_s": arguments.duration, "nodes": nodes,
            "on_the_aircraft": list(ON_THE_AIRCRAFT),
            "bridge_cpu_share_of_residual_node": bridge_share}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
