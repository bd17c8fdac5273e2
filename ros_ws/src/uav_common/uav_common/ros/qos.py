"""QoS per kind of topic, the one home of each node's choice (no other module states one)."""

from __future__ import annotations

from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)

# Sensor-rate streams and estimates, by each node's `qos` parameter. "reliable" (the
# default): keep-all, so that a fast simulation loses nothing while subscribers catch up;
# a slow subscriber holds its publisher back. "sensor_data": ROS's profile (best effort, the
# newest 5), so that no subscriber holds a publisher back; messages may be lost. A reliable
# subscription does not match a best-effort publisher (DDS): choose it on every node.
STREAM_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
STREAM_QOS_PROFILES = {"reliable": STREAM_QOS, "sensor_data": qos_profile_sensor_data}
# /clock: only the newest time matters.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
DIAGNOSTICS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
