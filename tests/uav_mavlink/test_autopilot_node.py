"""autopilot_node on UDP loopback: a simulated flight's streams, sent as ArduPlane or PX4
would, come out of mavlink_node as the flight again (to the link's resolution, each channel
interpolated between its message's readings), stamped with the flight's own times; and the
simulated ArduPlane answers a parameter read from the airframe file."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from helpers.diagnostics import latest_values
from uav_aircraft.airframe import load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.loopback import free_udp_port
from uav_common.message_fields import controls_array, stamp_nanoseconds, state_array
from uav_common.ros.messages import (
    air_data_message,
    controls_message,
    setpoints_message,
    state_message,
    true_wind_message,
)
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_msgs.msg import AircraftState, AirData, AutopilotSetpoints, ControlInputs
from uav_mavlink.autopilot_emulator import (
    ARDUPLANE_ADVISED_HZ,
    PX4_ONBOARD_HZ,
    AutopilotEmulator,
    flight_sample,
)
from uav_mavlink.ros.autopilot_node import STACKS
from uav_mavlink.stream_rates import ARDUPILOT
from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import Simulation

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

pytestmark = pytest.mark.integration

DURATION_S = 3.0
PUBLISH_PAUSE_S = 0.01  # wall time between samples: the link has no flow control
PLAYED = "/sim"  # autopilot_node's namespace: its inputs apart from mavlink_node's outputs
# How finely the link carries each state channel: float32 angles and rates, degE7, mm, cm/s
# (PX4's velocities float32 in LOCAL_POSITION_NED).
RESOLUTION = {"latitude": 2e-9, "longitude": 2e-9, "altitude": 6e-4, "roll": 1e-6,
              "pitch": 1e-6, "yaw": 1e-6, "velocity_north": 6e-3, "velocity_east": 6e-3,
              "velocity_down": 6e-3, "roll_rate": 1e-6, "pitch_rate": 1e-6, "yaw_rate": 1e-6}
# The message carrying each state channel, by stack (PX4's velocities its LOCAL_POSITION_NED).
_ATTITUDE = ("roll", "pitch", "yaw", "roll_rate", "pitch_rate", "yaw_rate")
_POSITION = ("latitude", "longitude", "altitude")
_VELOCITY = ("velocity_north", "velocity_east", "velocity_down")
CARRIED_BY = {
    "ardupilot": {**dict.fromkeys(_ATTITUDE, "ATTITUDE"),
                  **dict.fromkeys(_POSITION + _VELOCITY, "GLOBAL_POSITION_INT")},
    "px4": {**dict.fromkeys(_ATTITUDE, "ATTITUDE"),
            **dict.fromkeys(_POSITION, "GLOBAL_POSITION_INT"),
            **dict.fromkeys(_VELOCITY, "LOCAL_POSITION_NED")}}


def flight() -> list:
    """The default scenario's first DURATION_S, its samples at 20 Hz."""
    simulation = Simulation(dataclasses.replace(load_scenario(default_scenario_path()),
                                                duration_s=DURATION_S))
    samples = [simulation.sample()]
    while not simulation.finished:
        samples.append(simulation.step())
    return samples


def sent_at(stack: str, samples: list) -> dict[str, np.ndarray]:
    """The times [s] of the samples autopilot_node sends each message type on, at its
    default rates (ArduPlane's advised ones, PX4's onboard): the emulator's schedule."""
    airframe = load_airframe(load_vehicle("aerosonde").simulated_airframe_file)
    emulator = AutopilotEmulator(STACKS[stack], airframe, ARDUPLANE_ADVISED_HZ
                                 if STACKS[stack] == ARDUPILOT else PX4_ONBOARD_HZ)
    times_s: dict[str, list[float]] = {}
    for s in samples:
        for message in emulator.messages(flight_sample(s.time_s, s.state, s.controls,
                                                       s.air_data, s.wind_ned_mps,
                                                       s.setpoints)):
            times_s.setdefault(message.get_type(), []).append(s.time_s)
    return {kind: np.array(times) for kind, times in times_s.items()}


def start_link(start_process, stack: str, port: int, listener_args: tuple = ()) -> None:
    """mavlink_node listening on the port, stamping with the boot time as it is (and
    listener_args), and autopilot_node playing the stack to it from PLAYED."""
    start_process(ros2_run_argv("uav_mavlink", "mavlink_node", ros_args=[
        "-p", f"connection:=udpin:127.0.0.1:{port}", "-p", "boot_time_is_ros_time:=true",
        *listener_args]), "mavlink_node")
    start_process(ros2_run_argv("uav_mavlink", "autopilot_node", ros_args=[
        "-r", f"__ns:={PLAYED}", "-p", f"connection:=udpout:127.0.0.1:{port}",
        "-p", f"stack:={stack}"]), "autopilot_node")


def wait_until_sent_here(graph, received: dict, topic: str) -> None:
    """Until mavlink_node's topic is matched on both sides (received: this test's
    subscriptions, /diagnostics among them): its first samples go out at once, and a
    subscription that sees the publisher may not be sent to yet."""
    assert graph.wait_for_publishers(f"/{topic}", 1, 30)
    assert graph.wait(f"mavlink_node sending {topic} here", lambda: topic in latest_values(
        received["/diagnostics"], "/mavlink_node").get("subscribed", "").split(", "), 30)


def played_publishers(graph) -> dict:
    """Publishers on sim_node's topics under PLAYED, once autopilot_node listens (made once
    per test: the graph fixture keeps its node)."""
    publishers = {name: graph.node.create_publisher(kind, f"{PLAYED}/{name}", STREAM_QOS)
                  for name, kind in (("state", AircraftState), ("controls", ControlInputs),
                                     ("air_data", AirData), ("wind/true", Vector3Stamped),
                                     ("autopilot_setpoints", AutopilotSetpoints))}
    assert graph.wait("autopilot_node subscribed", lambda: all(
        p.get_subscription_count() >= 1 for p in publishers.values()), 30)
    return publishers


def publish_flight(graph, samples: list, publishers: dict | None = None) -> None:
    """The samples on sim_node's topics under PLAYED, paced (played_publishers' unless
    given)."""
    publishers = publishers or played_publishers(graph)
    for sample in samples:
        t = sample.time_s
        for name, message in (("controls", controls_message(t, sample.controls)),
                              ("air_data", air_data_message(t, sample.air_data)),
                              ("wind/true", true_wind_message(t, sample.wind_ned_mps)),
                              ("autopilot_setpoints", setpoints_message(t, sample.setpoints)),
                              ("state", state_message(t, sample.state))):
            publishers[name].publish(message)
        graph.spin(PUBLISH_PAUSE_S)


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("stack", ["ardupilot", "px4"])
def test_the_flight_comes_out_of_mavlink_node_as_it_went_in(start_process, graph, stack):
    port = free_udp_port()
    start_link(start_process, stack, port)
    received = graph.subscribe({"/state": AircraftState}, STREAM_QOS)
    received |= graph.subscribe({"/diagnostics": DiagnosticArray})
    wait_until_sent_here(graph, received, "state")
    samples = flight()
    publish_flight(graph, samples)
    # every sample: the last one's messages release it (each stream has a reading at it)
    assert graph.wait("the flight out of mavlink_node",
                      lambda: len(received["/state"]) >= len(samples), 30), (
        len(received["/state"]), len(samples), "missing at", sorted(
            {round(s.time_s, 2) for s in samples} - {round(stamp_nanoseconds(
                m.header.stamp) / 1e9, 2) for m in received["/state"]}),
        latest_values(received["/diagnostics"], "/mavlink_node"),
        latest_values(received["/diagnostics"], f"{PLAYED}/autopilot_node"))
    graph.spin(2.0, until=lambda: latest_values(received["/diagnostics"],
                                                f"{PLAYED}/autopilot_node").get("samples")
               == str(len(samples)))

    flown = {round(s.time_s * 1e9): s for s in samples}
    times_ns = sorted(flown)
    states = received["/state"]
    # stamped with the flight's own times, to the nanosecond
    assert [stamp_nanoseconds(m.header.stamp) for m in states] == times_ns
    # mavlink_node interpolates each channel linearly between its message's readings: where
    # the message did not go (ArduPlane's 10 Hz position between its readings) the flight's
    # own value lies off that line (by up to 0.13 m and 0.2 m/s, measured: the simulator's
    # noise), so the channel is the line through the flight at the message's times
    sent_s = sent_at(stack, samples)
    times_s = np.array([s.time_s for s in samples])
    flown_states = np.array([s.state for s in samples])
    expected = {name: np.interp(times_s, sent_s[kind], flown_states[
        np.searchsorted(times_s, sent_s[kind]), STATE_CHANNELS.index(name)])
        for name, kind in CARRIED_BY[stack].items()}
    assert len(sent_s["ATTITUDE"]) == len(samples)  # angles: no wrap to interpolate across
    # the first sample goes out with the first ATTITUDE, before the other streams' first
    for index, message in enumerate(states[1:], start=1):
        out = state_array(message)
        for name, resolution in RESOLUTION.items():
            error = out[STATE_CHANNELS.index(name)] - expected[name][index]
            if name == "yaw":
                error = math.remainder(error, 2 * math.pi)
            assert abs(error) <= resolution, (stack, message.header.stamp, name, error)
    engine = np.array([state_array(m)[STATE_CHANNELS.index("engine_speed")] for m in states])
    if stack == "ardupilot":  # RPM, at ATTITUDE's rate, right after it: none at the first
        assert np.isnan(engine[0])
        np.testing.assert_allclose(engine[1:], [s.state[STATE_CHANNELS.index("engine_speed")]
                                                for s in samples[1:]], rtol=1e-6)
    else:  # PX4 streams no engine speed
        assert np.isnan(engine).all()
    values = latest_values(received["/diagnostics"], f"{PLAYED}/autopilot_node")
    assert values["sent_attitude"] == str(len(samples)) and values["unsent"] == "none", values


@pytest.mark.timeout(60)
def test_the_played_arduplane_answers_a_servo_parameter_from_the_airframe(start_process,
                                                                           graph):
    port = free_udp_port()
    ground = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255,
                                        source_component=190, dialect="ardupilotmega")
    start_process(ros2_run_argv("uav_mavlink", "autopilot_node", ros_args=[
        "-r", f"__ns:={PLAYED}", "-p", f"connection:=udpout:127.0.0.1:{port}",
        "-p", "system_id:=7"]), "autopilot_node")
    publish_flight(graph, flight()[:5])  # it sends from its first sample on
    heartbeat = None
    for _ in range(100):
        graph.spin(0.05)
        heartbeat = heartbeat or ground.recv_match(type="HEARTBEAT", blocking=False)
        if heartbeat:
            break
    assert heartbeat is not None and heartbeat.get_srcSystem() == 7
    ground.mav.param_request_read_send(7, 1, b"SERVO2_FUNCTION", -1)
    ground.mav.param_request_read_send(7, 1, b"NO_SUCH_PARAM", -1)
    answer = None
    for _ in range(100):
        graph.spin(0.05)
        answer = answer or ground.recv_match(type="PARAM_VALUE", blocking=False)
        if answer:
            break
    assert answer is not None
    assert (answer.param_id, answer.param_value, answer.param_type) == (
        "SERVO2_FUNCTION", 19.0, mavutil.mavlink.MAV_PARAM_TYPE_INT16)
    ground.close()


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_the_servo_map_read_from_the_autopilot_replaces_a_wrong_file(start_process, graph,
                                                                     tmp_path):
    """mavlink_node given an airframe file with the aileron and elevator outputs swapped and
    trims 100 us off reads the played ArduPlane's SERVOn_* and maps its outputs right."""
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text(
        "name: wrong\noutput_unit: pwm_us\nsurfaces:\n"
        "  aileron:  {output: 2, trim_us: 1400, throw_us: 400, max_deflection_rad: 0.5236, "
        "sign: -1}\n"
        "  elevator: {output: 1, trim_us: 1600, throw_us: 400, max_deflection_rad: 0.5236, "
        "sign: -1}\n"
        "  rudder:   {output: 3, trim_us: 1500, throw_us: 400, max_deflection_rad: 0.5236, "
        "sign: -1}\n"
        "  throttle: {output: 4, idle_us: 1100, full_us: 1900}\n")
    port = free_udp_port()
    start_link(start_process, "ardupilot", port, ("-p", f"airframe:={wrong}",
                                                  "-p", "servo_map_from_autopilot:=true"))
    received = graph.subscribe({"/controls": ControlInputs}, STREAM_QOS)
    received |= graph.subscribe({"/diagnostics": DiagnosticArray})
    wait_until_sent_here(graph, received, "controls")
    samples = flight()
    publishers = played_publishers(graph)
    publish_flight(graph, samples[:5], publishers)  # heard: the parameters are asked for
    assert graph.wait("the map read", lambda: latest_values(
        received["/diagnostics"], "/mavlink_node").get("servo_map") == "autopilot", 30)
    first = len(received["/controls"])
    publish_flight(graph, samples[5:], publishers)
    assert graph.wait("the flight out of mavlink_node",
                      lambda: len(received["/controls"]) >= len(samples), 30), (
        first, len(received["/controls"]), len(samples))
    # SERVO_OUTPUT_RAW goes at 10 Hz: each control is the line through the flown one at its
    # times; whole microseconds on the link: 1 us of a 500 us throw is 1.05e-3 rad at
    # 0.5236 rad, of the 1000 us throttle 1e-3
    sent_s = sent_at("ardupilot", samples)["SERVO_OUTPUT_RAW"]
    times_s = np.array([s.time_s for s in samples])
    flown = np.array([s.controls for s in samples])[np.searchsorted(times_s, sent_s)]
    out = np.array([controls_array(m) for m in received["/controls"][first:]])
    for name in ("aileron", "elevator", "rudder", "throttle"):
        index = CONTROL_CHANNELS.index(name)
        expected = np.interp(times_s[first:], sent_s, flown[:, index])
        np.testing.assert_allclose(out[:, index], expected, atol=1.1e-3, err_msg=name)
