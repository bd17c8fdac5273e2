"""Pacing of a node that is the source of the graph's streams (sim_node, log_replay_node):
start once its subscribers are there, then publish at a real-time factor, or, at factor 0,
as fast as every subscriber acknowledges, losing nothing."""

from __future__ import annotations

import time
from collections.abc import Sequence

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import ReliabilityPolicy

from uav_common.ros.parameters import ParameterError

ACK_TIMEOUT_S = 10.0
ACK_POLL_S = 0.1  # wall time per wait for acknowledgements, between checks for SIGINT
DISCOVERY_SETTLE_S = 0.5  # wall time with unchanged subscription counts before starting
# Fast mode waits for acknowledgement every this many samples; in between, the reliable
# keep-all writers hold what is not yet acknowledged, so nothing is lost. Each wait idles
# the publisher while its subscribers drain: fewer waits, more of the two cores busy. The
# default flight through the demo (real-time factor, measured on 2 cores): 17.3 every 10
# samples, 26.4 every 20, 32.4 every 40, 33.2 every 100 (docs/performance.md).
ACK_EVERY_SAMPLES = 40


class PacedPublishers:
    """The source node's stream publishers, the first of them the one whose subscriptions
    wait_for_subscribers counts, and the pacing of what they publish in source time [s]
    (simulation or log time) against wall time. Pacing by acknowledgement (factor 0) needs
    reliable publishers: best-effort ones are never acknowledged (check_factor)."""

    def __init__(self, node: Node, publishers: Sequence[Publisher]) -> None:
        self.node = node
        self.publishers = list(publishers)
        self.acknowledged = all(publisher.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                                for publisher in self.publishers)
        # (wall time [s, monotonic], source time [s]) that the pacing counts from; None:
        # from the next sample on
        self.origin: tuple[float, float] | None = None

    def check_factor(self, real_time_factor: float) -> None:
        """ParameterError (one line) for a factor these publishers cannot be paced at."""
        if real_time_factor == 0 and not self.acknowledged:
            raise ParameterError(
                "real_time_factor 0 (as fast as the subscribers acknowledge) needs qos "
                "reliable: best-effort streams are never acknowledged")

    def wait_for_subscribers(self, wanted: int) -> None:
        """Wait for `wanted` subscriptions of the first publisher, then for discovery to
        settle (none when wanted is 0).

        A subscriber's other topics may be matched a moment after the first: the source
        starts once no stream's subscription count has changed for DISCOVERY_SETTLE_S.
        """
        if wanted <= 0:
            return
        first = self.publishers[0]
        self.node.get_logger().info(
            f"waiting for {wanted} subscription(s) of {first.topic_name}")
        while rclpy.ok() and first.get_subscription_count() < wanted:
            rclpy.spin_once(self.node, timeout_sec=0.05)
        counts, settled_at = None, time.monotonic()
        while rclpy.ok() and time.monotonic() - settled_at < DISCOVERY_SETTLE_S:
            latest = [publisher.get_subscription_count() for publisher in self.publishers]
            if latest != counts:
                counts, settled_at = latest, time.monotonic()
            rclpy.spin_once(self.node, timeout_sec=0.05)

    def wait_until_delivered(self, also: Sequence[Publisher] = ()) -> None:
        """Block until every subscriber has acknowledged what was published on the paced
        publishers and on `also` (no loss), in short slices so that SIGINT ends the wait; a
        subscriber that has not acknowledged within ACK_TIMEOUT_S (it died, and discovery
        has not dropped it yet) is warned of and not waited for any longer."""
        deadline = time.monotonic() + ACK_TIMEOUT_S
        poll = Duration(seconds=ACK_POLL_S)
        for publisher in [*self.publishers, *also]:
            while rclpy.ok() and not publisher.wait_for_all_acked(poll):
                if time.monotonic() > deadline:
                    self.node.get_logger().warning(
                        f"{publisher.topic_name}: a subscriber has not acknowledged for "
                        f"{ACK_TIMEOUT_S:g} s; going on without waiting for it")
                    return

    def start(self, time_s: float) -> None:
        """Count the pace from now, at source time time_s [s] (before the first sample)."""
        self.origin = (time.monotonic(), time_s)

    def restart(self) -> None:
        """Count the pace from the next sample on (a new real-time factor)."""
        self.origin = None

    def pace(self, time_s: float, sample_count: int, real_time_factor: float) -> None:
        """After publishing the sample at source time time_s [s], the sample_count-th: at a
        factor above 0, sleep until wall time has caught up with it (source seconds per
        wall second); at 0, every ACK_EVERY_SAMPLES samples wait until it is delivered."""
        if self.origin is None:
            self.origin = (time.monotonic(), time_s)
        if real_time_factor > 0:
            wall_s, source_s = self.origin
            time.sleep(max(0.0, wall_s + (time_s - source_s) / real_time_factor
                           - time.monotonic()))
        elif sample_count % ACK_EVERY_SAMPLES == 0:
            self.wait_until_delivered()
