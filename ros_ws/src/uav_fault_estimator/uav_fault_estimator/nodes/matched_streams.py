"""Subscriptions whose messages are matched by stamp (stamp_matching.py) for a node: the
ROS side shared by residual_node and detector_node."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from rclpy.node import Node
from uav_common.message_fields import stamp_nanoseconds
from uav_common.ros.node_tools import STREAM_QOS
from uav_common.ros.paced_publishing import ACK_EVERY_SAMPLES
from uav_sim.envelope import gate

from uav_fault_estimator.nodes.stamp_matching import StampGuard, StampMatcher, StampVerdict

# How many newer complete sets an optional message is waited for: a simulator in fast
# mode has up to ACK_EVERY_SAMPLES samples per stream in flight, and the callbacks of
# different streams interleave freely within them (with 20 and batches of 40, a CI run's
# residual_node took some samples without their air data: estimates off the offline
# chain's by up to 1 %).
OPTIONAL_WAIT_SETS = 2 * ACK_EVERY_SAMPLES
# (message type, message -> array, the array's envelope (low, high) arrays) per topic
Streams = dict[str, tuple[type, Callable[[Any], Any], tuple[np.ndarray, np.ndarray]]]


def checked_stamp(node: Node, guard: StampGuard, topic: str, stamp_ns: int,
                  restart_note: str) -> StampVerdict:
    """guard.check(stamp_ns), said on the node's log: a stray (at most every 5 s) and a
    restart (ending with restart_note: what the caller does about it)."""
    verdict = guard.check(stamp_ns)
    if verdict is StampVerdict.STRAY:
        node.get_logger().warning(
            f"{topic} stamp {stamp_ns / 1e9:.3f} s is out of order (a duplicate, one going "
            "backwards or far ahead): message dropped", throttle_duration_sec=5.0)
    elif verdict is StampVerdict.RESTART:
        node.get_logger().warning(f"{topic} stamps restarted at {stamp_ns / 1e9:.3f} s: the "
                                  f"source restarted, {restart_note}")
    return verdict


class MatchedStreams:
    """Subscribes each topic (reliable, keep-all) in the order given: sim_node's
    wait_for_subscribers counts `state` subscriptions, so list `state` last. Complete sets
    go to on_sample(time_s, arrays by topic) in stamp order, with the optional topics'
    arrays where they came (waited for, for up to StampMatcher.optional_wait newer sets,
    while the topic has a publisher or may still have messages queued). A required message
    whose stamp is a stray (StampGuard: a duplicate, one going backwards or far ahead) is
    dropped and counted; a restarted source (several such stamps in a row) is warned of
    (ending with restart_note: what on_restart does), resets the matcher and calls
    on_restart() first."""

    def __init__(self, node: Node, streams: Streams,
                 on_sample: Callable[[float, dict[str, Any]], None],
                 on_restart: Callable[[], None], restart_note: str,
                 optional: Streams | None = None) -> None:
        self.node = node
        optional = optional or {}
        self.to_array = {topic: convert for topic, (_, convert, _)
                         in {**optional, **streams}.items()}
        self.limits = {topic: limits for topic, (*_, limits) in {**optional, **streams}.items()}
        self.matcher = StampMatcher(tuple(streams), tuple(optional), self.has_publisher,
                                    optional_wait=OPTIONAL_WAIT_SETS)
        self.on_sample, self.on_restart = on_sample, on_restart
        self.restart_note = restart_note
        self.restarts = 0
        self.stray_messages = 0
        self.implausible_values = 0  # outside the aircraft's envelope: taken as missing
        for topic, (message_type, *_) in {**optional, **streams}.items():
            node.create_subscription(
                message_type, topic, lambda message, topic=topic: self.receive(topic, message),
                STREAM_QOS)

    def plausible(self, topic: str, message: Any) -> np.ndarray:
        """The message as an array, values outside the aircraft's envelope NaN (missing: the
        core holds the last good value and marks what depends on it), said and counted."""
        values, implausible = gate(self.to_array[topic](message), self.limits[topic])
        if implausible:
            self.implausible_values += implausible
            self.node.get_logger().warning(
                f"{topic} at {stamp_nanoseconds(message.header.stamp) / 1e9:.3f} s: "
                f"{implausible} value(s) outside the aircraft's envelope, taken as missing",
                throttle_duration_sec=5.0)
        return values

    def has_publisher(self, topic: str) -> bool:
        """Whether some node publishes this topic now."""
        return self.node.count_publishers(topic) > 0

    @property
    def late_optional(self) -> int:
        """Optional messages that came after their set had gone without them."""
        return self.matcher.late_optional

    @property
    def dropped_sets(self) -> int:
        """Stamps dropped because some stream's message never came."""
        return self.matcher.dropped_sets

    def receive(self, topic: str, message: Any) -> None:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        if topic in self.matcher.streams:
            verdict = checked_stamp(self.node, self.matcher.guard, topic, stamp_ns,
                                    self.restart_note)
            if verdict is StampVerdict.STRAY:
                self.stray_messages += 1
                return
            if verdict is StampVerdict.RESTART:
                self.matcher.reset()
                self.restarts += 1
                self.on_restart()
        values = self.plausible(topic, message)
        for sample_ns, payloads in self.matcher.add(topic, stamp_ns, values):
            self.on_sample(sample_ns / 1e9, payloads)
