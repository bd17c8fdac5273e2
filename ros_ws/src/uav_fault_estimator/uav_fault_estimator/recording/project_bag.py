"""A rosbag2 recording (MCAP storage) written with the `rosbags` library, without rosbag2.

ROS 2 from PyPI has no rosbag2; `rosbags` writes the same directory format (metadata.yaml
and an .mcap file) that `ros2 bag` and the report read. Messages arrive already serialized
(CDR), so nothing is decoded on the way. The project's own message types are registered
from their .msg definitions; the standard ones come with rosbags' ROS 2 Jazzy type store.
"""

from __future__ import annotations

import contextlib
import struct
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yaml
from rosbags.interfaces import Qos
from rosbags.rosbag2 import Reader, ReaderError, StoragePlugin, Writer
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore
from uav_common.health import VEHICLE_KEY, hardware_id
from uav_common.message_fields import (
    air_data_array,
    controls_array,
    setpoints_array,
    stamp_nanoseconds,
    stamp_seconds,
    state_array,
    wind_array,
)
from uav_common.package_data import share_dir
from uav_common.sample_grid import on_grid

from uav_fault_estimator.detection.detector import DetectorFlight
from uav_fault_estimator.detection.generators import NO_SETPOINTS
from uav_fault_estimator.estimation.model_calibration import SensorFlight

MESSAGE_PACKAGES = ("uav_fault_msgs",)  # the project's own message types
DIAGNOSTICS = "/diagnostics"  # every node's health: the vehicle a recording flew among it


def project_typestore(message_packages: Sequence[str] = MESSAGE_PACKAGES) -> Typestore:
    """ROS 2 Jazzy's standard types plus every .msg of the message packages (their
    installed share folders, or the source tree's)."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    for package in message_packages:
        for definition in sorted((share_dir(package) / "msg").glob("*.msg")):
            typestore.register(get_types_from_msg(
                definition.read_text(), f"{package}/msg/{definition.stem}"))
    return typestore


class Recording:
    """An open rosbag2 directory: topics are added as they appear, messages written raw."""

    def __init__(self, path: Path, typestore: Typestore) -> None:
        self.path = path
        self.typestore = typestore
        self.writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self.connections: dict[str, object] = {}
        self.counts: dict[str, int] = {}
        # per topic, the wall clock of its first and last message [ns] (the log times may be
        # sim time): metadata.yaml's custom_data at close
        self.wall_span_ns: dict[str, list[int]] = {}

    def add_topic(self, topic: str, message_type: str,
                  offered_qos: Sequence[Qos] = ()) -> None:
        """Register a topic with its publishers' QoS profiles (metadata.yaml's
        offered_qos_profiles, what `ros2 bag play` offers again); ValueError for a type the
        type store does not know."""
        if message_type not in self.typestore.fielddefs:
            raise ValueError(f"no definition of {message_type} for topic {topic}")
        self.connections[topic] = self.writer.add_connection(
            topic, message_type, typestore=self.typestore, offered_qos_profiles=offered_qos)
        self.counts[topic] = 0

    def write(self, topic: str, timestamp_ns: int, data: bytes) -> None:
        """One serialized (CDR) message of a registered topic at timestamp_ns."""
        self.writer.write(self.connections[topic], timestamp_ns, data)
        self.counts[topic] += 1
        now_ns = time.time_ns()
        self.wall_span_ns.setdefault(topic, [now_ns, now_ns])[1] = now_ns

    def close(self) -> None:
        """Finish the files: summary and metadata.yaml. Safe to call twice."""
        if self.writer is not None:
            for topic, (first_ns, last_ns) in self.wall_span_ns.items():
                self.writer.set_custom_data(WALL_SPAN_KEY + topic, f"{first_ns} {last_ns}")
            self.writer.close()
            self.writer = None


WALL_S = "wall_s"  # the key of read_topics' wall time the recording spans [s]
# metadata.yaml custom_data, per topic: "<first> <last>", its messages' wall clock [ns]
WALL_SPAN_KEY = "uav.wall_span_ns:"


class RecordingError(ValueError):
    """A recording that cannot be read; the message (one line) names it and says why."""


# What a damaged recording raises while it is opened, read or decoded (measured on truncated,
# empty, random and byte-flipped files and metadata): rosbags' own errors, the file
# system's, and what its parsers meet in damaged bytes or metadata (wrong lengths, offsets,
# encodings, record kinds, value types).
_DAMAGED = (ReaderError, SerdeError, OSError, ValueError, TypeError, AttributeError,
            struct.error, OverflowError, IndexError, KeyError, MemoryError)


def read_topics(bag: Path, typestore: Typestore, topics: tuple[str, ...],
                namespace: str = "") -> dict[str, list]:
    """The decoded messages of each topic of a recording, in recording order, and under
    WALL_S the wall time the recording spans [s] (wall_span_s). RecordingError (one line naming the
    recording) when it is not a rosbag2 folder or cannot be read or decoded. namespace
    ("/uav1"): read the topics under it (a namespaced run), keyed by their names without it
    (/clock stays global)."""
    bag = Path(bag)
    if not bag.is_dir():
        raise RecordingError(f"recording {bag}: " + (
            "not a folder (a rosbag2 recording is a folder with metadata.yaml)"
            if bag.exists() else "no such folder"))
    if not (bag / "metadata.yaml").is_file():
        raise RecordingError(f"recording {bag}: no metadata.yaml (not a rosbag2 recording)")
    messages: dict[str, list] = {topic: [] for topic in topics}
    received_ns: list[int] = []
    try:
        with Reader(bag) as reader:
            recorded = {in_namespace(topic, namespace): topic for topic in topics}
            wanted = [c for c in reader.connections if c.topic in recorded]
            # rosbags reads every connection when given none
            for connection, timestamp_ns, raw in (
                    reader.messages(connections=wanted) if wanted else ()):
                messages[recorded[connection.topic]].append(
                    typestore.deserialize_cdr(raw, connection.msgtype))
                received_ns.append(timestamp_ns)
    except _DAMAGED as error:
        reason = " ".join(str(error).split()) or type(error).__name__
        raise RecordingError(
            f"recording {bag}: unreadable, damaged or not rosbag2 ({reason})") from None
    messages[WALL_S] = wall_span_s(bag, tuple(recorded), received_ns)
    return messages


def in_namespace(topic: str, namespace: str) -> str:
    """An absolute topic name under a namespace ("" or "/": none); /clock is global."""
    return topic if topic == "/clock" else namespace.rstrip("/") + topic


def wall_span_s(bag: Path, topics: tuple[str, ...], received_ns: list[int]) -> float:
    """The wall time the topics' messages span in a recording [s]: from metadata.yaml's
    custom_data where the recorder wrote it, else from their log times (a recording made
    on wall time)."""
    with contextlib.suppress(OSError, yaml.YAMLError, KeyError, TypeError, ValueError):
        custom = yaml.safe_load((bag / "metadata.yaml").read_text())[
            "rosbag2_bagfile_information"]["custom_data"]
        spans = [[int(v) for v in custom[WALL_SPAN_KEY + topic].split()] for topic in topics
                 if WALL_SPAN_KEY + topic in custom]
        if spans:
            return 1e-9 * (max(last for _, last in spans) - min(first for first, _ in spans))
    return 1e-9 * (max(received_ns) - min(received_ns)) if received_ns else 0.0


def recorded_vehicle(bag: Path, typestore: Typestore) -> str | None:
    """The vehicle a recording says flew: what its aircraft's source (sim_node, mavlink_node)
    said on /diagnostics (uav_common.health.VEHICLE_KEY) in the recording's root namespace;
    None where none said it. RecordingError (one line naming the recording) when it cannot
    be read, or when two vehicles are said."""
    said = {item.value for array in read_topics(bag, typestore, (DIAGNOSTICS,))[DIAGNOSTICS]
            for status in array.status if status.hardware_id == hardware_id("")
            for item in status.values if item.key == VEHICLE_KEY}
    if len(said) > 1:
        raise RecordingError(f"recording {bag}: its /diagnostics say that "
                             f"{' and '.join(sorted(said))} flew")
    return said.pop() if said else None


def flight_from_recording(bag: Path, typestore: Typestore, period_s: float) -> DetectorFlight:
    """A recorded flight's /state and /controls matched by stamp, every period_s [s] of sim
    time, with /air_data's airspeed and /autopilot_setpoints where recorded (NaN where not),
    as offline.fly_on_grid gives them for a simulated one (its detector_flight).
    ValueError naming the bag when /state or /controls is missing or they share no stamp on
    the grid."""
    messages = read_topics(bag, typestore, ("/state", "/controls", "/air_data",
                                            "/autopilot_setpoints"))
    by_stamp = {topic: {stamp_nanoseconds(message.header.stamp): message
                        for message in messages[topic]}
                for topic in ("/controls", "/air_data", "/autopilot_setpoints")}
    controls = by_stamp["/controls"]
    if not messages["/state"] or not controls:
        raise ValueError(f"{bag}: no /state or no /controls recorded")
    rows = []
    for message in messages["/state"]:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        time_s = stamp_seconds(message.header.stamp)
        if stamp_ns in controls and on_grid(time_s, period_s):
            air_data = by_stamp["/air_data"].get(stamp_ns)
            setpoints = by_stamp["/autopilot_setpoints"].get(stamp_ns)
            rows.append((time_s, state_array(message), controls_array(controls[stamp_ns]),
                         np.nan if air_data is None else air_data_array(air_data)[0],
                         NO_SETPOINTS if setpoints is None else setpoints_array(setpoints)))
    if not rows:
        raise ValueError(f"{bag}: /state and /controls share no stamp on the {period_s:g} s grid")
    return DetectorFlight(*(np.array(column) for column in zip(*rows, strict=True)))


def sensor_flight_from_recording(bag: Path, typestore: Typestore) -> SensorFlight:
    """A recorded fault-free flight at the sensor rate, as a model calibration reads it:
    /state, /controls and /wind/filtered matched by stamp, with /air_data where recorded
    (NaN rows where not). RecordingError naming the bag when one of the three streams is
    missing, when they share no stamp, or when /faults/seeded has a fault seeded in it."""
    messages = read_topics(bag, typestore,
                           ("/state", "/controls", "/wind/filtered", "/air_data", "/faults/seeded"))
    by_stamp = {topic: {stamp_nanoseconds(m.header.stamp): m for m in messages[topic]}
                for topic in ("/controls", "/wind/filtered", "/air_data")}
    for topic in ("/state", "/controls", "/wind/filtered"):
        if not messages[topic]:
            raise RecordingError(f"recording {bag}: no {topic} recorded (a calibration needs "
                                 "/state, /controls and /wind/filtered)")
    for message in messages["/faults/seeded"]:
        seeded = [name for name, value in zip(message.names, message.values_pct, strict=True)
                  if value != 0.0]
        if seeded:
            raise RecordingError(
                f"recording {bag}: not a fault-free flight ({', '.join(seeded)} seeded at "
                f"{stamp_seconds(message.header.stamp):g} s)")
    rows = []
    for message in messages["/state"]:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        controls = by_stamp["/controls"].get(stamp_ns)
        wind = by_stamp["/wind/filtered"].get(stamp_ns)
        if controls is None or wind is None:
            continue
        air_data = by_stamp["/air_data"].get(stamp_ns)
        rows.append((stamp_seconds(message.header.stamp), state_array(message),
                     controls_array(controls), wind_array(wind),
                     np.full(3, np.nan) if air_data is None else air_data_array(air_data)))
    if not rows:
        raise RecordingError(f"recording {bag}: /state, /controls and /wind/filtered share "
                             "no stamp")
    times, states, inputs, winds, air_data = (np.array(c) for c in zip(*rows, strict=True))
    return SensorFlight(str(bag), times, states, inputs, winds, air_data)
