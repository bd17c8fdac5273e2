"""The autopilot's readings sampled onto the chain's grid of its boot time: held values,
missing streams, reboots, packets out of order, wrapped times and silences."""

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
    UINT32_US_S,
    VELOCITY,
    Reading,
)
from uav_mavlink.sample_assembly import MAX_FILL_S, SampleAssembly

PERIOD_S = 0.05
AGES_S = {ATTITUDE: 0.2, POSITION: 0.5, VELOCITY: 0.2, AIRSPEED: 1.0, OUTPUTS: 0.2}
FUEL_KG = 1.5
ROLL, PITCH, NORTH = (STATE_CHANNELS.index(name)
                      for name in ("roll", "pitch", "velocity_north"))


def attitude(time_s: float, roll: float = 0.0, pitch: float = 0.0) -> Reading:
    return Reading(ATTITUDE, time_s, {"roll": roll, "pitch": pitch, "yaw": 0.0,
                                      "roll_rate": 0.0, "pitch_rate": 0.0, "yaw_rate": 0.0})


def position(time_s: float, north_mps: float) -> Reading:
    return Reading(POSITION, time_s, {"latitude": 1.0, "longitude": 0.1, "altitude": 100.0,
                                      "velocity_north": north_mps, "velocity_east": 0.0,
                                      "velocity_down": 0.0})


def feed(assembly: SampleAssembly, readings) -> list:
    return [sample for reading in readings for sample in assembly.add(reading).samples]


@pytest.mark.timeout(10)
def test_50_hz_attitude_gives_every_grid_point_with_the_value_held_there():
    assembly = SampleAssembly(PERIOD_S, {ATTITUDE: 0.2}, FUEL_KG)
    times_s = [10.0 + 0.02 * k for k in range(51)]  # 10.00 .. 11.00 s at 50 Hz
    samples = feed(assembly, [attitude(t, roll=t) for t in times_s])
    # every grid point from the first reading to before the last one
    assert [s.boot_time_s for s in samples] == pytest.approx(
        [10.0 + PERIOD_S * k for k in range(20)], abs=1e-9)
    for sample in samples:  # the latest reading at or before the grid point
        held = max(t for t in times_s if t <= sample.boot_time_s + 1e-9)
        assert sample.state[ROLL] == held
        assert sample.missing == ()
        assert sample.state[STATE_CHANNELS.index("fuel_mass")] == FUEL_KG


@pytest.mark.timeout(10)
def test_a_stream_older_than_its_age_is_missing_and_nan():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    readings = [position(0.0, 20.0), Reading(AIRSPEED, None, {"airspeed": 22.0})]
    readings += [attitude(0.02 * k) for k in range(1, 60)]  # position never again
    samples = feed(assembly, readings)
    fresh = [s for s in samples if s.boot_time_s <= 0.5 + 1e-9]
    stale = [s for s in samples if s.boot_time_s > 0.5 + 1e-9]
    assert fresh and stale
    assert all(s.state[NORTH] == 20.0 and POSITION not in s.missing for s in fresh)
    assert all(math.isnan(s.state[NORTH]) and POSITION in s.missing for s in stale)
    # the airspeed (untimed) was stamped with the latest boot time, 0 s: held for 1 s
    assert all(s.airspeed_mps == 22.0 for s in samples if s.boot_time_s <= 1.0)
    assert all(OUTPUTS in s.missing and np.isnan(s.outputs_us).all() for s in samples)


@pytest.mark.timeout(10)
def test_the_velocity_stream_is_preferred_to_the_positions_while_fresh():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    readings = [position(0.0, 20.0), Reading(VELOCITY, 0.01, {
        "velocity_north": 21.0, "velocity_east": 0.0, "velocity_down": 0.0})]
    readings += [attitude(0.02 * k) for k in range(1, 20)]
    samples = feed(assembly, readings)
    # from its reading at 0.01 s for its 0.2 s; before and after it, the position's
    assert [s.state[NORTH] for s in samples] == [
        21.0 if 0.01 <= s.boot_time_s <= 0.21 else 20.0 for s in samples]


@pytest.mark.timeout(10)
def test_a_reboot_forgets_what_was_held_and_starts_the_grid_again():
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    feed(assembly, [position(99.0, 20.0)] + [attitude(99.0 + 0.02 * k) for k in range(50)])
    result = assembly.add(attitude(2.0))  # boot time back from 99.98 s to 2 s
    assert result.rebooted and result.samples == []
    samples = feed(assembly, [attitude(2.0 + 0.02 * k) for k in range(1, 11)])
    assert samples[0].boot_time_s == pytest.approx(2.0)
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
    """SERVO_OUTPUT_RAW's uint32 microseconds wrap at 71.6 min: an output read 2 ms after a
    wrap is 2 ms after the attitude, not 71.6 min before it."""
    assembly = SampleAssembly(PERIOD_S, AGES_S, FUEL_KG)
    boot_s = UINT32_US_S + 10.0
    outputs = {f"output_{n}": 1500.0 + n for n in range(1, 17)}
    feed(assembly, [attitude(boot_s)])
    assembly.add(Reading(OUTPUTS, None, outputs, wrapped_boot_time_s=10.002))
    samples = feed(assembly, [attitude(boot_s + 0.02 * k) for k in range(1, 10)])
    assert samples and all(OUTPUTS not in s.missing for s in samples)
    np.testing.assert_array_equal(samples[0].outputs_us, [1500.0 + n for n in range(1, 17)])


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
