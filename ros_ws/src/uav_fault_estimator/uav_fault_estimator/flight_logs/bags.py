"""ROS 1 bags (.bag) and ROS 2 bags (rosbag2 folders) as flight logs, with rosbags.

The topics read and what they mean are topics.py's: MAVROS's (/mavros/imu/data,
/mavros/rc/out, /mavros/vfr_hud) and the project's own recordings' (/state, /controls,
/air_data) by default, others by the topics argument. A message's time is its header stamp
(the log time where it has none), in seconds from the bag's start (its earliest log time).
ROS 1 bags carry their message definitions; for ROS 2 bags without them (sqlite3 storage)
the type store knows ROS 2 Jazzy's, the project's and MAVROS's.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag1 import ReaderError as Ros1ReaderError
from rosbags.rosbag2 import ReaderError as Ros2ReaderError

from uav_fault_estimator.flight_logs.streams import FlightLog
from uav_fault_estimator.flight_logs.topics import (
    MEANINGS,
    LogStreams,
    TopicMeaning,
    checked_topics,
    message_times_s,
    padded_rows,
    register_mavros_types,
    sought_topics,
)
from uav_fault_estimator.recording.project_bag import project_typestore

# What a damaged or foreign file raises in rosbags (besides its own errors): the file
# system's and its parsers' on bytes that are not a bag.
_UNREADABLE = (AnyReaderError, Ros1ReaderError, Ros2ReaderError, OSError, struct.error,
               KeyError, IndexError, UnicodeDecodeError)


def read_bag(path: Path, topics: Mapping[str, str] | None = None,
             axes: str | None = None) -> FlightLog:
    """The flight in a ROS 1 bag file or a ROS 2 bag folder. topics: topic name -> meaning
    (topics.MEANINGS; default topics.DEFAULT_TOPICS); a topic missing from the bag gives no
    stream. axes ("FRD" or "FLU") overrides each message type's own convention. ValueError
    (one line naming the bag) when it cannot be read; a topic of another type is not read
    (a warning)."""
    path = Path(path)
    topics = checked_topics(topics)
    merged = LogStreams()
    start_ns = 0
    try:
        with AnyReader([path], default_typestore=register_mavros_types(
                project_typestore())) as reader:
            wanted = [c for c in reader.connections if c.topic in topics
                      and c.msgtype == MEANINGS[topics[c.topic]].message_type]
            notes = [f"topic {c.topic} is {c.msgtype}, not "
                     f"{MEANINGS[topics[c.topic]].message_type}: not read"
                     for c in reader.connections if c.topic in topics and c not in wanted]
            for topic in sorted({c.topic for c in wanted}):
                meaning = MEANINGS[topics[topic]]
                times_s, fields = _topic_fields(
                    reader, [c for c in wanted if c.topic == topic], meaning)
                merged.add(topic, meaning, meaning.streams(times_s, fields,
                                                           axes or meaning.axes))
            start_ns = reader.start_time
    except (*_UNREADABLE, ValueError) as error:
        reason = " ".join(str(error).split()) or type(error).__name__
        raise ValueError(f"{path}: not a readable ROS bag ({reason})") from None
    return FlightLog(name=path.stem if path.suffix == ".bag" else path.name,
                     source=str(path), format="ros1_bag" if path.suffix == ".bag"
                     else "ros2_bag", streams=merged.streams,
                     airspeed_source=merged.airspeed_source,
                     warnings=tuple(f"log {path}: {note}" for note in notes + merged.notes),
                     start_stamp_s=start_ns * 1e-9, sought=sought_topics(topics))


def _topic_fields(reader: AnyReader, connections: list,
                  meaning: TopicMeaning) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """One topic's message times [s from the bag's start] and its meaning's fields by dotted
    path (arrays as (n, k), NaN where a message has fewer elements)."""
    stamps_ns, log_times_ns, rows = [], [], []
    for connection, log_time_ns, raw in reader.messages(connections=connections):
        message = reader.deserialize(raw, connection.msgtype)
        header = getattr(message, "header", None)
        stamps_ns.append(header.stamp.sec * 1_000_000_000 + header.stamp.nanosec
                         if header is not None else 0)
        log_times_ns.append(log_time_ns)
        rows.append([_field(message, path) for path in meaning.fields])
    fields = {}
    for k, path in enumerate(meaning.fields):
        values = [row[k] for row in rows]
        fields[path] = (padded_rows(values) if path in meaning.array_fields
                        else np.array(values, dtype=float))
    times_s = message_times_s(np.array(stamps_ns, dtype=np.int64),
                              np.array(log_times_ns, dtype=np.int64), reader.start_time)
    return times_s, fields


def _field(message: object, path: str) -> object:
    """A field of a decoded message by dotted path."""
    for name in path.split("."):
        message = getattr(message, name)
    return message

