"""standard_frames: the project's NED/FRD state in REP 103's ENU/FLU frames, checked against
attitudes and motions whose answer is known by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from uav_aircraft.frames import GRAVITY_MPS2
from uav_common.channels import STATE_CHANNELS
from uav_fault_estimator.viewing.standard_frames import (
    GeodeticPoint,
    StandardFrames,
    orientation_xyzw,
)

ORIGIN = GeodeticPoint(55.6, 12.5, 250.0)


def state(**values: float) -> np.ndarray:
    """An AircraftState array at ORIGIN, level, heading north, still, with values set."""
    array = np.zeros(len(STATE_CHANNELS))
    array[:3] = math.radians(ORIGIN.latitude_deg), math.radians(ORIGIN.longitude_deg), 250.0
    for name, value in values.items():
        array[STATE_CHANNELS.index(name)] = value
    return array


def rotation(xyzw: np.ndarray) -> np.ndarray:
    return Rotation.from_quat(xyzw).as_matrix()


@pytest.mark.timeout(10)
def test_heading_east_is_the_identity_and_north_a_quarter_turn_about_up():
    assert np.allclose(rotation(orientation_xyzw(0.0, 0.0, math.pi / 2)), np.eye(3), atol=1e-12)
    # heading north: base_link's x (forward) is map's y (north), its y (left) map's -x (west)
    north = rotation(orientation_xyzw(0.0, 0.0, 0.0))
    assert np.allclose(north @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    assert np.allclose(north @ [0, 1, 0], [-1, 0, 0], atol=1e-12)


@pytest.mark.timeout(10)
def test_right_wing_down_rolls_positive_about_forward_and_nose_up_is_negative_about_left():
    # heading east, 30 deg right wing down: base_link's left axis points up by 30 deg
    rolled = rotation(orientation_xyzw(math.radians(30), 0.0, math.pi / 2))
    assert np.allclose(rolled @ [0, 1, 0], [0, math.cos(math.radians(30)),
                                             math.sin(math.radians(30))], atol=1e-12)
    # heading east, 10 deg nose up: forward points up
    pitched = rotation(orientation_xyzw(0.0, math.radians(10), math.pi / 2))
    assert np.allclose(pitched @ [1, 0, 0], [math.cos(math.radians(10)), 0,
                                             math.sin(math.radians(10))], atol=1e-12)
    assert np.isnan(orientation_xyzw(math.nan, 0.0, 0.0)).all()


@pytest.mark.timeout(10)
def test_position_velocity_rates_and_specific_force_in_map_and_base_link():
    frames = StandardFrames(ORIGIN)
    # 1e-5 rad north at 55.6 deg: the meridian's radius of curvature is 6.379e6 m there
    moved = frames.update(0.0, state(latitude=math.radians(55.6) + 1e-5, velocity_north=25.0,
                                     velocity_down=-2.0, roll_rate=0.1, pitch_rate=0.2,
                                     yaw_rate=0.3))
    assert moved.position_enu_m == pytest.approx([0.0, 63.79, 0.0], abs=0.01)
    assert moved.velocity_flu_mps == pytest.approx([25.0, 0.0, 2.0])  # climbing 2 m/s
    assert moved.angular_velocity_flu_radps == pytest.approx([0.1, -0.2, -0.3])
    assert np.isnan(moved.specific_force_flu_mps2).all()  # nothing to difference yet
    # accelerating 1 m/s^2 forward over 0.05 s, level: the accelerometer's (1, 0, +g)
    steady = frames.update(0.05, state(velocity_north=25.05, velocity_down=-2.0))
    assert steady.specific_force_flu_mps2 == pytest.approx([1.0, 0.0, GRAVITY_MPS2])
    frames.reset()
    assert np.isnan(frames.update(0.10, state()).specific_force_flu_mps2).all()


@pytest.mark.timeout(10)
def test_the_map_origin_is_the_first_position_known():
    frames = StandardFrames()
    missing = frames.update(0.0, state(latitude=math.nan))
    assert frames.origin is None and np.isnan(missing.position_enu_m).all()
    frames.update(0.05, state())
    assert frames.origin == ORIGIN
    assert frames.update(0.1, state()).position_enu_m == pytest.approx([0, 0, 0], abs=1e-9)


@pytest.mark.timeout(10)
def test_what_a_state_lacks_is_marked_absent_in_the_standard_messages():
    from std_msgs.msg import Header
    from uav_fault_estimator.nodes.standard_topics_node import fix_message, imu_message

    lost = StandardFrames(ORIGIN).update(0.0, state(latitude=math.nan, roll=math.nan,
                                                    pitch_rate=math.nan))
    fix, imu = fix_message(Header(), lost), imu_message(Header(), lost)
    assert fix.status.status == fix.status.STATUS_NO_FIX
    assert imu.orientation_covariance[0] == imu.angular_velocity_covariance[0] \
        == imu.linear_acceleration_covariance[0] == -1.0
    assert (imu.angular_velocity.x, imu.orientation.w) == (0.0, 1.0)  # defaults, not NaN
