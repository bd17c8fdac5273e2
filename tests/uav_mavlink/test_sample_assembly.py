"""The autopilot's readings sampled onto the chain's grid of its boot time: interpolated
values, the faster body rates, missing streams, reboots, packets out of order, wrapped times,
silences, and how long a grid point waits at ArduPlane's advised rates."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_common.channels import STATE_CHANNELS
from uav_mavlink.autopilot_messages import (
    AIRSPEED,
    ATTITUDE,
    OUTPUTS,
    POSITION,
    RATES,
    SETPOINTS,
    UINT32_US_S,
    VELOCITY,
    WIND,
    Reading,
)
from uav_mavlink.sample_assembly import MAX_FILL_S, SampleAssembly

PERIOD_S = 0.05
AGES_S = {ATTITUDE: 0.2, POSITION: 0.5, VELOCITY: 0.2, AIRSPEED: 1.0, OUTPUTS: 0.2}
FUEL_KG = 1.5
ROLL, PITCH, YAW, NORTH, ROLL_RATE = (
    STATE_CHANNELS.index(name) for name in ("roll", "pitch", "yaw", "velocity_north",
                                            "roll_rate"))


def attitude(time_s: float, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0,
             roll_rate: float = 0.0) -> Reading:
    return Reading(ATTITUDE, time_s, {"roll": roll, "pitch": pitch, "yaw": yaw,
                                      "roll_rate": roll_rate, "pitch_rate": 0.0,
                                      "yaw_rate": 0.0})


def imu(time_s: float, roll_rate: float) -> Reading:
    return Reading(RATES, time_s, {"roll_rate": roll_rate, "pitch_rate": 0.0,
                                   "yaw_rate": 0.0})


def position(time_s: float, north_mps: float) -> Reading:
    return Reading(POSITION, time_s, {"latitude": 1.0, "longitude": 0.1, "altitude": 100.0,
                                      "velocity_north": north_mps, "velocity_east": 0.0,
                                      "velocity_down": 0.0})


def feed(assembly: SampleAssembly, readings) -> list:
    return [sample for reading in readings for sample in assembly.add(reading).samples]


def in_time_order(readings: list[Reading]) -> list[Reading]:
    return sorted(readings, key=lambda reading: reading.boot_time_s)


@pytest.mark.timeout(10)
def test_50_hz_attitude_gives_every_grid_point_interpolated():
    assembly = SampleAssembly(PERIOD_S, {ATTITUDE: 0.2}, FUEL_KG)
    times_s = [10.0 + 0.02 * k for k in range(51)]  # 10.00 .. 11.00 s at 50 Hz
    samples = feed(assembly, [attitude(t, roll=0.1 * (t - 10.0)) for t in times_s])
    # every grid point from the first reading to the last one (a reading at it releases it)
    assert [s.boot_time_s for s in samples] == pytest.approx(
        [10.0 + PERIOD_S * k for k in range(21)], abs=1e-9)
    for sample in samples:  # a ramp, interpolated: exact between the readings
        assert sample.state[ROLL] == pytest.approx(0.1 * (sample.boot_time_s - 10.0),
                                                   abs=1e-12)
        assert sample.missing == ()
        assert sample.state[STATE_CHANNELS.index("fuel_mass")] == FUEL_KG


@pytest.mark.timeout(10)
def test_angles_are_interpolated_the_short_way_round():
    assembly = SampleAssembly(PERIOD_S, {ATTITUDE: 0.2}, FUEL_KG)
    samples = feed(assembly, [attitude(0.0, yaw=math.pi - 0.1),
                              attitude(0.1, yaw=-math.pi + 0.1)])
    assert abs(samples[1].state[YAW]) == pytest.approx(math.pi)  # across +-pi, not through 0


@pytest.mark.timeout(10)
def test_a_stream_that_stops_is_missing_after_its_last_reading_and_waited_for_its_gap():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    first = assembly.add(position(0.0, 20.0)).samples  # on a grid point, the only stream
    assert [s.boot_time_s for s in first] == [0.0] and first[0].state[NORTH] == 20.0
    assert assembly.add(Reading(AIRSPEED, None, {"airspeed": 22.0})).samples == []
    # grid points after 0 s wait while a position within its gap (0.5 s) may still come
    assert feed(assembly, [attitude(0.02 * k) for k in range(1, 26)]) == []  # to 0.5 s
    later = feed(assembly, [attitude(0.5 + 0.02 * k) for k in range(1, 60)])
    assert [s.boot_time_s for s in later] == pytest.approx(
        [PERIOD_S * k for k in range(1, len(later) + 1)], abs=1e-9)
    # nothing is extrapolated after a stream's last reading
    assert all(math.isnan(s.state[NORTH]) and POSITION in s.missing for s in later)
    assert all(math.isnan(s.airspeed_mps) and AIRSPEED in s.missing for s in later)
    assert all(OUTPUTS in s.missing and np.isnan(s.outputs_us).all() for s in first + later)


@pytest.mark.timeout(10)
def test_a_grid_point_waits_for_a_reading_on_it_that_may_still_come_whatever_the_gap():
    """Streams read at the same instants, on the grid points, one after the other: the
    point waits for the later stream's reading on it (a reading on a point gives its value
    there, however far before it the previous one lies) instead of judging it missing when
    the first stream's reading at the point comes."""
    assembly = SampleAssembly(PERIOD_S, {ATTITUDE: 0.2, POSITION: 0.02}, FUEL_KG)
    readings = [reading for k in range(10)
                for reading in (attitude(PERIOD_S * k), position(PERIOD_S * k, 20.0 + k))]
    samples = feed(assembly, readings)
    assert len(samples) == 10
    # the first goes out with the first attitude, before the position is heard
    assert samples[0].missing == (POSITION,)
    assert [s.state[NORTH] for s in samples[1:]] == [20.0 + k for k in range(1, 10)]
    assert all(s.missing == () for s in samples[1:])


@pytest.mark.timeout(10)
def test_the_velocity_stream_is_preferred_to_the_positions_where_it_is_known():
    readings = [position(0.0, 20.0), position(0.4, 20.0)]
    readings += [Reading(VELOCITY, t, {"velocity_north": 21.0, "velocity_east": 0.0,
                                       "velocity_down": 0.0}) for t in (0.01, 0.11, 0.21)]
    readings += [attitude(0.02 * k) for k in range(1, 26)]
    samples = feed(SampleAssembly(PERIOD_S, AGES_S, FUEL_KG), in_time_order(readings))
    # between its first and last reading the velocity stream's; before and after, the
    # position's
    assert len(samples) == 9
    assert [s.state[NORTH] for s in samples] == [
        21.0 if 0.01 <= s.boot_time_s <= 0.21 else 20.0 for s in samples]


@pytest.mark.timeout(10)
def test_the_body_rates_come_from_the_faster_of_attitude_and_the_imu():
    readings = [imu(0.1 * k, roll_rate=1.0) for k in range(21)]  # 10 Hz
    readings += [attitude(0.4 * k, roll_rate=-1.0) for k in range(6)]  # 2.5 Hz
    samples = feed(SampleAssembly(PERIOD_S, {ATTITUDE: 1.0}, FUEL_KG), in_time_order(readings))
    assert len(samples) == 41 and all(s.state[ROLL_RATE] == 1.0 for s in samples[5:])
    # at 25 Hz the attitude is the faster: its rates, and a 1 Hz IMU is not waited for
    readings = [attitude(0.04 * k, roll_rate=-1.0) for k in range(51)]
    readings += [imu(float(k), roll_rate=1.0) for k in range(3)]
    assembly = SampleAssembly(PERIOD_S, {ATTITUDE: 1.0}, FUEL_KG)
    released = []
    for reading in in_time_order(readings):
        released += [(s, reading.boot_time_s) for s in assembly.add(reading).samples]
    assert len(released) == 41
    assert all(s.state[ROLL_RATE] == -1.0 and RATES not in s.missing for s, _ in released)
    assert max(at_s - s.boot_time_s for s, at_s in released) < 0.04 + 1e-9


@pytest.mark.timeout(10)
def test_a_reboot_forgets_what_was_held_and_starts_the_grid_again():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    feed(assembly, [position(99.0, 20.0)] + [attitude(99.0 + 0.02 * k) for k in range(50)])
    result = assembly.add(attitude(2.0))  # boot time back from 99.98 s to 2 s
    # the grid starts again at the reading, which is on a grid point: released at once
    assert result.rebooted and [s.boot_time_s for s in result.samples] == [2.0]
    samples = result.samples + feed(assembly, [attitude(2.0 + 0.02 * k)
                                               for k in range(1, 11)])
    assert all(POSITION in s.missing for s in samples)  # the old position is forgotten


@pytest.mark.timeout(10)
def test_a_reading_out_of_order_is_dropped_and_counted():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    feed(assembly, [attitude(5.0 + 0.02 * k, roll=1.0) for k in range(10)])
    late = assembly.add(attitude(5.1, roll=-1.0))  # behind the latest (5.18 s)
    assert late.dropped and not late.rebooted and assembly.out_of_order == 1
    samples = feed(assembly, [attitude(5.2 + 0.02 * k, roll=1.0) for k in range(5)])
    assert all(s.state[ROLL] == 1.0 for s in samples)


@pytest.mark.timeout(10)
def test_the_outputs_wrapped_time_is_unwrapped_about_the_boot_time():
    """SERVO_OUTPUT_RAW's uint32 microseconds wrap at 71.6 min: outputs read just after a
    wrap are just after the attitude, not 71.6 min before it."""
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    boot_s = UINT32_US_S + 10.0
    outputs = {f"output_{n}": 1500.0 + n for n in range(1, 17)}
    samples = feed(assembly, [attitude(boot_s)])
    for k in range(1, 10):
        assembly.add(Reading(OUTPUTS, None, outputs, wrapped_boot_time_s=10.0 + 0.02 * k - 0.001))
        samples += assembly.add(attitude(boot_s + 0.02 * k)).samples
    after = [s for s in samples if s.boot_time_s >= boot_s + 0.019]  # the first outputs
    assert len(after) >= 2 and all(OUTPUTS not in s.missing for s in after)
    np.testing.assert_array_equal(after[0].outputs_us, [1500.0 + n for n in range(1, 17)])


@pytest.mark.timeout(10)
def test_a_long_silence_gives_one_sample_not_a_gap_filled_with_missing_ones():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    feed(assembly, [attitude(0.02 * k) for k in range(10)])
    after = feed(assembly, [attitude(0.18 + 60.0)])
    assert len(after) == 1 and after[0].boot_time_s == pytest.approx(60.15)
    assert ATTITUDE in after[0].missing
    short = feed(assembly, [attitude(60.18 + MAX_FILL_S / 2)])
    assert len(short) == round(MAX_FILL_S / 2 / PERIOD_S)  # a shorter gap is filled


@pytest.mark.timeout(10)
def test_arduplanes_pitch_trim_is_added_back_and_untimed_readings_wait_for_a_clock():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG, pitch_trim_rad=0.03)
    assert assembly.add(Reading(AIRSPEED, None, {"airspeed": 20.0})).dropped
    samples = feed(assembly, [attitude(0.02 * k, pitch=0.1) for k in range(10)])
    assert all(s.state[PITCH] == pytest.approx(0.13) for s in samples)
    assert all(AIRSPEED in s.missing for s in samples)


@pytest.mark.timeout(10)
def test_at_arduplanes_advised_rates_a_grid_point_goes_out_within_a_tenth_of_a_second():
    """ATTITUDE at 25 Hz; position, outputs and VFR_HUD at 10 Hz; the wind and setpoints at
    2 Hz, held rather than waited for: a grid point waits for the 10 Hz streams only."""
    ages = {**AGES_S, SETPOINTS: 3.0, WIND: 3.0}
    del ages[VELOCITY]
    outputs = {f"output_{n}": 1500.0 for n in range(1, 17)}
    rates_hz = {ATTITUDE: 25, POSITION: 10, OUTPUTS: 10, AIRSPEED: 10, WIND: 2, SETPOINTS: 2}
    phase_s = {ATTITUDE: 0.003, POSITION: 0.011, OUTPUTS: 0.027, AIRSPEED: 0.043,
               WIND: 0.061, SETPOINTS: 0.077}
    readings = {
        ATTITUDE: attitude, POSITION: lambda t: position(t, 20.0),
        OUTPUTS: lambda t: Reading(OUTPUTS, None, outputs, wrapped_boot_time_s=t),
        AIRSPEED: lambda t: Reading(AIRSPEED, None, {"airspeed": 20.0}),
        WIND: lambda t: Reading(WIND, None, {"north": 1.0, "east": 0.0, "down": 0.0}),
        SETPOINTS: lambda t: Reading(SETPOINTS, None, {"roll_rad": 0.0, "pitch_rad": 0.0})}
    events = sorted((100.0 + phase_s[s] + k / hz, s) for s, hz in rates_hz.items()
                    for k in range(20 * hz))
    assembly = SampleAssembly(PERIOD_S, ages, FUEL_KG)
    latencies_s = []
    for time_s, stream in events:
        for sample in assembly.add(readings[stream](time_s)).samples:
            if sample.boot_time_s > 101.0:  # every stream heard twice
                assert sample.missing == ()
                latencies_s.append(time_s - sample.boot_time_s)
    assert len(latencies_s) > 350 and max(latencies_s) < 0.1
