"""Each message the chain reads, packed and parsed by pymavlink as the link carries it
(float32 fields, integer units), read into the project's channels and units."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_mavlink.autopilot_messages import (
    AIRSPEED,
    ATTITUDE,
    OUTPUTS,
    POSITION,
    RATES,
    RATES_2,
    SETPOINTS,
    VELOCITY,
    WIND,
    read_message,
)

FLOAT32 = 1e-6  # relative: a float field's rounding on the link


def on_the_link(message):
    """The message as a receiver parses it from the bytes a sender packs."""
    sender, receiver = mavlink.MAVLink(None, srcSystem=1, srcComponent=1), mavlink.MAVLink(None)
    return receiver.decode(bytearray(message.pack(sender)))


@pytest.mark.timeout(10)
def test_attitude_is_the_euler_angles_and_body_rates():
    reading = read_message(on_the_link(mavlink.MAVLink_attitude_message(
        123_456, 0.1, -0.05, 3.0, 0.2, -0.3, 0.05)))
    assert reading.stream == ATTITUDE and reading.boot_time_s == 123.456
    expected = {"roll": 0.1, "pitch": -0.05, "yaw": 3.0, "roll_rate": 0.2, "pitch_rate": -0.3,
                "yaw_rate": 0.05}
    assert reading.values == pytest.approx(expected, rel=FLOAT32)


@pytest.mark.timeout(10)
def test_global_position_is_radians_metres_and_metres_per_second_down_positive():
    reading = read_message(on_the_link(mavlink.MAVLink_global_position_int_message(
        5_000, 555_000_000, 93_000_000, 1_234_567, 234_567, 1_950, -340, 120, 18_000)))
    assert reading.stream == POSITION and reading.boot_time_s == 5.0
    assert reading.values == pytest.approx({
        "latitude": math.radians(55.5), "longitude": math.radians(9.3), "altitude": 1234.567,
        "velocity_north": 19.5, "velocity_east": -3.4, "velocity_down": 1.2}, rel=1e-12)


@pytest.mark.timeout(10)
def test_local_position_gives_the_velocities_only():
    reading = read_message(on_the_link(mavlink.MAVLink_local_position_ned_message(
        7_000, 10.0, 20.0, -100.0, 18.0, -2.5, 0.4)))
    assert reading.stream == VELOCITY and reading.boot_time_s == 7.0
    assert reading.values == pytest.approx(
        {"velocity_north": 18.0, "velocity_east": -2.5, "velocity_down": 0.4}, rel=FLOAT32)


@pytest.mark.timeout(10)
def test_vfr_hud_gives_the_airspeed_without_a_time():
    reading = read_message(on_the_link(mavlink.MAVLink_vfr_hud_message(
        23.5, 25.0, 90, 55, 120.0, 0.3)))
    assert (reading.stream, reading.boot_time_s) == (AIRSPEED, None)
    assert reading.values == pytest.approx({"airspeed": 23.5}, rel=FLOAT32)


@pytest.mark.timeout(10)
def test_servo_outputs_are_pwm_by_output_and_unused_ones_nan():
    pwm = [1500, 1620, 1100, 1450, 0, 1900, 1500, 1000]
    extension = [0] * 8
    message = mavlink.MAVLink_servo_output_raw_message(4_000_000_123, 0, *pwm, *extension)
    reading = read_message(on_the_link(message))
    assert reading.stream == OUTPUTS and reading.boot_time_s is None
    # the uint32 of microseconds since boot wraps: 4 000 000 123 us is its own value here
    assert reading.wrapped_boot_time_s == pytest.approx(4000.000123, abs=1e-9)
    outputs = [reading.values[f"output_{n}"] for n in range(1, 17)]
    np.testing.assert_array_equal(outputs, [*(p or math.nan for p in pwm), *[math.nan] * 8])
    aux = mavlink.MAVLink_servo_output_raw_message(0, 1, *pwm, *extension)
    assert read_message(on_the_link(aux)) is None  # port 1: outputs 17 and up


@pytest.mark.timeout(10)
def test_nav_controller_output_gives_the_commanded_roll_and_pitch_in_radians():
    reading = read_message(on_the_link(mavlink.MAVLink_nav_controller_output_message(
        -25.0, 4.5, 90, 95, 300, 1.5, 120.0, 2.0)))
    assert (reading.stream, reading.boot_time_s) == (SETPOINTS, None)
    assert reading.values == pytest.approx(
        {"roll_rad": math.radians(-25.0), "pitch_rad": math.radians(4.5)}, rel=FLOAT32)


@pytest.mark.timeout(10)
@pytest.mark.parametrize("wind_ned_mps", [(3.0, -4.0, 0.5), (-6.0, 0.0, -0.2), (0.0, 2.0, 0.0)])
def test_ardupilots_wind_comes_back_as_the_ned_vector_it_sent(wind_ned_mps):
    """ArduPilot sends its NED wind w as direction atan2(-w_E, -w_N) [deg], speed |w| and
    speed_z w_D (GCS_Common send_wind)."""
    north, east, down = wind_ned_mps
    sent = mavlink.MAVLink_wind_message(math.degrees(math.atan2(-east, -north)),
                                        math.sqrt(north**2 + east**2 + down**2), down)
    reading = read_message(on_the_link(sent))
    assert reading.stream == WIND
    assert [reading.values[axis] for axis in ("north", "east", "down")] == pytest.approx(
        wind_ned_mps, abs=1e-5)


@pytest.mark.timeout(10)
def test_px4s_wind_cov_is_already_ned():
    sent = mavlink.MAVLink_wind_cov_message(9_000_000, 2.0, -1.0, 0.1, 0.5, 0.3, 120.0, 0.4, 0.2)
    reading = read_message(on_the_link(sent))
    assert reading.stream == WIND
    assert reading.values == pytest.approx({"north": 2.0, "east": -1.0, "down": 0.1},
                                           rel=FLOAT32)


@pytest.mark.timeout(10)
def test_a_message_the_chain_does_not_read_is_none():
    heartbeat = mavlink.MAVLink_heartbeat_message(1, 3, 0, 10, 4, 3)
    assert read_message(on_the_link(heartbeat)) is None


@pytest.mark.timeout(10)
def test_the_imus_give_body_rates_in_radians_per_second():
    """ArduPilot's RAW_IMU (IMU1) and SCALED_IMU2 in whole mrad/s, PX4's HIGHRES_IMU in rad/s;
    a time_usec as large as UNIX time is no boot time; another IMU's RAW_IMU is not read."""
    raw = read_message(on_the_link(mavlink.MAVLink_raw_imu_message(
        12_345_678, 10, -20, -1000, 200, -300, 50, 0, 0, 0)))
    assert raw.stream == RATES and raw.boot_time_s == pytest.approx(12.345678)
    assert raw.values == pytest.approx({"roll_rate": 0.2, "pitch_rate": -0.3,
                                        "yaw_rate": 0.05})
    second = read_message(on_the_link(mavlink.MAVLink_scaled_imu2_message(
        7_000, 0, 0, -1000, -100, 0, 25, 0, 0, 0)))
    assert second.stream == RATES_2 and second.boot_time_s == 7.0
    assert second.values == pytest.approx({"roll_rate": -0.1, "pitch_rate": 0.0,
                                           "yaw_rate": 0.025})
    highres = read_message(on_the_link(mavlink.MAVLink_highres_imu_message(
        1_700_000_000_000_000, 0.0, 0.0, -9.8, 0.1, -0.2, 0.3, 0.0, 0.0, 0.0, 1013.0, 0.0,
        0.0, 20.0, 0)))
    assert highres.stream == RATES and highres.boot_time_s is None  # UNIX time
    assert highres.values == pytest.approx({"roll_rate": 0.1, "pitch_rate": -0.2,
                                            "yaw_rate": 0.3}, rel=FLOAT32)
    assert read_message(on_the_link(mavlink.MAVLink_raw_imu_message(
        1_000, 0, 0, 0, 0, 0, 0, 0, 0, 0, id=1))) is None
