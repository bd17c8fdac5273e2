"""Per-topic CSV files exported from bags, one folder a flight, as flight logs.

The layouts bag exporters write: one file a topic, named after it (/mavros/imu/data:
mavros-imu-data.csv, _mavros_imu_data.csv or mavros_imu_data.csv), or after the folder and
the topic (ALFA's processed flights: FOLDER-mavros-imu-data.csv), a header row of the
log time and the message's fields by dotted path with a prefix `field.` (rostopic echo -p,
"%time,field.header.stamp,...") or `.` ("time,.header.stamp.secs,.header.stamp.nsecs,...").
Stamps are one column in nanoseconds (`header.stamp`) or two (`header.stamp.secs`/`nsecs`,
ROS 1; `header.stamp.sec`/`nanosec`, ROS 2); the log time `time` is in nanoseconds when
written as an integer above 1e12 (rostopic), in seconds otherwise. Arrays are one column an
element (`channels0`, `channels_0` or `channels[0]`) or one column of a bracketed list
("[1500, 1500]" or "(1500, 1500)"). The topics and their meaning are topics.py's, shared
with the bags; times are in seconds from the earliest log time of the files read, which
the log records (FlightLog.start_stamp_s).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uav_fault_estimator.flight_logs.streams import FlightLog
from uav_fault_estimator.flight_logs.topics import (
    MEANINGS,
    LogStreams,
    TopicMeaning,
    checked_topics,
    message_times_ns,
    message_times_s,
    padded_rows,
    sought_topics,
)

NANOSECONDS_ABOVE = 1e12  # a log time written as an integer above this is in nanoseconds
# Largest CSV file read [bytes]: a file is read row by row, and the columns its topic
# needs are held as text, several times their size; an hour of a 50 Hz topic is about
# 60 MB.
MAX_FILE_BYTES = 256 * 2**20
# Log times (`time`) must be finite, below MAX_LOG_TIME_S (the year 5138) and in order:
# back by at most TIME_BACK_TOLERANCE_S (exporters write rows of one instant out of
# order), forward by at most MAX_TIME_STEP_S from one row to the next.
MAX_LOG_TIME_S = 1e11
TIME_BACK_TOLERANCE_S = 1.0
MAX_TIME_STEP_S = 3600.0
_STAMP_PAIRS = (("header.stamp.secs", "header.stamp.nsecs"),
                ("header.stamp.sec", "header.stamp.nanosec"))


def topic_file_key(name: str) -> str:
    """A topic name or a CSV file's stem, reduced to what both spell alike: "/mavros/vfr_hud",
    "mavros-vfr_hud" and "_mavros_vfr_hud" all give "mavros_vfr_hud"."""
    return re.sub(r"[/\-_]+", "_", name).strip("_")


def topic_file_name(topic: str) -> str:
    """The file a topic is looked for in, as the line naming a missing stream spells it."""
    return f"[FOLDER-]{topic.strip('/').replace('/', '-')}.csv"


def csv_files(folder: Path) -> dict[str, Path]:
    """The folder's CSV files by topic_file_key of their stems, a leading folder name and
    dash dropped (ALFA's FOLDER-mavros-imu-data.csv)."""
    prefix = f"{folder.name}-"
    return {topic_file_key(path.stem.removeprefix(prefix)): path
            for path in sorted(folder.glob("*.csv"))}


def read_csv_folder(folder: Path, topics: Mapping[str, str] | None = None,
                    axes: str | None = None) -> FlightLog:
    """The flight in a folder of per-topic CSV files. topics: topic name -> meaning
    (topics.MEANINGS; default topics.DEFAULT_TOPICS); a topic without a file gives no stream.
    axes ("FRD" or "FLU") overrides each message type's own convention. ValueError (one line
    naming the file) when a file lacks a field its topic needs or a value is not a number."""
    folder = Path(folder)
    topics = checked_topics(topics)
    files = csv_files(folder)
    tables = {topic: _table(files[topic_file_key(topic)], MEANINGS[topics[topic]])
              for topic in topics if topic_file_key(topic) in files}
    if not files:
        raise ValueError(f"{folder}: no CSV files (one a topic, named after it)")
    start_ns = log_start_ns(
        [_named(files[topic_file_key(topic)], _log_times_ns, table)
         for topic, table in tables.items()], [_stamps_ns(table) for table in tables.values()])
    merged = LogStreams()
    for topic, table in sorted(tables.items()):
        meaning = MEANINGS[topics[topic]]
        path = files[topic_file_key(topic)]
        try:
            fields = {name: (_array_field(table, name) if name in meaning.array_fields
                             else _numbers(table, name)) for name in meaning.fields}
            stamps_ns = _stamps_ns(table)
            log_ns = _log_times_ns(table)
            times_s = message_times_s(stamps_ns, log_ns if log_ns.size else stamps_ns,
                                      start_ns)
            merged.add(topic, meaning, meaning.streams(times_s, fields, axes or meaning.axes))
        except (KeyError, ValueError) as error:
            reason = error.args[0] if error.args else type(error).__name__
            raise ValueError(f"{path}: {reason}") from None
    return FlightLog(name=folder.name, source=str(folder), format="csv",
                     streams=merged.streams, airspeed_source=merged.airspeed_source,
                     warnings=tuple(f"log {folder}: {note}" for note in merged.notes),
                     start_stamp_s=start_ns * 1e-9,
                     sought=sought_topics(topics, topic_file_name))


def log_start_ns(log_times_ns: list[np.ndarray], stamps_ns: list[np.ndarray]) -> int:
    """The instant a flight's times count from [ns]: the earliest log time of its files
    (each file's log times, empty for a file without), else the earliest positive stamp, else
    0."""
    logged = [int(times.min()) for times in log_times_ns if times.size]
    if logged:
        return min(logged)
    return min((int(t) for stamps in stamps_ns for t in stamps if t > 0), default=0)


@dataclass(frozen=True)
class TopicRows:
    """One topic's messages as its CSV file holds them, in file order: stamps_ns (n,) their
    header stamps [ns] (0: none), log_times_ns (n,) when each was logged [ns] (empty: the
    file has no log time), fields by dotted path (an array field (n, k))."""

    stamps_ns: np.ndarray
    log_times_ns: np.ndarray
    fields: dict[str, np.ndarray]

    @property
    def times_ns(self) -> np.ndarray:
        """Each message's time [ns, the log's clock] (topics.message_times_ns)."""
        return message_times_ns(self.stamps_ns, self.log_times_ns if self.log_times_ns.size
                                else self.stamps_ns)


def read_topic_rows(folder: Path, topic: str, fields: tuple[str, ...] = (),
                    array_fields: tuple[str, ...] = ()) -> TopicRows | None:
    """The fields (dotted paths; array_fields among them read as arrays) of one topic's CSV
    file in folder, as read_csv_folder reads them; None when the folder has no file for the
    topic. ValueError (one line naming the file) as read_csv_folder's."""
    path = csv_files(Path(folder)).get(topic_file_key(topic))
    if path is None:
        return None
    meaning = TopicMeaning("", fields, array_fields, "FLU", "", lambda *_: {}, ())
    table = _table(path, meaning)
    try:
        values = {name: (_array_field(table, name) if name in array_fields
                         else _numbers(table, name)) for name in fields}
        return TopicRows(_stamps_ns(table), _log_times_ns(table), values)
    except (KeyError, ValueError) as error:
        reason = error.args[0] if error.args else type(error).__name__
        raise ValueError(f"{path}: {reason}") from None


def _named(path: Path, read: Callable[[dict[str, list[str]]], np.ndarray],
           table: dict[str, list[str]]) -> np.ndarray:
    """read(table), its ValueError prefixed with the file's path."""
    try:
        return read(table)
    except ValueError as error:
        raise ValueError(f"{path}: {error.args[0]}") from None


def _table(path: Path, meaning: TopicMeaning) -> dict[str, list[str]]:
    """The columns of a CSV file that the meaning (topics.MEANINGS entry) reads, the stamps
    and the log time, by field path (prefixes `%`, `field.` and `.` dropped), read row by
    row: the other columns are never held. ValueError naming the file when it is too
    large, not text, or empty."""
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ValueError(f"{path}: {size / 2**20:.0f} MiB, more than the {MAX_FILE_BYTES // 2**20}"
                         " MiB a CSV file may have here: export a shorter span of the flight")
    try:
        with path.open(newline="") as file:
            rows = csv.reader(file)
            names = [re.sub(r"^%?(field)?\.?", "", name.strip()) for name in next(rows, [])]
            if not names:
                raise ValueError(f"{path}: empty (expected a header row)")
            kept = [k for k, name in enumerate(names) if _read_by(meaning, name)]
            table: dict[str, list[str]] = {names[k]: [] for k in kept}
            for row in rows:
                for k in kept:
                    table[names[k]].append(row[k] if k < len(row) else "")
    except (UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"{path}: not a CSV text file ({error})") from None
    return table


def _read_by(meaning: TopicMeaning, column: str) -> bool:
    """Whether a column is one the meaning's fields, the stamps or the log time need."""
    if column in meaning.fields or column == "time" or column.startswith("header.stamp"):
        return True
    return any(_ELEMENT.match(column) and _ELEMENT.match(column)[1] == name
               for name in meaning.array_fields)


def _numbers(table: dict[str, list[str]], name: str) -> np.ndarray:
    """A column as floats; KeyError naming a missing field, ValueError a bad value."""
    if name not in table:
        raise KeyError(f"no column for field {name}")
    try:
        return np.array([float(text) if text.strip() else np.nan for text in table[name]])
    except ValueError:
        raise ValueError(f"field {name}: a value that is not a number") from None


def _integers(table: dict[str, list[str]], name: str) -> np.ndarray:
    """A column of integers exactly (stamps in nanoseconds exceed a float's precision)."""
    try:
        return np.array([int(text) if text.strip() else 0 for text in table[name]],
                        dtype=np.int64)
    except ValueError:
        raise ValueError(f"field {name}: a value that is not an integer") from None


def _stamps_ns(table: dict[str, list[str]]) -> np.ndarray:
    """The header stamps [ns] (n,), zeros where the topic has no header."""
    if "header.stamp" in table:
        return _integers(table, "header.stamp")
    for seconds, nanoseconds in _STAMP_PAIRS:
        if seconds in table and nanoseconds in table:
            return (_integers(table, seconds) * 1_000_000_000
                    + _integers(table, nanoseconds))
    return np.zeros(len(next(iter(table.values()), [])), dtype=np.int64)


def _log_times_ns(table: dict[str, list[str]]) -> np.ndarray:
    """The log times [ns] (n,) from the `time` column; empty without one."""
    if "time" not in table:
        return np.zeros(0, dtype=np.int64)
    texts = table["time"]
    if all(re.fullmatch(r"\s*\d+\s*", text) for text in texts) and texts and \
            int(texts[0]) > NANOSECONDS_ABOVE:
        times_ns = _integers(table, "time")
        _check_log_times(times_ns / 1e9)
        return times_ns
    times_s = _numbers(table, "time")
    _check_log_times(times_s)
    return np.round(times_s * 1e9).astype(np.int64)


def _check_log_times(times_s: np.ndarray) -> None:
    """ValueError naming the first row (1: the first after the header) whose log time [s]
    is not finite, beyond MAX_LOG_TIME_S, or out of order."""
    bad = ~(np.abs(times_s) < MAX_LOG_TIME_S)  # NaN too
    if bad.any():
        row = int(np.argmax(bad))
        raise ValueError(f"row {row + 1}: time {times_s[row]:.12g} is not a log time in "
                         "seconds")
    steps = np.diff(times_s)
    jumps = (steps < -TIME_BACK_TOLERANCE_S) | (steps > MAX_TIME_STEP_S)
    if jumps.any():
        row = int(np.argmax(jumps)) + 1
        raise ValueError(f"row {row + 1}: time {times_s[row]:.12g} s after "
                         f"{times_s[row - 1]:.12g} s "
                         f"(at most {TIME_BACK_TOLERANCE_S:g} s back or "
                         f"{MAX_TIME_STEP_S:g} s forward from one row to the next)")


# An array's element column: "channels0", "channels_0" or "channels[0]".
_ELEMENT = re.compile(r"^(.+?)(?:_?(\d+)|\[(\d+)\])$")


def _array_field(table: dict[str, list[str]], name: str) -> np.ndarray:
    """An array field (n, k): from one column an element, or one column of lists."""
    indexed = {int(match[2] or match[3]): column for column in table
               if (match := _ELEMENT.match(column)) and match[1] == name}
    if indexed:
        return np.column_stack([_numbers(table, indexed[k]) for k in sorted(indexed)])
    if name not in table:
        raise KeyError(f"no column for field {name}")
    return padded_rows([[float(x) for x in re.findall(r"[-+0-9.eE]+", text)]
                        for text in table[name]])
