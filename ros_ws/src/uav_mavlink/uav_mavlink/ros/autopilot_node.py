"""autopilot_node: the simulator's flight streamed as ArduPlane or PX4 would, over MAVLink.

Subscribes sim_node's streams (relative names, the `qos` chosen): `state`, `controls`,
`wind/true` (the autopilot's wind estimate: the wind it flies in), `autopilot_setpoints` and,
where the aircraft has it, `air_data`, matched by stamp (uav_common.ros.matched_streams).
Each matched sample goes to the stack's emulator (uav_mavlink.autopilot_emulator: the
messages due at their stream rates, in the link's units), whose messages leave on
`connection` as system `system_id`, component 1 (the autopilot), their boot time the
sample's stamp: run with use_sim_time, the autopilot's clock is the simulation's. Without
air data its airspeed is the synthetic one (ground velocity less the wind). As ArduPlane
(`stack` ardupilot) it answers PARAM_REQUEST_READ for its servo set-up from the airframe file
(uav_mavlink.autopilot_parameters); as PX4 it answers none. `/diagnostics`: the messages
sent by type, the parameters answered, the messages a lost value kept back.
"""

from __future__ import annotations

import sys
from collections import Counter
from typing import Any

from geometry_msgs.msg import Vector3Stamped
from pymavlink import mavutil
from rclpy.clock import Clock as RosClock
from rclpy.clock import ClockType
from rclpy.node import Node
from uav_aircraft.airframe import load_airframe
from uav_aircraft.vehicle_parameter import VEHICLE_PARAMETER
from uav_aircraft.vehicles import load_vehicle
from uav_common.envelope import (
    AIR_DATA_LIMITS,
    CONTROL_LIMITS,
    SETPOINT_LIMITS,
    STATE_LIMITS,
    WIND_LIMITS,
)
from uav_common.message_fields import (
    air_data_array,
    controls_array,
    setpoints_array,
    state_array,
    true_wind_array,
)
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.matched_streams import MatchedStreams
from uav_common.ros.node_life import run_node
from uav_common.ros.parameters import QOS_PARAMETER, ParameterSpec, declare_parameters
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_fault_msgs.msg import AircraftState, AirData, AutopilotSetpoints, ControlInputs

from uav_mavlink.autopilot_emulator import (
    ARDUPLANE_ADVISED_HZ,
    ARDUPLANE_DEFAULT_HZ,
    PX4_ONBOARD_HZ,
    AutopilotEmulator,
    flight_sample,
)
from uav_mavlink.autopilot_parameters import ParameterTable
from uav_mavlink.link import DIALECT
from uav_mavlink.stream_rates import ARDUPILOT, PX4

STACKS = {"ardupilot": ARDUPILOT, "px4": PX4}  # the `stack` parameter's values
ARDUPLANE_RATES = {"advised": ARDUPLANE_ADVISED_HZ, "defaults": ARDUPLANE_DEFAULT_HZ}
PARAMETERS = {
    "connection": ParameterSpec(
        "where the autopilot's link goes, as pymavlink takes it: udpout:HOST:PORT (to a "
        "listener's udpin:, as mavlink_node's), tcpin:HOST:PORT, or a serial port DEVICE,BAUD",
        "udpout:127.0.0.1:14550"),
    "stack": ParameterSpec("the autopilot played: ardupilot (ArduPlane) or px4", "ardupilot",
                           choices=tuple(STACKS)),
    "rates": ParameterSpec(
        "ArduPlane's stream rates: advised (docs/onboard.md's settings: ATTITUDE at 25 Hz, "
        "position, servo outputs and VFR_HUD at 10 Hz) or defaults (every group at 1 Hz); "
        "PX4 streams its onboard mode's rates whatever this says", "advised",
        choices=tuple(ARDUPLANE_RATES)),
    "system_id": ParameterSpec("the autopilot's MAVLink system id", 1, 1, 255),
    "vehicle": VEHICLE_PARAMETER,
    "airframe": ParameterSpec("airframe YAML mapping the autopilot's servo outputs to surfaces "
                              "(docs/flight_logs.md); empty: the vehicle's one airframe file",
                              ""),
    "qos": QOS_PARAMETER,
}
# `state` last: see MatchedStreams
STREAMS = {"controls": (ControlInputs, controls_array, CONTROL_LIMITS, None),
           "wind/true": (Vector3Stamped, true_wind_array, WIND_LIMITS, None),
           "autopilot_setpoints": (AutopilotSetpoints, setpoints_array, SETPOINT_LIMITS, None),
           "state": (AircraftState, state_array, STATE_LIMITS, None)}
OPTIONAL_STREAMS = {"air_data": (AirData, air_data_array, AIR_DATA_LIMITS, None)}
READ_PERIOD_S = 0.05  # how often the link is read for parameter requests [s, wall time]
_WALL = RosClock(clock_type=ClockType.STEADY_TIME)


class AutopilotNode(Node):
    """Thin adapter: parameters in, matched samples to the emulator's messages on the link,
    parameter requests answered from the table, diagnostics."""

    def __init__(self) -> None:
        super().__init__("autopilot_node")
        self.parameters = p = declare_parameters(self, PARAMETERS)
        self.airframe = load_airframe(p["airframe"]
                                      or load_vehicle(p["vehicle"]).simulated_airframe_file)
        self.stack = STACKS[p["stack"]]
        self.rates_hz = ARDUPLANE_RATES[p["rates"]] if self.stack == ARDUPILOT else PX4_ONBOARD_HZ
        self.emulator = AutopilotEmulator(self.stack, self.airframe, self.rates_hz)
        self.table = ParameterTable(self.airframe) if self.stack == ARDUPILOT else None
        self.link = mavutil.mavlink_connection(
            p["connection"], source_system=p["system_id"],
            source_component=mavutil.mavlink.MAV_COMP_ID_AUTOPILOT1, dialect=DIALECT,
            robust_parsing=True, autoreconnect=False)
        self.sent: Counter[str] = Counter()  # messages sent, by type
        self.counts: Counter[str] = Counter()  # samples, parameters answered, unknown
        self.streams = MatchedStreams(
            self, STREAMS, self.stream, self.reboot, "the autopilot reboots (its boot time "
            "starts again)", STREAM_QOS_PROFILES[p["qos"]], OPTIONAL_STREAMS)
        self.streams.subscribe()
        self.create_timer(READ_PERIOD_S, self.read_link, clock=_WALL)
        self.diagnostics = Diagnostics(self, silent_after_s=None, before_publish=self.report)
        self.get_logger().info(
            f"{self.stack} on {p['connection']} as system {p['system_id']}"
            + (f" at the {p['rates']} rates" if self.stack == ARDUPILOT else "")
            + f"; servo mapping {self.airframe.path}")

    def reboot(self) -> None:
        """The simulation started again: a new boot, its streams due from its first sample."""
        self.emulator = AutopilotEmulator(self.stack, self.airframe, self.rates_hz)

    def stream(self, time_s: float, payloads: dict[str, Any]) -> None:
        """Send the messages due at the matched sample of sim time time_s [s]."""
        sample = flight_sample(time_s, payloads["state"], payloads["controls"],
                               payloads.get("air_data"), payloads["wind/true"],
                               payloads["autopilot_setpoints"])
        unsent = sum(self.emulator.unsent.values())
        for message in self.emulator.messages(sample):
            self.link.mav.send(message)
            self.sent[message.get_type()] += 1
        if sum(self.emulator.unsent.values()) > unsent:
            self.get_logger().warning(
                f"at {time_s:.2f} s a message was not sent: a value it carries is missing "
                "(NaN, a lost sensor)", throttle_duration_sec=5.0)
        self.counts["samples"] += 1

    def read_link(self) -> None:
        """Answer the parameter requests addressed to this autopilot."""
        while (message := self.link.recv_msg()) is not None:
            if (message.get_type() == "PARAM_REQUEST_READ"
                    and message.target_system == self.parameters["system_id"]):
                self.answer(message.param_id, message.param_index)

    def answer(self, name: str, index: int) -> None:
        """PARAM_VALUE for the parameter asked for; none, as ArduPilot, for one it does not
        have (counted, and said once each)."""
        value = self.table.read(name, index) if self.table is not None else None
        if value is None:
            if self.counts["unknown_parameters"] == 0:
                self.get_logger().info(
                    f"asked for parameter {name or f'#{index}'}, which this {self.stack} "
                    "does not have: not answered (further ones counted on /diagnostics)")
            self.counts["unknown_parameters"] += 1
            return
        self.link.mav.send(self.table.message(value))
        self.counts["parameters_answered"] += 1

    def report(self) -> None:
        """Diagnostics: what was sent, the parameters answered, the messages kept back."""
        unsent = ", ".join(sorted(self.emulator.unsent)) or "none"
        values = {"stack": self.stack, "connection": self.parameters["connection"],
                  **self.counts, "unsent": unsent,
                  "implausible_values": self.streams.implausible_values,
                  "dropped_incomplete_samples": self.streams.dropped_sets,
                  "stamp_resets": self.streams.restarts,
                  **{f"sent_{kind.lower()}": count for kind, count in sorted(self.sent.items())}}
        if self.emulator.unsent:
            self.diagnostics.update(WARN, f"messages not sent for a missing value: {unsent}",
                                    values)
        else:
            self.diagnostics.update(OK, f"streaming as {self.stack}", values)


def main(args: list[str] | None = None) -> int:
    return run_node("autopilot_node", AutopilotNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
