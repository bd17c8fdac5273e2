"""standard_topics_node beside sim_node under a namespace: one /tf, Odometry, Imu and
NavSatFix per state with its stamp and REP 105's frames (the vehicle's base_link prefixed),
their values consistent with the state they come from, the flown track, and each seeded
fault as a Float64."""

from __future__ import annotations

import math

import numpy as np
import pytest
from nav_msgs.msg import Odometry, Path
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu, NavSatFix
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage
from uav_aircraft.frames import GRAVITY_MPS2
from uav_common.message_fields import stamp_seconds, state_array
from uav_common.ros.qos import STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv
from uav_fault_estimator.viewing.standard_frames import VELOCITY_NED
from uav_fault_msgs.msg import AircraftState, FaultVector

pytestmark = pytest.mark.integration

DURATION_S = 6.0
SEEDED = "/uav2/faults/seeded_pct/right_wing_lift_loss"


def flown(received: dict, topic: str) -> dict[float, object]:
    """The topic's messages by stamp [s]."""
    return {stamp_seconds(message.header.stamp): message for message in received[topic]}


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_each_state_is_published_in_the_standard_frames(short_scenario, start_process, graph):
    namespace = ["-r", "__ns:=/uav2"]
    received = graph.subscribe({"/uav2/state": AircraftState, "/uav2/odom": Odometry,
                                "/uav2/imu": Imu, "/uav2/fix": NavSatFix, "/tf": TFMessage,
                                "/uav2/faults/seeded": FaultVector}, STREAM_QOS)
    received.update(graph.subscribe({"/uav2/track": Path, SEEDED: Float64}))
    start_process(ros2_run_argv("uav_fault_estimator", "standard_topics_node", ros_args=[
        *namespace, "-p", "track_period_s:=1.0", "-p", "wait_for_subscribers:=1"]),
        "standard_topics_node")  # inputs once this test's subscriptions are matched
    scenario = short_scenario(DURATION_S, faults=[{"name": "right_wing_lift_loss",
                                                   "start_s": 0, "ramp_s": 0,
                                                   "magnitude_pct": 12.5}])
    sim = start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        *namespace, *fast_flight_ros_args(scenario, subscribers=2)]), "sim_node")
    assert sim.wait(timeout_s=60) == 0, sim.output()
    expected = round(DURATION_S * 20) + 1
    graph.spin(10.0, until=lambda: len(received["/uav2/odom"]) >= expected
               and len(received["/tf"]) >= expected)

    states = flown(received, "/uav2/state")
    odometry, imu, fixes = (flown(received, f"/uav2/{topic}") for topic in ("odom", "imu", "fix"))
    transforms = {stamp_seconds(t.header.stamp): t for m in received["/tf"] for t in m.transforms}
    assert len(states) == expected
    assert set(odometry) == set(imu) == set(fixes) == set(transforms) == set(states)
    odom = odometry[max(states)]
    assert (odom.header.frame_id, odom.child_frame_id) == ("map", "uav2/base_link")
    assert imu[max(states)].header.frame_id == fixes[max(states)].header.frame_id \
        == "uav2/base_link"
    transform = transforms[max(states)]
    assert (transform.header.frame_id, transform.child_frame_id) == ("map", "uav2/base_link")
    assert transform.transform.translation.y == odom.pose.pose.position.y
    for time_s, state in states.items():
        values = state_array(state)
        assert (fixes[time_s].latitude, fixes[time_s].longitude) == pytest.approx(
            (math.degrees(state.latitude_rad), math.degrees(state.longitude_rad)), abs=1e-12)
        # the twist (base_link) turned by the pose's orientation is the state's NED ground
        # velocity in ENU: frames and signs agree
        pose, twist = odometry[time_s].pose.pose, odometry[time_s].twist.twist
        q = pose.orientation
        velocity_enu = Rotation.from_quat([q.x, q.y, q.z, q.w]).apply(
            [twist.linear.x, twist.linear.y, twist.linear.z])
        north, east, down = values[VELOCITY_NED]
        assert velocity_enu == pytest.approx([east, north, -down], abs=1e-9)
    start = odometry[min(states)].pose.pose.position
    assert (start.x, start.y, start.z) == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    forces = np.array([[m.linear_acceleration.x, m.linear_acceleration.y,
                        m.linear_acceleration.z] for t, m in sorted(imu.items())[1:]])
    print(f"specific force mean {forces.mean(axis=0)} m/s^2, deviation {forces.std(axis=0)}")
    # flying level at a steady airspeed, the accelerometer reads about g up, on average
    assert forces.mean(axis=0) == pytest.approx([0.0, 0.0, GRAVITY_MPS2], abs=1.0)
    assert imu[min(states)].linear_acceleration_covariance[0] == -1.0  # none differenced yet

    track = received["/uav2/track"][-1]
    assert track.header.frame_id == "map"
    assert [stamp_seconds(p.header.stamp) for p in track.poses] == pytest.approx(
        [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    assert received[SEEDED] and received[SEEDED][-1].data == 12.5
