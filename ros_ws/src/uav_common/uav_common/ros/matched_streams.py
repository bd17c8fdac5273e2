"""Subscriptions whose messages are matched by stamp (uav_common.stamp_matching) for a node:
the ROS side shared by residual_node, detector_node and autopilot_node."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from rclpy.node import Node
from rclpy.qos import QoSProfile

from uav_common.envelope import RateGate, gate
from uav_common.message_fields import stamp_nanoseconds
from uav_common.ros.paced_publishing import ACK_EVERY_SAMPLES
from uav_common.stamp_matching import GuardedStream, StampMatcher, StampVerdict

# How many newer complete sets an optional message is waited for: a simulator in fast
# mode has up to ACK_EVERY_SAMPLES samples per stream in flight, and the callbacks of
# different streams interleave freely within them (with 20 and batches of 40, a CI run's
# residual_node took some samples without their air data: estimates off the offline
# chain's by up to 1 %).
OPTIONAL_WAIT_SETS = 2 * ACK_EVERY_SAMPLES
# Per topic: message type, message -> array, the array's envelope (low, high) arrays, and
# a RateGate factory for a stream whose glitches are told by their rate (or None).
Streams = dict[str, tuple[type, Callable[[Any], Any], tuple[np.ndarray, np.ndarray],
                          Callable[[], RateGate] | None]]


def guarded(node: Node, stream: GuardedStream, topic: str, stamp_ns: int, payload: Any,
            restart_note: str) -> tuple[StampVerdict, list[tuple[int, Any]]]:
    """stream.feed(stamp_ns, payload), said on the node's log: a stray (at most every 5 s),
    a gap (once each) and a restart (ending with restart_note: what the caller does)."""
    verdict, taken = stream.feed(stamp_ns, payload)
    if verdict is StampVerdict.STRAY:
        node.get_logger().warning(
            f"{topic} stamp {stamp_ns / 1e9:.3f} s is out of order (a duplicate, one going "
            "backwards or far ahead): message dropped", throttle_duration_sec=5.0)
    elif verdict is StampVerdict.GAP:
        node.get_logger().info(f"{topic} resumed at {taken[0][0] / 1e9:.3f} s after a gap of "
                               f"{stream.guard.last_gap_ns / 1e9:.2f} s")
    elif verdict is StampVerdict.RESTART:
        node.get_logger().warning(f"{topic} stamps restarted at {stamp_ns / 1e9:.3f} s: the "
                                  f"source restarted, {restart_note}")
    return verdict, taken


class MatchedStreams:
    """Subscribes each topic (with the node's stream qos) in the order given, on
    subscribe(): sim_node's wait_for_subscribers counts `state` subscriptions, so list
    `state` last. Complete sets go to on_sample(time_s, arrays by topic) in stamp order,
    with the optional topics' arrays where they came (waited for, for up to
    StampMatcher.optional_wait newer sets, while the topic has a publisher or may still have
    messages queued). A required message whose stamp is a stray (StampGuard: a duplicate,
    one going backwards or far ahead) is dropped and counted; each required topic's stamps
    are guarded on their own (skew between topics is no stray), a topic resuming after a gap
    is taken (said, counted in `gaps`), and a restarted source (its stamps back, several in
    a row) is warned of (ending with restart_note: what on_restart does), resets the matcher
    and every guard and calls on_restart() first."""

    def __init__(self, node: Node, streams: Streams,
                 on_sample: Callable[[float, dict[str, Any]], None],
                 on_restart: Callable[[], None], restart_note: str, qos: QoSProfile,
                 optional: Streams | None = None) -> None:
        self.node = node
        optional = optional or {}
        self.to_array = {topic: convert for topic, (_, convert, *_)
                         in {**optional, **streams}.items()}
        self.limits = {topic: limits for topic, (_, _, limits, _)
                       in {**optional, **streams}.items()}
        self.rate_gates = {topic: make() for topic, (*_, make)
                           in {**optional, **streams}.items() if make is not None}
        self.matcher = StampMatcher(tuple(streams), tuple(optional), self.has_publisher,
                                    optional_wait=OPTIONAL_WAIT_SETS)
        self.guards = {topic: GuardedStream() for topic in {**optional, **streams}}
        self.on_sample, self.on_restart = on_sample, on_restart
        self.restart_note = restart_note
        self.restarts = 0
        self.gaps = 0  # a required stream resumed after a silence (nothing reset)
        self.implausible_values = 0  # outside the aircraft's envelope: taken as missing
        self.qos = qos
        self.message_types = {topic: message_type for topic, (message_type, *_)
                              in {**optional, **streams}.items()}

    def subscribe(self) -> None:
        """Subscribe every topic, `state` last (when_subscribed calls it)."""
        for topic, message_type in self.message_types.items():
            self.node.create_subscription(
                message_type, topic, lambda message, topic=topic: self.receive(topic, message),
                self.qos)

    def plausible(self, topic: str, message: Any) -> np.ndarray:
        """The message as an array, values outside the aircraft's envelope or changed faster
        than it can change (RateGate: a glitch) NaN (missing: the core holds the last good
        value and marks what depends on it), said and counted."""
        values, implausible = gate(self.to_array[topic](message), self.limits[topic])
        if topic in self.rate_gates:
            values, glitches = self.rate_gates[topic](
                stamp_nanoseconds(message.header.stamp) / 1e9, values)
            implausible += glitches
        if implausible:
            self.implausible_values += implausible
            self.node.get_logger().warning(
                f"{topic} at {stamp_nanoseconds(message.header.stamp) / 1e9:.3f} s: "
                f"{implausible} value(s) outside the aircraft's envelope or its rates, taken "
                "as missing",
                throttle_duration_sec=5.0)
        return values

    def has_publisher(self, topic: str) -> bool:
        """Whether some node publishes this topic now."""
        return self.node.count_publishers(topic) > 0

    @property
    def late_optional(self) -> int:
        """Optional messages that came after their set had gone without them, or with a
        stray stamp."""
        return self.matcher.late_optional + sum(
            self.guards[topic].strays for topic in self.matcher.optional)

    @property
    def dropped_sets(self) -> int:
        """Stamps dropped because some stream's message never came."""
        return self.matcher.dropped_sets

    @property
    def stray_messages(self) -> int:
        """Required messages dropped for their stamps."""
        return sum(self.guards[topic].strays for topic in self.matcher.streams)

    def receive(self, topic: str, message: Any) -> None:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        required = topic in self.matcher.streams
        verdict, taken = guarded(self.node, self.guards[topic], topic, stamp_ns, message,
                                 self.restart_note if required else "its messages taken")
        if verdict is StampVerdict.RESTART and required:
            self.matcher.reset()
            for rate_gate in self.rate_gates.values():
                rate_gate.reset()
            for other in self.guards.values():
                if other is not self.guards[topic]:
                    other.reset()
            self.restarts += 1
            self.on_restart()
        self.gaps += verdict is StampVerdict.GAP and required
        for taken_ns, taken_message in taken:
            self.release(self.matcher.add(topic, taken_ns, self.plausible(topic, taken_message)))

    def release(self, sets: list[tuple[int, dict[str, Any]]]) -> None:
        for sample_ns, payloads in sets:
            self.on_sample(sample_ns / 1e9, payloads)
