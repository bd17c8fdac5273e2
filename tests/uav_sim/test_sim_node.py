"""sim_node as a process: every stream at the sensor rate in sim time, /clock and
/diagnostics stamped in it, its own end; no air_data when the aircraft carries none."""

from __future__ import annotations

import subprocess

import pytest
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from rosgraph_msgs.msg import Clock
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import ros2_run_argv
from uav_fault_msgs.msg import AircraftState, AirData, ControlInputs, FaultVector, WindEstimate
from uav_sim.paths import scenarios_dir

pytestmark = pytest.mark.integration

DURATION_S = 10.0
RATE_HZ = 20.0
STREAMS = {
    "/state": AircraftState,
    "/controls": ControlInputs,
    "/wind/filtered": WindEstimate,
    "/faults/seeded": FaultVector,
    "/wind/true": Vector3Stamped,
    "/air_data": AirData,
}


def sim_argv(scenario, real_time_factor: float) -> list[str]:
    return ros2_run_argv("uav_sim", "sim_node", ros_args=[
        "-p", f"scenario:={scenario}", "-p", f"sensor_rate_hz:={RATE_HZ}",
        "-p", f"real_time_factor:={real_time_factor}", "-p", "wait_for_subscribers:=1"])


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("real_time_factor", [5.0, 0.0], ids=["paced", "as-fast-as-acked"])
def test_sim_node_publishes_every_stream_at_the_rate_and_ends(
    short_scenario, graph, start_process, real_time_factor
):
    received = graph.subscribe(STREAMS, STREAM_QOS)
    clock = graph.subscribe({"/clock": Clock})["/clock"]
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray},
                                  DIAGNOSTICS_QOS)["/diagnostics"]
    scenario = short_scenario(DURATION_S)
    sim = start_process(sim_argv(scenario, real_time_factor), "sim_node")
    expected = int(DURATION_S * RATE_HZ) + 1
    graph.spin(60.0, until=lambda: not sim.running())
    assert sim.wait(timeout_s=10) == 0, sim.output()
    assert "finished at 10 s of simulation time" in sim.output()
    # the last messages may still be on their way (the last /clock too)
    graph.spin(10.0, until=lambda: all(len(messages) >= expected
                                       for messages in received.values())
               and clock and stamp_seconds(clock[-1].clock) >= DURATION_S)
    for topic, messages in received.items():
        stamps = [stamp_seconds(message.header.stamp) for message in messages]
        print(f"{topic}: {len(stamps)} messages, stamps {stamps[0]:.2f} .. {stamps[-1]:.2f} s")
        assert len(stamps) == expected, topic
        assert stamps == pytest.approx([k / RATE_HZ for k in range(expected)], abs=1e-9), topic
    assert clock and stamp_seconds(clock[-1].clock) == pytest.approx(DURATION_S)
    health_stamps = [stamp_seconds(array.header.stamp) for array in diagnostics
                     if any(status.name == "/sim_node" for status in array.status)]
    print(f"/diagnostics of sim_node stamped at {health_stamps} s")
    assert health_stamps and all(0.0 <= t <= DURATION_S for t in health_stamps)  # sim time
    seeded = received["/faults/seeded"][-1]
    assert list(seeded.names)[:4] == [
        "right_wing_lift_loss",
        "right_wing_drag_increase",
        "left_wing_lift_loss",
        "left_wing_drag_increase",
    ]


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_without_air_data_on_board_no_air_data_is_published(short_scenario, graph,
                                                             start_process):
    received = graph.subscribe({"/state": AircraftState, "/air_data": AirData}, STREAM_QOS)
    scenario = short_scenario(3.0, sensors={"air_data": False, "noise": True})
    sim = start_process(sim_argv(scenario, 0.0), "sim_node")
    graph.spin(60.0, until=lambda: received["/state"])
    publishers = {topic: graph.node.count_publishers(topic) for topic in ("/state", "/air_data")}
    graph.spin(60.0, until=lambda: not sim.running())
    assert sim.wait(timeout_s=10) == 0, sim.output()
    expected = int(3.0 * RATE_HZ) + 1
    graph.spin(10.0, until=lambda: len(received["/state"]) >= expected)  # the last ones
    assert publishers == {"/state": 1, "/air_data": 0}
    assert len(received["/state"]) == expected
    assert received["/air_data"] == []


@pytest.mark.timeout(60)
def test_sim_node_with_a_missing_scenario_ends_with_one_message(tmp_path):
    missing = tmp_path / "nope.yaml"
    result = subprocess.run(
        ros2_run_argv("uav_sim", "sim_node", ros_args=["-p", f"scenario:={missing}"]),
        capture_output=True,
        text=True,
        timeout=50,
    )
    assert result.returncode == 2  # bad input
    assert "Traceback" not in result.stderr
    assert str(missing) in result.stderr


@pytest.mark.timeout(60)
def test_a_vehicle_other_than_the_scenarios_ends_sim_node_with_one_line():
    scenario = scenarios_dir() / "default.yaml"
    result = subprocess.run(
        ros2_run_argv("uav_sim", "sim_node", ros_args=["-p", f"scenario:={scenario}", "-p",
                                                       "vehicle:=carbon_z"]),
        capture_output=True, text=True, timeout=50)
    assert result.returncode == 2
    assert result.stderr == (f"sim_node: parameter vehicle is 'carbon_z', but the scenario "
                             f"{scenario} flies 'aerosonde'\n")


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_simulator_on_sim_time_follows_the_clock_and_ends_when_it_stops(
        short_scenario, graph, start_process):
    """The second vehicle's simulator: it steps only as far as /clock goes (its state stamps
    never run ahead of the clock), and a clock that stops before its scenario's end ends it
    with one line and status 2 after clock_stall_s."""
    states = graph.subscribe({"/state": AircraftState}, STREAM_QOS)["/state"]
    clock = graph.node.create_publisher(Clock, "/clock", 10)
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        "-p", f"scenario:={short_scenario(DURATION_S)}", "-p", "use_sim_time:=true",
        "-p", "clock_stall_s:=2.0", "-p", "wait_for_subscribers:=1"]), "sim_node")
    # the simulator's /clock subscription matched with this test's clock, as the clock
    # sees it, and the simulator waiting for this test's state subscription
    assert graph.wait("the simulator subscribed to this test's /clock",
                      lambda: clock.get_subscription_count() >= 1, timeout_s=30), sim.output()
    assert graph.wait_for_publishers("/state", 1, timeout_s=30)
    assert graph.node.count_publishers("/clock") == 1  # this test's: the simulator follows
    for step in range(1, 41):  # the clock to 2 s, then no more
        clock_s = step / RATE_HZ
        clock.publish(Clock(clock=Time(sec=int(clock_s), nanosec=round(clock_s % 1 * 1e9))))
        graph.spin(0.02)
    assert sim.wait(timeout_s=30) == 2, sim.output()
    graph.spin(10.0, until=lambda: len(states) >= 41)  # the last ones may be on their way
    stamps = [stamp_seconds(message.header.stamp) for message in states]
    print(f"{len(stamps)} states, the last at {stamps[-1]} s")
    assert stamps == pytest.approx([k / RATE_HZ for k in range(41)])
    assert ("the /clock it follows stood still at 2 s for 2 s of wall time, before this "
            "scenario's end at 10 s") in sim.output()
