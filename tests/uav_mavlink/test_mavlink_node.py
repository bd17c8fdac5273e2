"""mavlink_node against a scripted ArduPlane on UDP loopback: the project's streams on the grid
of the autopilot's clock, in the project's units and conventions; another system's messages
ignored; and nothing sent to the aircraft but the node's own heartbeat."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from helpers.diagnostics import latest_values
from uav_aircraft.fdm import loaded_fuel_kg
from uav_aircraft.vehicles import load_vehicle
from uav_common.loopback import free_udp_port
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_msgs.msg import (
    AircraftState,
    AirData,
    AutopilotSetpoints,
    ControlInputs,
    WindEstimate,
)

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

pytestmark = pytest.mark.integration

STEP_S = 0.02  # the scripted ATTITUDE at 50 Hz; the rest at 10 Hz, WIND at 2 Hz
STEPS = 150  # 3 s of the autopilot's time
BOOT_S = 100.0  # its boot time at the first step [s]
PITCH_TRIM_DEG = 2.0
WIND_NED_MPS = (3.0, -4.0, 0.5)
PWM_US = (1600, 1450, 1750, 1500, 0, 0, 0, 0)  # aileron, elevator, throttle, rudder (aerosonde_sim)


def roll_at(boot_s):
    """The scripted roll [rad] at boot time(s) boot_s [s]."""
    return 0.3 * np.sin(boot_s)


def send_step(link, stranger, step: int) -> None:
    """One 50 Hz step of the scripted ArduPlane (system 1) and, from the second step on, of
    a second autopilot on the same link (system 2), heard after the first."""
    boot_s = BOOT_S + step * STEP_S
    boot_ms = round(boot_s * 1000)
    mav = link.mav
    if step % 50 == 0:
        mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_FIXED_WING,
                           mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4)
    if step % 50 == 1:
        stranger.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_FIXED_WING,
                                    mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4)
    mav.attitude_send(boot_ms, float(roll_at(boot_s)), 0.05, 1.0, 0.1, -0.02, 0.03)
    if step > 0:
        stranger.mav.attitude_send(boot_ms, 1.2, 1.2, 1.2, 1.0, 1.0, 1.0)
    if step % 5 == 0:
        mav.global_position_int_send(boot_ms, 555_000_000, 93_000_000, 120_000, 20_000, 1_950,
                                     -340, 120, 18_000)
        mav.vfr_hud_send(23.5, 25.0, 90, 55, 120.0, 0.3)
        mav.servo_output_raw_send(round(boot_s * 1e6) % 2**32, 0, *PWM_US)
        mav.nav_controller_output_send(-20.0, 4.0, 90, 95, 300, 1.5, 120.0, 2.0)
    if step % 25 == 0:
        north, east, down = WIND_NED_MPS
        mav.wind_send(math.degrees(math.atan2(-east, -north)),
                      math.sqrt(north**2 + east**2 + down**2), down)


@pytest.mark.timeout(120)
def test_an_arduplane_stream_becomes_the_projects_streams(start_process, graph):
    port = free_udp_port()
    node = start_process(ros2_run_argv("uav_mavlink", "mavlink_node", ros_args=[
        "-p", f"connection:=udpin:127.0.0.1:{port}", "-p", f"pitch_trim_deg:={PITCH_TRIM_DEG}",
    ]), "mavlink_node")
    received = graph.subscribe({"/state": AircraftState, "/controls": ControlInputs,
                                "/air_data": AirData, "/wind/filtered": WindEstimate,
                                "/autopilot_setpoints": AutopilotSetpoints}, STREAM_QOS)
    received |= graph.subscribe({"/diagnostics": DiagnosticArray})
    for topic in ("/state", "/controls", "/air_data", "/wind/filtered",
                  "/autopilot_setpoints"):
        assert graph.wait_for_publishers(topic, 1, 30), node.output()
    # matched on this side is not yet on the node's: a sample it publishes before its writer
    # matches this test's reader is lost, and under load (3 busy cores) one run in four
    # lacked one. Its diagnostics (each second) heard mean its writers have matched this
    # test's readers: the streams' readers were announced before /diagnostics', in order.
    assert graph.wait("the node's diagnostics",
                      lambda: latest_values(received["/diagnostics"], "/mavlink_node"), 30)
    link = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=1,
                                      source_component=1, dialect="ardupilotmega")
    stranger = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=2,
                                          source_component=1, dialect="ardupilotmega")
    sent_to_us = []
    for step in range(STEPS):
        send_step(link, stranger, step)
        graph.spin(STEP_S)
        for peer in (link, stranger):  # the node answers whichever peer it heard last
            while (message := peer.recv_msg()) is not None:
                sent_to_us.append(message)
    # the grid points from the first ATTITUDE to the last reading of the 10 Hz streams (each
    # grid point waits for a reading of every stream at or after it)
    expected_samples = math.floor((STEPS - 1) // 5 * 5 * STEP_S / 0.05 + 1e-9) + 1
    assert graph.wait("every sample", lambda: len(received["/state"]) >= expected_samples, 10)
    graph.spin(2.0, until=lambda: latest_values(received["/diagnostics"], "/mavlink_node")
               .get("autopilot") == "ArduPilot")  # said after the stream
    print(node.output())

    states = received["/state"]
    stamps_ns = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in states])
    assert set(np.diff(stamps_ns)) == {50_000_000}  # the autopilot's grid, to the nanosecond
    assert len(states) == expected_samples
    boot_s = BOOT_S + 0.05 * np.arange(len(states))  # the grid, from the first reading
    # interpolated between the neighbouring ATTITUDEs, float32 on the link
    sent_s = BOOT_S + STEP_S * np.arange(STEPS)
    np.testing.assert_allclose([m.roll_rad for m in states],
                               np.interp(boot_s, sent_s, roll_at(sent_s)), atol=1e-6)
    assert all(m.pitch_rad == pytest.approx(0.05 + math.radians(PITCH_TRIM_DEG), abs=1e-6)
               for m in states)
    last = states[-1]
    assert last.latitude_rad == pytest.approx(math.radians(55.5), rel=1e-12)
    assert last.altitude_m == pytest.approx(120.0)
    assert (last.velocity_north_mps, last.velocity_down_mps) == pytest.approx((19.5, 1.2))
    assert (last.roll_rate_radps, last.yaw_rate_radps) == pytest.approx((0.1, 0.03), abs=1e-6)
    # no engine speed streamed; the fuel the default vehicle's model carries (5 kg)
    assert math.isnan(last.engine_speed_rpm)
    assert last.fuel_mass_kg == pytest.approx(loaded_fuel_kg(load_vehicle("aerosonde")))

    controls = received["/controls"][-1]
    limit_rad = 0.5236  # aerosonde_sim.yaml: 500 us of throw to 0.5236 rad
    assert controls.aileron_rad == pytest.approx(limit_rad * 100 / 500)
    assert controls.elevator_rad == pytest.approx(-limit_rad * 50 / 500)
    assert controls.rudder_rad == 0.0 and controls.throttle == pytest.approx(0.75)
    assert (controls.flap_rad, controls.mixture, controls.ignition) == (0.0, 1.0, True)
    air_data = received["/air_data"][-1]
    assert air_data.true_airspeed_mps == pytest.approx(23.5)
    assert math.isnan(air_data.angle_of_attack_rad) and math.isnan(air_data.sideslip_rad)
    wind = received["/wind/filtered"][-1]
    assert (wind.north_mps, wind.east_mps, wind.down_mps) == pytest.approx(WIND_NED_MPS,
                                                                           abs=1e-5)
    setpoints = received["/autopilot_setpoints"][-1]
    assert (setpoints.roll_rad, setpoints.pitch_rad) == pytest.approx(
        (math.radians(-20.0), math.radians(4.0)))
    assert math.isnan(setpoints.velocity_down_mps)

    values = latest_values(received["/diagnostics"], "/mavlink_node")
    assert (values["autopilot"], values["system"]) == ("ArduPilot", "1"), values
    # read-only: the node sent us its heartbeat as an onboard computer, and nothing else
    assert sent_to_us and {m.get_type() for m in sent_to_us} == {"HEARTBEAT"}
    assert all((m.get_srcComponent(), m.type, m.autopilot) == (
        191, mavutil.mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavutil.mavlink.MAV_AUTOPILOT_INVALID)
        for m in sent_to_us)


@pytest.mark.timeout(120)
def test_arduplanes_one_hertz_defaults_are_said_once_with_the_parameter_to_raise(
        start_process, graph):
    """The scripted ArduPlane at its default stream rates, 1 Hz a group, but VFR_HUD at 2 Hz
    (SRn_EXTRA2 raised), for 6 s of wall time; the node judges rates over 1.5 s windows:
    the three slow messages are said once each, however many windows find them slow."""
    port = free_udp_port()
    node = start_process(ros2_run_argv("uav_mavlink", "mavlink_node", ros_args=[
        "-p", f"connection:=udpin:127.0.0.1:{port}", "-p", "rate_window_s:=1.5"]),
        "mavlink_node")
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray})["/diagnostics"]
    assert graph.wait_for_publishers("/diagnostics", 1, 30), node.output()
    link = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=1,
                                      source_component=1, dialect="ardupilotmega")
    judged = []  # the too_slow values /diagnostics said, in order
    for half_second in range(12):
        boot_ms = round(1000 * (BOOT_S + 0.5 * half_second))
        link.mav.vfr_hud_send(20.0, 20.0, 0, 50, 100.0, 0.0)
        if half_second % 2 == 0:
            link.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_FIXED_WING,
                                    mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4)
            link.mav.attitude_send(boot_ms, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            link.mav.global_position_int_send(boot_ms, 0, 0, 0, 0, 0, 0, 0, 0)
            link.mav.servo_output_raw_send(boot_ms * 1000, 0, *PWM_US)
        graph.spin(0.5)
        judged.append(latest_values(diagnostics, "/mavlink_node").get("too_slow"))
    slow = "ATTITUDE, GLOBAL_POSITION_INT, SERVO_OUTPUT_RAW"
    assert slow in judged, judged  # (6 s: three windows or more judged them)
    lines = [line for line in node.output().splitlines() if "arrives at" in line]
    assert len(lines) == 3, node.output()  # each said once; VFR_HUD's 2 Hz is enough
    assert any("ATTITUDE arrives at" in line and "the chain needs 20 Hz: raise SRn_EXTRA1 "
               "(MAVm_EXTRA1 from ArduPilot 4.7" in line for line in lines), lines
    assert any("SERVO_OUTPUT_RAW" in line and "SRn_RC_CHAN" in line for line in lines), lines
