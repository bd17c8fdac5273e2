"""Publishes /clock running twice as fast as the wall clock and /sim_ticks at 20 Hz of that
simulated time (40 Hz of wall time), until interrupted: `ros2 topic hz` test fixture."""

import sys
from pathlib import Path

from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import UInt32

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from helpers.fixture_node import run_timer_node

SIM_STEP_NS = 50_000_000  # 20 Hz of simulated time
WALL_PERIOD_S = 0.025  # real-time factor 2


def clock_and_ticks(node):
    """The tick: the next /clock and sim_ticks message."""
    clock = node.create_publisher(
        Clock, "/clock", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    )
    ticks = node.create_publisher(UInt32, "sim_ticks", 10)
    step = 0

    def tick() -> None:
        nonlocal step
        step += 1
        now = Clock()
        now.clock.sec, now.clock.nanosec = divmod(step * SIM_STEP_NS, 1_000_000_000)
        clock.publish(now)
        ticks.publish(UInt32(data=step))

    return tick


def main() -> None:
    run_timer_node("clock_publisher", WALL_PERIOD_S, clock_and_ticks)


if __name__ == "__main__":
    main()
