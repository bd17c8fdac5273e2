"""mavlink_node: an autopilot's MAVLink link (ArduPlane, PX4) as the project's streams.

Listens on `connection` (pymavlink's form: `udpin:127.0.0.1:14550`, `/dev/ttyACM0,921600`,
`tcp:HOST:PORT`) to the autopilot of `target_system` (0: the first one heard), samples what it
streams onto a grid of its boot time (uav_mavlink.sample_assembly) and publishes, stamped with
the autopilot's boot time mapped once to ROS time by a whole number of seconds (so that a
grid point stays one; again after a reboot), as sim_node does
(relative names, the `qos` chosen): `state` (AircraftState: ATTITUDE, GLOBAL_POSITION_INT or
LOCAL_POSITION_NED, RPM; the fuel mass the parameter), `controls` (ControlInputs: SERVO_OUTPUT_RAW
through the airframe file's servo mapping, or ArduPilot's own SERVOn_* parameters read with
PARAM_REQUEST_READ when `servo_map_from_autopilot`; flap 0, mixture and ignition 1), `air_data`
(AirData: VFR_HUD's airspeed, the vanes' angles NaN), `wind/filtered` (WindEstimate: the
autopilot's wind estimate, WIND or WIND_COV, through the paper's filter), `autopilot_setpoints`
(NAV_CONTROLLER_OUTPUT's commanded roll and pitch, POSITION_TARGET_GLOBAL_INT's commanded
vertical velocity), `/clock` when `publish_clock`, and
`/diagnostics` (the link, each message type's rate, the streams missing). Sends its own
heartbeat and, where enabled, the fault estimates (`faults/estimate`) as NAMED_VALUE_FLOAT and
the alarms (`faults/alarm`'s combined alarm starting and ending, an estimate crossing the
detection threshold) as STATUSTEXT (uav_mavlink.ground_reports); nothing else
(uav_mavlink.link: read-only to the aircraft). Each fault of the link (the link lost and back,
judged with the stream rates by uav_mavlink.link_watch; another system on the link,
packets failing their checksum, readings out of order, a stream missing and back, a reboot,
the link itself failing) is said once in the log and counted on `/diagnostics`.
"""

from __future__ import annotations

import contextlib
import math
import sys
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

from rclpy.clock import Clock as RosClock
from rclpy.clock import ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from uav_aircraft.airframe import load_airframe
from uav_aircraft.fdm import fuel_on_board_kg
from uav_aircraft.vehicle_parameter import FUEL_MASS_PARAMETER, VEHICLE_PARAMETER
from uav_aircraft.vehicles import load_vehicle
from uav_common.health import VEHICLE_KEY
from uav_common.message_fields import stamp_seconds
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.messages import (
    air_data_message,
    controls_message,
    setpoints_message,
    stamp_from_nanoseconds,
    state_message,
    wind_message,
)
from uav_common.ros.node_life import run_node
from uav_common.ros.parameters import QOS_PARAMETER, ParameterSpec, declare_parameters
from uav_common.ros.qos import CLOCK_QOS, STREAM_QOS_PROFILES
from uav_common.sample_grid import NANOSECONDS_PER_SECOND
from uav_fault_msgs.msg import (
    AircraftState,
    AirData,
    AutopilotSetpoints,
    ControlInputs,
    FaultAlarm,
    FaultEstimate,
    WindEstimate,
)

from uav_mavlink.autopilot_messages import read_message
from uav_mavlink.ground_reports import (
    HOLD_S,
    TEXT_INTERVAL_S,
    GroundTexts,
    alarm_tests,
    named_values,
)
from uav_mavlink.link import AUTOPILOTS, is_autopilot_heartbeat, open_link, send_heartbeat
from uav_mavlink.link_watch import LinkWatch
from uav_mavlink.project_streams import StreamConversion
from uav_mavlink.sample_assembly import (
    MAX_AGE_PARAMETERS,
    Sample,
    SampleAssembly,
    ros_offset_ns,
)
from uav_mavlink.servo_setup import ServoParameterReads, airframe_from_servo_parameters

PARAMETERS = {
    "connection": ParameterSpec(
        "the autopilot's link as pymavlink takes it: udpin:HOST:PORT (listen), udpout:, "
        "tcp:HOST:PORT, or a serial port DEVICE,BAUD", "udpin:127.0.0.1:14550"),
    "target_system": ParameterSpec("the autopilot's MAVLink system id; 0: the first "
                                   "autopilot heard", 0, 0, 255),
    "source_system": ParameterSpec("the system id this node sends its heartbeat as (the "
                                   "vehicle's, as an onboard computer)", 1, 1, 255),
    "vehicle": VEHICLE_PARAMETER,
    "airframe": ParameterSpec("airframe YAML mapping the autopilot's servo outputs to surfaces "
                              "(docs/flight_logs.md); empty: the vehicle's one airframe file",
                              ""),
    "servo_map_from_autopilot": ParameterSpec(
        "ArduPilot: read the outputs, trims, throws and reversals from the autopilot's "
        "SERVOn_FUNCTION/MIN/MAX/TRIM/REVERSED parameters (PARAM_REQUEST_READ) and map "
        "SERVO_OUTPUT_RAW with them, the surfaces' full deflections from the airframe file; "
        "until they are read, or where they cannot be, the airframe file's map", False),
    "sample_period_s": ParameterSpec("period of the grid the streams are sampled onto, on the "
                                     "autopilot's clock [s]", 0.05, 0.01, 1.0),
    "attitude_max_age_s": ParameterSpec(
        "the longest gap between two ATTITUDE (and IMU) messages the state's attitude and "
        "rates are interpolated over [s]", 0.2, 0.01, 10.0),
    "position_max_age_s": ParameterSpec(
        "the longest gap between two position or velocity messages interpolated over [s]",
        0.5, 0.01, 10.0),
    "outputs_max_age_s": ParameterSpec(
        "the longest gap between two SERVO_OUTPUT_RAW interpolated over [s]", 0.5, 0.01,
        10.0),
    "air_data_max_age_s": ParameterSpec(
        "the longest gap between two VFR_HUD interpolated over [s]", 1.0, 0.01, 10.0),
    "slow_max_age_s": ParameterSpec(
        "the longest the wind, setpoints and engine speed are held (not waited for, not "
        "interpolated) [s]", 3.0, 0.1, 60.0),
    "fuel_mass_kg": FUEL_MASS_PARAMETER,
    "pitch_trim_deg": ParameterSpec(
        "added to ATTITUDE's pitch: ArduPlane subtracts its pitch trim parameter from the "
        "pitch it sends (PTCH_TRIM_DEG; 0 for PX4) [deg]", 0.0, -45.0, 45.0),
    "wind_filter_tau_s": ParameterSpec(
        "time constant of the filter the autopilot's wind estimate goes through (embedded-"
        "estimation paper eq. 4; the scenarios' 10 s) [s]", 10.0, 0.1, 1000.0),
    "rate_window_s": ParameterSpec(
        "time the link must be alive (heartbeat or streams arriving) over which each "
        "message's rate is measured before it is judged too slow for the chain (said once "
        "per message, with the setting that raises it) [s, wall time]", 5.0, 1.0, 600.0),
    "boot_time_is_ros_time": ParameterSpec(
        "the autopilot's boot time is ROS time already (an autopilot played by the simulator "
        "on its /clock): stamp with it as it is, instead of mapping it by the whole seconds "
        "between the two at the first sample", False),
    "publish_clock": ParameterSpec("publish the autopilot's time, mapped to ROS time, on "
                                   "/clock (for nodes run with use_sim_time)", False),
    "ground_estimates_hz": ParameterSpec(
        "send the newest fault estimates (faults/estimate) to the ground station as "
        "NAMED_VALUE_FLOAT, one per fault under a short name, at most this often; 0: none "
        "[Hz, wall time]", 1.0, 0.0, 10.0),
    "ground_alarms": ParameterSpec(
        "send a STATUSTEXT when the detector's combined alarm (faults/alarm) starts "
        "(WARNING: its cause and tests) and ends (NOTICE: its length), and when an estimate "
        "reaches the detection threshold (WARNING) and is back under it (NOTICE)", True),
    "ground_text_interval_s": ParameterSpec(
        "the least time between two STATUSTEXT lines; lines wait their turn, in order "
        "[s, wall time]", TEXT_INTERVAL_S, 0.1, 600.0),
    "ground_end_hold_s": ParameterSpec(
        "how long the combined alarm, or an estimate over the threshold, stays off before "
        "its end is said: a shorter pause goes on, so a flickering test or an estimate "
        "hovering at the threshold gives one onset and one end [s, flight time]", HOLD_S,
        0.0, 600.0),
    "qos": QOS_PARAMETER,
}
READ_PERIOD_S = 0.005  # how often the link is read [s, wall time]
HEARTBEAT_PERIOD_S = 1.0  # the onboard computer's heartbeat [s, wall time]
LINK_LOST_S = 3.0  # nothing from the autopilot for this long: the link is lost [s]
TEXT_PERIOD_S = 0.1  # how often waiting STATUSTEXT lines are looked at [s, wall time]
_WALL = RosClock(clock_type=ClockType.STEADY_TIME)


class MavlinkNode(Node):
    """Thin adapter: parameters in, link messages to readings to grid samples (cores), samples
    to messages, diagnostics."""

    def __init__(self) -> None:
        super().__init__("mavlink_node")
        self.parameters = declare_parameters(self, PARAMETERS)
        p = self.parameters
        self.airframe = load_airframe(p["airframe"]
                                      or load_vehicle(p["vehicle"]).only_airframe_file())
        self.assembly = SampleAssembly(
            p["sample_period_s"],
            {stream: p[name] for stream, name in MAX_AGE_PARAMETERS.items()},
            fuel_on_board_kg(p["fuel_mass_kg"], load_vehicle(p["vehicle"])),
            math.radians(p["pitch_trim_deg"]))
        self.conversion = StreamConversion(self.airframe, p["wind_filter_tau_s"])
        self.link = open_link(p["connection"], p["source_system"])
        qos = STREAM_QOS_PROFILES[p["qos"]]
        self.publishers_ = {
            "state": self.create_publisher(AircraftState, "state", qos),
            "controls": self.create_publisher(ControlInputs, "controls", qos),
            "air_data": self.create_publisher(AirData, "air_data", qos),
            "wind": self.create_publisher(WindEstimate, "wind/filtered", qos),
            "setpoints": self.create_publisher(AutopilotSetpoints, "autopilot_setpoints", qos),
        }
        self.clock_publisher = (self.create_publisher(Clock, "/clock", CLOCK_QOS)
                                if p["publish_clock"] else None)
        self.target_system = p["target_system"]
        self.autopilot = ""  # ArduPilot or PX4, once heard
        self.autopilot_component = 0  # its component id, once heard
        # the servo parameters being read; None when not asked for, or done
        self.servo_reads = ServoParameterReads() if p["servo_map_from_autopilot"] else None
        self.servo_map = "file"  # where the map in use comes from: file, autopilot
        # ROS time minus the autopilot's boot time [ns]: integers, as a float of seconds
        # since 1970 resolves only 0.24 us
        self.offset_ns: int | None = None
        self.last_sample: Sample | None = None
        self.watch = LinkWatch(LINK_LOST_S, p["rate_window_s"], required_hz={
            "ATTITUDE": 1.0 / p["sample_period_s"],
            "GLOBAL_POSITION_INT": 1.0 / p["position_max_age_s"],
            "VFR_HUD": 1.0 / p["air_data_max_age_s"],
            "SERVO_OUTPUT_RAW": 1.0 / p["outputs_max_age_s"]}, optional_hz={
            "LOCAL_POSITION_NED": 1.0 / p["position_max_age_s"],
            **dict.fromkeys(("RAW_IMU", "SCALED_IMU2", "HIGHRES_IMU"),
                            1.0 / p["attitude_max_age_s"]),
            **dict.fromkeys(("NAV_CONTROLLER_OUTPUT", "POSITION_TARGET_GLOBAL_INT", "WIND",
                             "WIND_COV", "RPM"), 1.0 / p["slow_max_age_s"])})
        self.counts = Counter()  # samples, reboots, bad packets, other systems' messages
        self.said: set[str] = set()  # link faults said once per node's life
        self.other_systems: set[int] = set()
        self.missing: tuple[str, ...] = ()  # streams missing at the last sample
        self.heard_s: dict[str, float] = {}  # each stream's last reading [s, wall time]
        self.ground_texts = GroundTexts(p["ground_text_interval_s"], p["ground_end_hold_s"])
        self.estimates_sent_s = -math.inf  # wall time of the last NAMED_VALUE_FLOATs [s]
        if p["ground_estimates_hz"] > 0 or p["ground_alarms"]:
            self.create_subscription(FaultEstimate, "faults/estimate", self.on_estimate, qos)
        if p["ground_alarms"]:
            self.create_subscription(FaultAlarm, "faults/alarm", self.on_alarm, qos)
        self.diagnostics = Diagnostics(self, silent_after_s=None,
                                       before_publish=self.report)
        self.create_timer(READ_PERIOD_S, self.read_link, clock=_WALL)
        self.reopen_s = 0.0  # wall time of the last attempt to open a failed link [s]
        self.create_timer(HEARTBEAT_PERIOD_S, self.send_heartbeat, clock=_WALL)
        if p["ground_alarms"]:
            self.create_timer(TEXT_PERIOD_S, self.send_texts, clock=_WALL)
        self.get_logger().info(
            f"listening on {p['connection']} for "
            f"{'the first autopilot' if not self.target_system else f'system {self.target_system}'}"
            f"; servo mapping {self.airframe.path}"
            + (" until the autopilot's SERVOn_* are read" if self.servo_reads else ""))

    def read_link(self) -> None:
        """Every message waiting on the link, in order. A link that fails (a serial port
        gone) is said once and opened again every heartbeat period until it works."""
        try:
            if self.link is None:
                self._reopen()
            while self.link is not None and (message := self.link.recv_msg()) is not None:
                self.take(message)
            self._check_link()
        except OSError as error:
            if self.link is not None:  # said when it fails, not at every attempt to reopen
                self.get_logger().error(f"link {self.parameters['connection']} failed "
                                        f"({error}): opening it again every second")
            self.link, self.reopen_s = None, time.monotonic()

    def _check_link(self) -> None:
        """The link lost or back and the streams too slow, judged once every waiting
        message is read (a node held up is not a silent link), each said once."""
        for line in self.watch.check(time.monotonic(), self.target_system, self.autopilot):
            # two call sites: rclpy fixes a call site's severity at its first call
            if line.level == "warning":
                self.get_logger().warning(line.text)
            else:
                self.get_logger().info(line.text)

    def _reopen(self) -> None:
        if time.monotonic() - self.reopen_s < HEARTBEAT_PERIOD_S:
            return
        self.reopen_s = time.monotonic()
        self.link = open_link(self.parameters["connection"], self.parameters["source_system"])
        self.get_logger().info(f"link {self.parameters['connection']} open again")

    def send_heartbeat(self) -> None:
        self._send(send_heartbeat)
        self._read_servo_setup()

    def _read_servo_setup(self) -> None:
        """Ask the autopilot for its servo parameters (again for those unanswered), once it
        is heard; give up, saying so once, after the reads' last attempt."""
        reads = self.servo_reads
        if reads is None or not self.autopilot:
            return
        if self.autopilot != "ArduPilot":
            self.get_logger().warning(f"servo_map_from_autopilot: {self.autopilot}'s servo "
                                      f"set-up is not read; the map stays {self.airframe.path}")
            self.servo_reads = None
            return
        for name in reads.due(time.monotonic()):
            self._send(lambda link, n=name: link.mav.param_request_read_send(
                self.target_system, self.autopilot_component, n.encode(), -1))
        if reads.given_up:
            self.get_logger().warning(
                f"the autopilot answered {len(reads.values)} of its "
                f"{len(reads.values) + len(reads.unanswered)} servo parameters (none for "
                f"{', '.join(reads.unanswered[:3])}...): the map stays {self.airframe.path}")
            self.servo_reads = None

    def _take_servo_parameter(self, message: Any) -> None:
        """A PARAM_VALUE of the autopilot: once every servo parameter is in, the map they
        give replaces the file's (said in one line, with what it could not express)."""
        reads = self.servo_reads
        if reads is None:
            return
        reads.take(message.param_id, message.param_value)
        if not reads.complete:
            return
        self.servo_reads = None
        try:
            airframe, notes = airframe_from_servo_parameters(
                reads.values, self.airframe, f"system {self.target_system}'s SERVOn_*")
        except ValueError as error:
            self.get_logger().error(f"the autopilot's servo parameters give no map ({error}): "
                                    f"the map stays {self.airframe.path}")
            return
        self.airframe = self.conversion.airframe = airframe
        self.servo_map = "autopilot"
        maps = "; ".join(f"{name} output {c.output} trim {c.zero:.0f} us, "
                         f"{c.span:+.0f} us to full" for name, c in airframe.controls.items())
        copies = "".join(f"; output {m.output} copies {m.of_output} x {m.factor:.3g}"
                         for m in airframe.mixed)
        self.get_logger().info(f"servo mapping from the autopilot's parameters: {maps}{copies}"
                               + "".join(f". {note}" for note in notes))

    def take(self, message: Any) -> None:
        kind = message.get_type()
        if kind == "BAD_DATA":
            self.counts["bad_packets"] += 1
            self._say_once("bad_packets", "packets failing their checksum or cut short on the "
                                          "link: dropped, counted on /diagnostics (bad_packets)")
            return
        if is_autopilot_heartbeat(message) and self._is_target(message.get_srcSystem()):
            self._heard(message)
            self.watch.heard(time.monotonic(), kind)
            return
        if not self.target_system or message.get_srcSystem() != self.target_system:
            self._other_system(message)
            return
        self.watch.heard(time.monotonic(), kind)
        if kind == "PARAM_VALUE":
            self._take_servo_parameter(message)
            return
        reading = read_message(message)
        if reading is None:
            return
        self.heard_s[reading.stream] = time.monotonic()
        out_of_order = self.assembly.out_of_order
        assembled = self.assembly.add(reading)
        if self.assembly.out_of_order > out_of_order:
            self._say_once("out_of_order", f"{kind} came out of order (older than one already "
                                           "taken): dropped, counted on /diagnostics")
        if assembled.rebooted:
            self.get_logger().warning("the autopilot's boot time went back: it rebooted; "
                                      "its clock is mapped to ROS time again")
            self.counts["reboots"] += 1
            self.offset_ns = None
            self.conversion.reset()
        for sample in assembled.samples:
            self.publish(sample)

    def _is_target(self, system: int) -> bool:
        return not self.target_system or system == self.target_system

    def _other_system(self, message: Any) -> None:
        """A message of a system other than the autopilot listened to (a second autopilot,
        a ground station): ignored, the system said once."""
        self.counts["other_systems_messages"] += 1
        system = message.get_srcSystem()
        if self.target_system and system not in self.other_systems:
            self.other_systems.add(system)
            self.get_logger().info(f"system {system} (component {message.get_srcComponent()}) "
                                   f"is on the link too: its messages are ignored; this node "
                                   f"listens to system {self.target_system}")

    def _say_once(self, what: str, text: str) -> None:
        if what not in self.said:
            self.said.add(what)
            self.get_logger().warning(text)

    def _heard(self, heartbeat: Any) -> None:
        if not self.target_system:
            self.target_system = heartbeat.get_srcSystem()
        if not self.autopilot:
            self.autopilot = AUTOPILOTS[heartbeat.autopilot]
            self.autopilot_component = heartbeat.get_srcComponent()
            self.get_logger().info(f"heard {self.autopilot} as system {self.target_system}")
            self._read_servo_setup()

    def publish(self, sample: Sample) -> None:
        """The sample on every stream, stamped with its boot time mapped to ROS time."""
        boot_ns = round(sample.boot_time_s * NANOSECONDS_PER_SECOND)
        if self.offset_ns is None:
            self.offset_ns = (0 if self.parameters["boot_time_is_ros_time"] else
                              ros_offset_ns(self.get_clock().now().nanoseconds, boot_ns))
        ros_stamp = stamp_from_nanoseconds(boot_ns + self.offset_ns)
        streams = self.conversion.streams(sample)
        messages = {"state": state_message(0.0, streams.state),
                    "controls": controls_message(0.0, streams.controls),
                    "air_data": air_data_message(0.0, streams.air_data),
                    "wind": wind_message(0.0, streams.wind_filtered_ned_mps,
                                         self.conversion.wind_filter.tau_s),
                    "setpoints": setpoints_message(0.0, streams.setpoints)}
        for name, message in messages.items():
            message.header.stamp = ros_stamp  # exact: the helpers take float seconds
            self.publishers_[name].publish(message)
        if self.clock_publisher is not None:
            self.clock_publisher.publish(Clock(clock=ros_stamp))
        self.counts["samples"] += 1
        self.last_sample = sample
        self._say_missing(sample.missing)

    def _say_missing(self, missing: tuple[str, ...]) -> None:
        """A stream going missing (older than its maximum age) and coming back, said once
        each time."""
        missing = self._heard_missing(missing)
        lost = [name for name in missing if name not in self.missing]
        back = [name for name in self.missing if name not in missing]
        if lost:
            self.get_logger().warning(f"streams missing: {', '.join(lost)} (older than their "
                                      "maximum age; published as NaN until they return)")
        if back:
            self.get_logger().info(f"streams back: {', '.join(back)}")
        self.missing = missing

    def _heard_missing(self, missing: tuple[str, ...]) -> tuple[str, ...]:
        """The streams missing that the autopilot has sent: one it never streams (PX4's
        engine speed, ArduPlane's LOCAL_POSITION_NED where its position covers it) is
        `not_streamed` on /diagnostics instead."""
        return tuple(name for name in missing if name in self.heard_s)

    def on_estimate(self, message: FaultEstimate) -> None:
        """The estimates to the ground station: NAMED_VALUE_FLOAT at most
        ground_estimates_hz, a STATUSTEXT for one crossing the threshold."""
        now_s = time.monotonic()
        hz = self.parameters["ground_estimates_hz"]
        if hz > 0 and now_s - self.estimates_sent_s >= 1.0 / hz:
            self.estimates_sent_s = now_s
            boot_ms = self._boot_ms()
            for name, value in named_values(message.names, message.values_pct):
                self._send(lambda link, n=name, v=value: link.mav.named_value_float_send(
                    boot_ms, n.encode(), v))
        if self.parameters["ground_alarms"]:
            self.ground_texts.estimates(stamp_seconds(message.header.stamp), message.names,
                                        message.values_pct)
            self.send_texts()

    def on_alarm(self, message: FaultAlarm) -> None:
        """The detector's combined alarm, its cause and the tests raising it, to the
        ground texts (onset and end said once each)."""
        try:
            tests = alarm_tests(message.alarm, message.parameter_deviation,
                                message.parameter_threshold, message.fast_alarm,
                                message.template_alarm)
        except ValueError:  # zip(strict=True): arrays of different lengths
            self.counts["malformed_alarms"] += 1
            self._say_once("malformed_alarm", "faults/alarm with per-channel arrays of "
                           "different lengths: ignored, counted on /diagnostics")
            return
        self.ground_texts.alarm(stamp_seconds(message.header.stamp), message.combined_alarm,
                                message.cause, tests)
        self.send_texts()

    def send_texts(self) -> None:
        """The next waiting STATUSTEXT, when the interval since the last one has passed."""
        text = self.ground_texts.due(time.monotonic())
        if text is not None:
            self.get_logger().info(f"to the ground station: {text.text}")
            self._send(lambda link: link.mav.statustext_send(text.severity, text.text.encode()))

    def _send(self, send: Callable[[Any], None]) -> None:
        """send(link) if the link is open (a failed link is reopened by read_link)."""
        if self.link is not None:
            with contextlib.suppress(OSError):  # read_link says the failure, reopens the link
                send(self.link)

    def _boot_ms(self) -> int:
        """The autopilot's boot time of the newest sample [ms] (0 before one)."""
        return 0 if self.last_sample is None else round(self.last_sample.boot_time_s * 1000)

    def report(self) -> None:
        """Diagnostics: the link, each message type's rate over the last judged window, the
        streams missing and those too slow."""
        now_s = time.monotonic()
        watch = self.watch
        rates = {f"rate_{kind.lower()}_hz": f"{hz:.1f}"
                 for kind, hz in sorted(watch.rates_hz.items())}
        missing = self._heard_missing(self.last_sample.missing if self.last_sample else ())
        stale = [stream for stream, heard_s in sorted(self.heard_s.items())
                 if now_s - heard_s > self.assembly.max_age_s[stream]]
        values = {VEHICLE_KEY: self.parameters["vehicle"],
                  "autopilot": self.autopilot or "-", "system": self.target_system,
                  "link": "alive" if watch.alive else "lost" if watch.heard_s else "not heard",
                  "link_losses": watch.losses,
                  "servo_map": self.servo_map if self.servo_reads is None else "file, "
                  f"reading the autopilot's ({len(self.servo_reads.values)} answered)",
                  "missing": ", ".join(missing) or "none",
                  "not_streamed": ", ".join(sorted(set(self.assembly.max_age_s)
                                                   - set(self.heard_s))) or "none",
                  "stale": ", ".join(stale) or "none",
                  "too_slow": ", ".join(watch.slow) or "none",
                  "out_of_order": self.assembly.out_of_order,
                  "ground_texts_waiting": len(self.ground_texts.waiting),
                  "ground_texts_dropped": self.ground_texts.dropped,
                  # matched on this side: a subscriber's own match can come first
                  "subscribed": ", ".join(
                      publisher.topic_name.lstrip("/") for publisher in self.publishers_.values()
                      if publisher.get_subscription_count() > 0) or "none",
                  **self.counts, **rates}
        if not watch.alive:
            self.diagnostics.update(WARN, "link lost" if watch.heard_s else
                                    "no autopilot heard", values)
        elif watch.slow:
            self.diagnostics.update(WARN, "streams too slow: " + ", ".join(watch.slow), values)
        elif missing:
            self.diagnostics.update(WARN, "streams missing: " + ", ".join(missing), values)
        else:
            self.diagnostics.update(OK, f"linked to {self.autopilot}", values)


def main(args: list[str] | None = None) -> int:
    return run_node("mavlink_node", MavlinkNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
