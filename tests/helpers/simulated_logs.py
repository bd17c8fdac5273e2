"""Flight logs the project makes itself from simulated flights: a PX4 ULog, a ROS 1 bag with
MAVROS types and that bag's per-topic CSV export, like a real aircraft's.

Like a real log: body rates and attitude (one IMU message) at 10 Hz, airspeed at 5 Hz and
servo outputs at 2.9 Hz, each at its own jittered instants (not on the detector's 0.2 s
grid); the surfaces as integer PWM per output channel with the trims, throws, signs and the
mirrored copy of tests/flight_logs/fixture_airframe.yaml; FLU axes (ENU attitude) in the
MAVROS bag, FRD in the ULog. The instants are samples of a Simulation at 120 Hz, so every
value written is the simulator's at its instant (LogTruth).

The ULog is written here, following the ULog file format specification (header, flag bits,
format, info, subscription and data messages): pyulog 1.3.0's ULog.write_ulog only writes
back a log it has parsed (its topics' buffers are private parsed state), it has no way to
build one from arrays.
"""

from __future__ import annotations

import csv
import struct
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path

import numpy as np
import yaml
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.typesys import Stores, get_typestore
from uav_common.channels import AIR_DATA_CHANNELS, AIR_DATA_FIELDS, CONTROL_CHANNELS, STATE_CHANNELS
from uav_fault_estimator.detection.calibration import DEFAULT_SAMPLE_PERIOD_S
from uav_fault_estimator.detection.detector import DetectorFlight
from uav_fault_estimator.flight_logs.axes import (
    body_rates_frd,
    quaternions_from_euler,
    world_vectors_ned,
)
from uav_fault_estimator.flight_logs.log_writers import ulog_message, ulog_records
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    GROUND_VELOCITY,
    OUTPUTS,
    STREAM_COLUMNS,
    SURFACES,
)
from uav_fault_estimator.flight_logs.topics import (
    CONTROL_FIELDS,
    MAVROS_TOPICS,
    STATE_FIELDS,
    register_mavros_types,
)
from uav_fault_estimator.recording.project_bag import Recording, project_typestore
from uav_sim.scenario import Scenario
from uav_sim.simulation import Simulation

from helpers.repo import REPO_ROOT

FIXTURE_AIRFRAME = (REPO_ROOT / "tests" / "uav_fault_estimator" / "flight_logs"
                    / "fixture_airframe.yaml")
SENSOR_RATE_HZ = 120.0  # the simulation's sample grid: the log instants are picked from it


@dataclass(frozen=True)
class StreamTiming:
    """A stream's instants: every period_ticks samples of the 120 Hz grid from phase_ticks,
    each moved by a uniform random jitter of at most jitter_ticks."""

    period_ticks: int
    phase_ticks: int
    jitter_ticks: int


# Rates and attitude share the IMU's instants (sensor_msgs/Imu carries both).
TIMINGS: Mapping[str, StreamTiming] = {
    BODY_RATES: StreamTiming(12, 1, 3),  # 10 Hz
    AIRSPEED: StreamTiming(24, 7, 4),  # 5 Hz
    OUTPUTS: StreamTiming(41, 3, 2),  # 2.93 Hz
    GROUND_VELOCITY: StreamTiming(29, 5, 3),  # 4.14 Hz, as ALFA's local_position/velocity
}
# The surfaces in radians (the project's own recordings) at the outputs' instants.
STREAM_TIMING = {BODY_RATES: BODY_RATES, ATTITUDE: BODY_RATES, AIRSPEED: AIRSPEED,
                 OUTPUTS: OUTPUTS, SURFACES: OUTPUTS, GROUND_VELOCITY: GROUND_VELOCITY}


@dataclass(frozen=True)
class TruthStream:
    """What a log holds of one stream: times_s (n,) [s of simulation time] and values (n, k)
    as written (FRD/NED, SI; OUTPUTS: integer PWM [us]; SURFACES: rad and throttle)."""

    times_s: np.ndarray
    values: np.ndarray


@dataclass(frozen=True)
class LogTruth:
    """The simulated flight's streams as the logs hold them, by stream name; and grid: the
    same flight sampled directly on the detector's grid (the run a log is compared with)."""

    streams: Mapping[str, TruthStream]
    grid: DetectorFlight


def simulate_truth(scenario: Scenario, seed: int,
                   airframe: Path = FIXTURE_AIRFRAME) -> LogTruth:
    """Fly the scenario at 120 Hz and pick each stream's instants (TIMINGS, jitter from
    seed): body rates, attitude, airspeed (measured, as on board), the outputs' PWM (by the
    airframe file's map) and the ground velocity."""
    simulation = Simulation(scenario, SENSOR_RATE_HZ)
    samples = [simulation.sample()]
    while not simulation.finished:
        samples.append(simulation.step())
    times_s = np.array([s.time_s for s in samples])
    states = np.array([s.state for s in samples])
    controls = np.array([s.controls for s in samples])
    airspeed = np.array([s.air_data[AIR_DATA_CHANNELS.index("airspeed")] for s in samples])
    rng = np.random.default_rng(seed)
    picks = {name: _instants(timing, len(samples), rng) for name, timing in TIMINGS.items()}
    state_columns = {name: [STATE_CHANNELS.index(c) for c in STREAM_COLUMNS[name]]
                     for name in (BODY_RATES, ATTITUDE, GROUND_VELOCITY)}
    values = {
        BODY_RATES: states[:, state_columns[BODY_RATES]],
        ATTITUDE: states[:, state_columns[ATTITUDE]],
        GROUND_VELOCITY: states[:, state_columns[GROUND_VELOCITY]],
        AIRSPEED: airspeed[:, None],
        OUTPUTS: pwm_outputs(controls, airframe),
        SURFACES: controls[:, [CONTROL_CHANNELS.index(c) for c in STREAM_COLUMNS[SURFACES]]],
    }
    every = round(DEFAULT_SAMPLE_PERIOD_S * SENSOR_RATE_HZ)
    grid = DetectorFlight(times_s[::every], states[::every], controls[::every],
                          airspeed[::every])
    return LogTruth({name: TruthStream(times_s[picks[STREAM_TIMING[name]]],
                                       value[picks[STREAM_TIMING[name]]])
                     for name, value in values.items()}, grid)


def _instants(timing: StreamTiming, count: int, rng: np.random.Generator) -> np.ndarray:
    """Indices into a grid of count samples: jittered, strictly increasing (jitter below
    half a period)."""
    nominal = np.arange(timing.phase_ticks, count - timing.jitter_ticks, timing.period_ticks)
    jitter = rng.integers(-timing.jitter_ticks, timing.jitter_ticks + 1, nominal.size)
    return np.clip(nominal + jitter, 0, count - 1)


def fixture_airframe() -> dict:
    """tests/flight_logs/fixture_airframe.yaml, the outputs' truth."""
    return yaml.safe_load(FIXTURE_AIRFRAME.read_text())


def pwm_outputs(controls: np.ndarray, airframe_file: Path = FIXTURE_AIRFRAME) -> np.ndarray:
    """The PWM [us, integers] (n, outputs) of controls (n, 7) in CONTROL_CHANNELS order: the
    inverse of the airframe file's map (airframe.py's formulas; by default
    fixture_airframe.yaml, the outputs' truth), then its copies."""
    airframe = yaml.safe_load(airframe_file.read_text())
    surfaces, mixed = airframe["surfaces"], airframe.get("mixed", [])
    count = max([s["output"] for s in surfaces.values()] + [m["output"] for m in mixed])
    pwm = np.zeros((controls.shape[0], count))
    for name, surface in surfaces.items():
        value = controls[:, CONTROL_CHANNELS.index(name)]
        if "trim_us" in surface:
            pwm_us = surface["trim_us"] + surface["throw_us"] * value / (
                surface["sign"] * surface["max_deflection_rad"])
        else:
            pwm_us = surface["idle_us"] + (surface["full_us"] - surface["idle_us"]) * value
        pwm[:, surface["output"] - 1] = np.round(pwm_us)
    trims = {s["output"]: s.get("trim_us", s.get("idle_us")) for s in surfaces.values()}
    for copy in mixed:
        trim = trims[copy["of_output"]]
        pwm[:, copy["output"] - 1] = np.round(
            trim + copy["factor"] * (pwm[:, copy["of_output"] - 1] - trim))
    return pwm


# ---- PX4 ULog ------------------------------------------------------------------------------

ULOG_MAGIC = b"ULog\x01\x12\x35"
ULOG_VERSION = 1
ULOG_START_US = 12_345_678  # the log's start [us since boot]; simulation time 0 is there
# Topic formats (PX4's field names and types; padding left out, which the format allows).
ULOG_FORMATS = {
    "vehicle_angular_velocity": [("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"),
                                 ("float[3]", "xyz")],
    "vehicle_attitude": [("uint64_t", "timestamp"), ("float[4]", "q")],
    "airspeed_validated": [("uint64_t", "timestamp"), ("float", "indicated_airspeed_m_s"),
                           ("float", "calibrated_airspeed_m_s"),
                           ("float", "true_airspeed_m_s")],
    "actuator_outputs": [("uint64_t", "timestamp"), ("uint32_t", "noutputs"),
                         ("float[16]", "output")],
}


def write_ulog(path: Path, truth: LogTruth) -> None:
    """The flight as a PX4 ULog: ULOG_FORMATS' topics, FRD, the attitude as quaternions
    (FRD body to NED, w first), true airspeed (indicated and calibrated NaN: a log where
    only the true one is valid), PWM in actuator_outputs' first outputs."""
    streams = truth.streams
    pwm = streams[OUTPUTS].values
    columns = {
        "vehicle_angular_velocity": [streams[BODY_RATES].values[:, k] for k in range(3)],
        "vehicle_attitude": list(quaternions_from_euler(streams[ATTITUDE].values, "FRD").T),
        "airspeed_validated": [np.full(streams[AIRSPEED].times_s.size, np.nan)] * 2
        + [streams[AIRSPEED].values[:, 0]],
        "actuator_outputs": [np.full(pwm.shape[0], pwm.shape[1])]
        + [pwm[:, k] if k < pwm.shape[1] else np.zeros(pwm.shape[0]) for k in range(16)],
    }
    times_s = {"vehicle_angular_velocity": streams[BODY_RATES].times_s,
               "vehicle_attitude": streams[ATTITUDE].times_s,
               "airspeed_validated": streams[AIRSPEED].times_s,
               "actuator_outputs": streams[OUTPUTS].times_s}
    messages = []  # (timestamp [us], bytes) of every data message
    with Path(path).open("wb") as file:
        file.write(ULOG_MAGIC + bytes([ULOG_VERSION]) + struct.pack("<Q", ULOG_START_US))
        file.write(ulog_message(b"B", bytes(16) + bytes(24)))  # no flags, nothing appended
        for name, format_fields in ULOG_FORMATS.items():
            text = name + ":" + "".join(f"{kind} {field};" for kind, field in format_fields)
            file.write(ulog_message(b"F", text.encode()))
        file.write(ulog_message(b"I", _info("char[12] sys_name", b"uav_sim_log")))
        for msg_id, name in enumerate(ULOG_FORMATS):
            file.write(ulog_message(b"A", struct.pack("<BH", 0, msg_id) + name.encode()))
            timestamps_us = ULOG_START_US + np.round(times_s[name] * 1e6).astype(np.uint64)
            values = [timestamps_us] + ([timestamps_us] if name == "vehicle_angular_velocity"
                                        else []) + columns[name]
            records = ulog_records(ULOG_FORMATS[name], values)
            messages += [(int(t), ulog_message(b"D", struct.pack("<H", msg_id) + record))
                         for t, record in zip(timestamps_us, records, strict=True)]
        for _, message in sorted(messages, key=lambda m: m[0]):
            file.write(message)


def _info(key: str, value: bytes) -> bytes:
    """An info message's payload: key length, "type name", value."""
    return bytes([len(key)]) + key.encode() + value


# ---- ROS 1 bag with MAVROS types -----------------------------------------------------------

BAG_START_NS = 1_700_000_000_000_000_000  # wall clock of simulation time 0 [ns]
LATENCY_NS = (1_000_000, 20_000_000)  # a message is logged 1-20 ms after its stamp


def mavros_ros1_typestore():
    """ROS 1 Noetic's types plus MAVROS's RCOut and VFR_HUD."""
    return register_mavros_types(get_typestore(Stores.ROS1_NOETIC))


def write_mavros_bag(path: Path, truth: LogTruth, seed: int) -> float:
    """The flight as a ROS 1 bag of MAVROS topics (topics.MAVROS_TOPICS): sensor_msgs/Imu
    (FLU rates, ENU/FLU orientation), mavros_msgs/RCOut (PWM), VFR_HUD (airspeed) and
    local_position/velocity's TwistStamped (ENU ground velocity), stamped
    at the simulation's instants, logged a random latency later. Returns the bag's start
    (its first log time) in seconds of simulation time, from which a reader counts."""
    typestore = mavros_ros1_typestore()
    types = typestore.types
    topic: dict[str, str] = {}  # each meaning's first topic (imu/data before imu/data_raw)
    for name, meaning in MAVROS_TOPICS.items():
        topic.setdefault(meaning, name)
    streams = truth.streams
    rng = np.random.default_rng(seed)

    def header(time_s: float, seq: int):
        stamp_ns = BAG_START_NS + round(time_s * 1e9)
        return types["std_msgs/msg/Header"](
            seq=seq, stamp=types["builtin_interfaces/msg/Time"](
                sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000),
            frame_id="base_link")

    def vector(type_name: str, values: np.ndarray):
        return types[type_name](*(float(v) for v in values))

    messages = []  # (topic, message type, message, stamp time [s])
    rates_flu = body_rates_frd(streams[BODY_RATES].values, "FLU")
    quaternions = quaternions_from_euler(streams[ATTITUDE].values, "FLU")
    zeros9 = np.zeros(9)
    for k, time_s in enumerate(streams[BODY_RATES].times_s):
        messages.append((topic["imu"], "sensor_msgs/msg/Imu", types["sensor_msgs/msg/Imu"](
            header=header(time_s, k),
            orientation=vector("geometry_msgs/msg/Quaternion", quaternions[k, [1, 2, 3, 0]]),
            orientation_covariance=zeros9,
            angular_velocity=vector("geometry_msgs/msg/Vector3", rates_flu[k]),
            angular_velocity_covariance=zeros9,
            linear_acceleration=vector("geometry_msgs/msg/Vector3", np.zeros(3)),
            linear_acceleration_covariance=zeros9), time_s))
    for k, time_s in enumerate(streams[OUTPUTS].times_s):
        messages.append((topic["rc_out"], "mavros_msgs/msg/RCOut", types["mavros_msgs/msg/RCOut"](
            header=header(time_s, k),
            channels=streams[OUTPUTS].values[k].astype(np.uint16)), time_s))
    for k, time_s in enumerate(streams[AIRSPEED].times_s):
        messages.append((topic["vfr_hud"], "mavros_msgs/msg/VFR_HUD",
                         types["mavros_msgs/msg/VFR_HUD"](
                             header=header(time_s, k),
                             airspeed=float(streams[AIRSPEED].values[k, 0]),
                             groundspeed=0.0, heading=0, throttle=0.0, altitude=0.0,
                             climb=0.0),
                         time_s))
    velocity = streams[GROUND_VELOCITY]
    velocity_enu = world_vectors_ned(velocity.values, "FLU")  # its own inverse
    for k, time_s in enumerate(velocity.times_s):
        messages.append((topic["velocity"], "geometry_msgs/msg/TwistStamped",
                         types["geometry_msgs/msg/TwistStamped"](
                             header=header(time_s, k), twist=types["geometry_msgs/msg/Twist"](
                                 linear=vector("geometry_msgs/msg/Vector3", velocity_enu[k]),
                                 angular=vector("geometry_msgs/msg/Vector3", np.zeros(3)))),
                         time_s))
    log_ns = [BAG_START_NS + round(m[3] * 1e9) + int(rng.integers(*LATENCY_NS))
              for m in messages]
    with Ros1Writer(path) as writer:
        connections = {name: writer.add_connection(name, message_type, typestore=typestore)
                       for name, message_type in {(m[0], m[1]) for m in messages}}
        for (name, message_type, message, _), time_ns in sorted(
                zip(messages, log_ns, strict=True), key=lambda m: m[1]):
            writer.write(connections[name], time_ns,
                         typestore.serialize_ros1(message, message_type))
    return (min(log_ns) - BAG_START_NS) * 1e-9


# ---- the project's own ROS 2 recording -----------------------------------------------------


def write_project_bag(path: Path, truth: LogTruth) -> None:
    """The flight as recorder_node records it (rosbag2, MCAP): /state (body rates, attitude;
    the other channels 0) at the IMU's instants, /air_data at the airspeed's, /controls
    (SURFACES) at the outputs', stamped and logged at simulation time."""
    typestore = project_typestore()
    types = typestore.types
    streams = truth.streams
    recording = Recording(path, typestore)
    messages = []  # (log time [ns], topic, message type, fields)
    for k, time_s in enumerate(streams[BODY_RATES].times_s):
        values = dict(zip(STREAM_COLUMNS[BODY_RATES] + STREAM_COLUMNS[ATTITUDE],
                          [*streams[BODY_RATES].values[k], *streams[ATTITUDE].values[k]],
                          strict=True))
        messages.append((time_s, "/state", "uav_fault_msgs/msg/AircraftState",
                         {STATE_FIELDS[c]: float(values.get(c, 0.0)) for c in STATE_CHANNELS}))
    for k, time_s in enumerate(streams[AIRSPEED].times_s):
        messages.append((time_s, "/air_data", "uav_fault_msgs/msg/AirData",
                         {name: float(streams[AIRSPEED].values[k, 0]) if name == AIR_DATA_FIELDS[0]
                          else 0.0 for name in AIR_DATA_FIELDS}))
    for k, time_s in enumerate(streams[SURFACES].times_s):
        values = dict(zip(STREAM_COLUMNS[SURFACES], streams[SURFACES].values[k], strict=True))
        messages.append((time_s, "/controls", "uav_fault_msgs/msg/ControlInputs",
                         {CONTROL_FIELDS[c]: (True if c == "ignition" else
                                              float(values.get(c, 0.0)))
                          for c in CONTROL_CHANNELS}))
    try:
        for topic, message_type in sorted({(m[1], m[2]) for m in messages}):
            recording.add_topic(topic, message_type)
        for time_s, topic, message_type, values in sorted(messages, key=lambda m: m[0]):
            stamp_ns = round(time_s * 1e9)
            header = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](
                    sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000),
                frame_id="")
            message = types[message_type](header=header, **values)
            recording.write(topic, stamp_ns, typestore.serialize_cdr(message, message_type))
    finally:
        recording.close()


# ---- per-topic CSV export ------------------------------------------------------------------

ROSTOPIC, DOTTED, ALFA = "rostopic", "dotted", "alfa"  # the CSV layouts (csv_logs.py)


def export_csv(bag: Path, folder: Path, layout: str) -> None:
    """A bag's topics as per-topic CSV files in folder, as exporters write them. ROSTOPIC:
    rostopic echo -p (_mavros_imu_data.csv; "%time" [ns], "field." prefixes, stamps one
    column [ns], arrays one column an element: channels0). DOTTED: mavros-imu-data.csv;
    "time" [s], "." prefixes, stamps secs and nsecs, arrays one column of a list. ALFA:
    ROSTOPIC's columns in ALFA's processed layout, FOLDER-mavros-imu-data.csv."""
    folder.mkdir(parents=True, exist_ok=True)
    rows: dict[str, list[dict[str, str]]] = {}
    with AnyReader([bag]) as reader:
        for connection, time_ns, raw in reader.messages():
            message = reader.deserialize(raw, connection.msgtype)
            columns = ROSTOPIC if layout == ALFA else layout
            row = {"%time" if columns == ROSTOPIC else "time":
                   str(time_ns) if columns == ROSTOPIC else repr(time_ns * 1e-9)}
            prefix = "field." if columns == ROSTOPIC else "."
            row.update((prefix + name, value) for name, value in _flat(message, columns))
            rows.setdefault(connection.topic, []).append(row)
    for topic, topic_rows in rows.items():
        name = {ROSTOPIC: topic.replace("/", "_"),
                DOTTED: topic.strip("/").replace("/", "-"),
                ALFA: f"{folder.name}-" + topic.strip("/").replace("/", "-")}[layout]
        with (folder / f"{name}.csv").open("w", newline="") as file:
            writer = csv.DictWriter(file, fieldnames=list(topic_rows[0]))
            writer.writeheader()
            writer.writerows(topic_rows)


def _flat(message: object, layout: str, path: str = "") -> Iterator[tuple[str, str]]:
    """A decoded message's fields as (dotted path, text), in the layout's forms."""
    names = {f.name for f in fields(message)} - {"__msgtype__"} if is_dataclass(message) else ()
    if names == {"sec", "nanosec"}:
        if layout == ROSTOPIC:
            yield path, str(message.sec * 1_000_000_000 + message.nanosec)
        else:
            yield f"{path}.secs", str(message.sec)
            yield f"{path}.nsecs", str(message.nanosec)
    elif is_dataclass(message):
        for field in fields(message):
            if field.name in names:
                yield from _flat(getattr(message, field.name), layout,
                                 f"{path}.{field.name}" if path else field.name)
    elif isinstance(message, np.ndarray):
        if layout == ROSTOPIC:
            for k, value in enumerate(message.tolist()):
                yield f"{path}{k}", repr(value)
        else:
            yield path, repr(message.tolist())
    else:
        value = message.item() if isinstance(message, np.generic) else message
        yield path, repr(value) if isinstance(value, float) else str(value)
