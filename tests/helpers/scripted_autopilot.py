"""A scripted ArduPlane on a UDP link, and mavlink_node started against it: the link tests'
autopilot, whose boot clock runs only when the test steps it."""

from __future__ import annotations

import os

from diagnostic_msgs.msg import DiagnosticArray
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_msgs.msg import AircraftState

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

STEP_S = 0.05  # the scripted autopilot's step: ATTITUDE each, the others every other
PWM_US = (1600, 1450, 1750, 1500, 0, 0, 0, 0)


class ScriptedArduPlane:
    """An ArduPlane of system 1 on udpout to the node's port; its boot clock [s] runs
    only when it steps."""

    def __init__(self, port: int, boot_s: float) -> None:
        self.link = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=1,
                                               source_component=1, dialect="ardupilotmega")
        self.boot_s = boot_s
        self.steps = 0
        self.received: list = []  # what the node sent us

    def heartbeat(self) -> None:
        self.link.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_FIXED_WING,
                                     mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4)

    def step(self, attitude: bool = True) -> None:
        """One step of the streams (ATTITUDE unless attitude is False), heartbeat once a
        second."""
        boot_ms = round(self.boot_s * 1000)
        mav = self.link.mav
        if self.steps % 20 == 0:
            self.heartbeat()
        if attitude:
            mav.attitude_send(boot_ms, 0.1, 0.05, 1.0, 0.0, 0.0, 0.0)
        if self.steps % 2 == 0:
            mav.global_position_int_send(boot_ms, 555_000_000, 93_000_000, 120_000, 20_000,
                                         1_950, -340, 120, 18_000)
            mav.vfr_hud_send(23.5, 25.0, 90, 55, 120.0, 0.3)
            mav.servo_output_raw_send(round(self.boot_s * 1e6) % 2**32, 0, *PWM_US)
        self.boot_s += STEP_S
        self.steps += 1

    def collect(self) -> None:
        while (message := self.link.recv_msg()) is not None:
            self.received.append(message)

    def packed_attitude(self, boot_s: float) -> bytes:
        message = self.link.mav.attitude_encode(round(boot_s * 1000), 0.1, 0.05, 1.0, 0, 0, 0)
        return bytes(message.pack(self.link.mav))


def run_steps(graph, autopilot: ScriptedArduPlane, count: int, attitude: bool = True) -> None:
    for _ in range(count):
        autopilot.step(attitude)
        graph.spin(STEP_S)
        autopilot.collect()


def start_node(start_process, graph, port: int, *parameters: str):
    node = start_process(ros2_run_argv("uav_mavlink", "mavlink_node", ros_args=[
        "-p", f"connection:=udpin:127.0.0.1:{port}", *(
            item for parameter in parameters for item in ("-p", parameter))]), "mavlink_node")
    received = graph.subscribe({"/state": AircraftState}, STREAM_QOS)
    received |= graph.subscribe({"/diagnostics": DiagnosticArray})
    assert graph.wait_for_publishers("/state", 1, 30), node.output()
    return node, received
