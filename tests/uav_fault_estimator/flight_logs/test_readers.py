"""Each flight-log reader on the project's own test logs of one simulated flight (the
aileron-fault scenario, cut to 60 s): what it reads back equals what the simulator gave at
the written instants, in FRD, with the PWM and the streams' rates as written."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import simulated_logs
from helpers.simulated_logs import DOTTED, ROSTOPIC, LogTruth
from rosbags.highlevel import AnyReader
from uav_fault_estimator.flight_logs import csv_logs
from uav_fault_estimator.flight_logs.readers import log_paths, read_log
from uav_fault_estimator.flight_logs.streams import (
    AIRSPEED,
    ATTITUDE,
    BODY_RATES,
    GROUND_VELOCITY,
    OUTPUTS,
    SURFACES,
    FlightLog,
)
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

SEED = 17
FLOAT32_ULP = np.finfo(np.float32).eps  # relative precision of the ULog's and VFR_HUD's floats
ULOG_TIME_S = 0.5e-6  # ULog timestamps are whole microseconds
DOTTED_TIME_S = 0.5e-6  # the dotted CSV's log time: float seconds near 1.7e9 s


@dataclasses.dataclass(frozen=True)
class Logs:
    truth: LogTruth
    folder: Path
    bag_start_s: float  # the bag's first log time [s of simulation time]


@pytest.fixture(scope="session")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Logs:
    """One simulated flight written as every format (about 1 s)."""
    scenario = dataclasses.replace(load_scenario(scenarios_dir() / "aileron_loss.yaml"),
                                   duration_s=60.0)
    truth = simulated_logs.simulate_truth(scenario, SEED)
    folder = tmp_path_factory.mktemp("flight_logs")
    simulated_logs.write_ulog(folder / "flight.ulg", truth)
    bag_start_s = simulated_logs.write_mavros_bag(folder / "flight.bag", truth, SEED)
    for layout in (ROSTOPIC, DOTTED):
        simulated_logs.export_csv(folder / "flight.bag", folder / f"csv_{layout}", layout)
    simulated_logs.write_project_bag(folder / "recording", truth)
    return Logs(truth, folder, bag_start_s)


def assert_stream(log: FlightLog, truth: LogTruth, name: str, start_s: float,
                  time_tolerance_s: float, value_tolerance: float) -> None:
    """log's stream equals the truth's at the written instants, counted from start_s [s of
    simulation time]; angles compared modulo 2 pi (yaw's range is the reader's)."""
    series, expected = log.streams[name], truth.streams[name]
    np.testing.assert_allclose(series.times_s, expected.times_s - start_s, rtol=0,
                               atol=time_tolerance_s)
    error = series.values - expected.values
    if name == ATTITUDE:
        error = np.angle(np.exp(1j * error))
    np.testing.assert_allclose(error, 0.0, rtol=0, atol=value_tolerance)
    assert series.median_period_s == pytest.approx(
        float(np.median(np.diff(expected.times_s))), abs=2 * time_tolerance_s)


@pytest.mark.timeout(60)
def test_ulog(logs: Logs) -> None:
    log = read_log(logs.folder / "flight.ulg")
    assert (log.format, log.output_unit, log.airspeed_source) == ("ulog", "pwm_us", "true")
    assert set(log.streams) == {BODY_RATES, ATTITUDE, AIRSPEED, OUTPUTS}
    truth = logs.truth
    # float32 in the file: rates below 1 rad/s, airspeed below 32 m/s, quaternions of norm 1
    assert_stream(log, truth, BODY_RATES, 0.0, ULOG_TIME_S, FLOAT32_ULP)
    assert_stream(log, truth, AIRSPEED, 0.0, ULOG_TIME_S, 32 * FLOAT32_ULP)
    assert_stream(log, truth, ATTITUDE, 0.0, ULOG_TIME_S, 8 * FLOAT32_ULP)
    assert_stream(log, truth, OUTPUTS, 0.0, ULOG_TIME_S, 0.0)


@pytest.mark.timeout(60)
def test_mavros_bag_flu_to_frd(logs: Logs) -> None:
    """The bag holds FLU (q and r negated, ENU attitude and ground velocity); the reader
    gives FRD and NED. Forced to read it as FRD, q and r come out negated."""
    bag = logs.folder / "flight.bag"
    with AnyReader([bag]) as reader:
        connection = next(c for c in reader.connections if c.topic == "/mavros/imu/data")
        _, _, raw = next(reader.messages(connections=[connection]))
        rate = reader.deserialize(raw, connection.msgtype).angular_velocity
    p, q, r = logs.truth.streams[BODY_RATES].values[0]
    assert (rate.x, rate.y, rate.z) == (p, -q, -r)

    log = read_log(bag)
    assert (log.format, log.output_unit, log.airspeed_source) == (
        "ros1_bag", "pwm_us", "indicated")
    assert set(log.streams) == {BODY_RATES, ATTITUDE, AIRSPEED, OUTPUTS, GROUND_VELOCITY}
    truth, start_s = logs.truth, logs.bag_start_s
    assert_stream(log, truth, BODY_RATES, start_s, 1e-9, 0.0)  # float64: exact
    assert_stream(log, truth, ATTITUDE, start_s, 1e-9, 1e-12)
    assert_stream(log, truth, AIRSPEED, start_s, 1e-9, 32 * FLOAT32_ULP)  # VFR_HUD: float32
    assert_stream(log, truth, OUTPUTS, start_s, 1e-9, 0.0)
    assert_stream(log, truth, GROUND_VELOCITY, start_s, 1e-9, 0.0)  # float64, axes swapped

    as_frd = read_log(bag, axes="FRD").streams[BODY_RATES].values
    np.testing.assert_array_equal(as_frd, log.streams[BODY_RATES].values * [1, -1, -1])


@pytest.mark.timeout(60)
@pytest.mark.parametrize("layout", [ROSTOPIC, DOTTED])
def test_csv_export_equals_the_bag(logs: Logs, layout: str) -> None:
    """Both CSV layouts (rostopic's `field.`, one stamp column in ns, channels0...; the
    dotted one, secs/nsecs, time in s, channels as a list) read as the bag does."""
    log = read_log(logs.folder / f"csv_{layout}")
    assert (log.format, log.output_unit, log.airspeed_source) == ("csv", "pwm_us", "indicated")
    assert set(log.streams) == {BODY_RATES, ATTITUDE, AIRSPEED, OUTPUTS, GROUND_VELOCITY}
    time_tolerance_s = 1e-9 if layout == ROSTOPIC else DOTTED_TIME_S
    truth, start_s = logs.truth, logs.bag_start_s
    assert_stream(log, truth, BODY_RATES, start_s, time_tolerance_s, 0.0)
    assert_stream(log, truth, ATTITUDE, start_s, time_tolerance_s, 1e-12)
    assert_stream(log, truth, AIRSPEED, start_s, time_tolerance_s, 32 * FLOAT32_ULP)
    assert_stream(log, truth, OUTPUTS, start_s, time_tolerance_s, 0.0)
    assert_stream(log, truth, GROUND_VELOCITY, start_s, time_tolerance_s, 1e-12)


@pytest.mark.timeout(60)
def test_project_recording(logs: Logs) -> None:
    """A ROS 2 recording of the project's own topics: rates, attitude, true airspeed and
    the surfaces in radians (SURFACES), at simulation time from the first message."""
    log = read_log(logs.folder / "recording")
    assert (log.format, log.airspeed_source) == ("ros2_bag", "true")
    assert set(log.streams) == {BODY_RATES, ATTITUDE, AIRSPEED, SURFACES}
    truth = logs.truth
    start_s = min(stream.times_s[0] for stream in truth.streams.values())
    for name in (BODY_RATES, ATTITUDE, AIRSPEED, SURFACES):
        assert_stream(log, truth, name, start_s, 1e-9, 0.0)


@pytest.mark.timeout(60)
def test_pwm_follows_the_fixture_airframe(logs: Logs) -> None:
    """The written PWM is the airframe truth's: output 5 the mirror of output 1, trims and
    throws as fixture_airframe.yaml says."""
    pwm = logs.truth.streams[OUTPUTS].values
    surfaces = logs.truth.streams[SURFACES].values
    np.testing.assert_array_equal(pwm[:, 4], 3000 - pwm[:, 0])
    aileron = simulated_logs.fixture_airframe()["surfaces"]["aileron"]
    np.testing.assert_allclose(
        pwm[:, 0], aileron["trim_us"] + aileron["throw_us"] * surfaces[:, 0]
        / (aileron["sign"] * aileron["max_deflection_rad"]), atol=0.5)


@pytest.mark.timeout(30)
@pytest.mark.parametrize("name, content", [
    ("random.ulg", bytes(range(256)) * 4),
    ("text.ulg", b"not a log\n"),
    ("random.bag", bytes(range(256)) * 4),
    ("notes.txt", b"a flight\n"),
])
def test_a_file_that_is_not_a_log(tmp_path: Path, name: str, content: bytes) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(ValueError, match=str(path)) as raised:
        read_log(path)
    assert "\n" not in str(raised.value)


@pytest.mark.timeout(30)
def test_log_paths_expand_folders_one_level(tmp_path: Path) -> None:
    """A log given stays; another folder stands for the logs directly in it, in name order
    (not deeper, not other files); a path that is no log stays for read_log to refuse; a
    folder without logs is one line."""
    (tmp_path / "b.ulg").write_bytes(b"")
    (tmp_path / "a.bag").write_bytes(b"")
    (tmp_path / "notes.txt").write_text("a flight\n")
    (tmp_path / "rosbag2").mkdir()
    (tmp_path / "rosbag2" / "metadata.yaml").write_text("")
    (tmp_path / "csv").mkdir()
    (tmp_path / "csv" / "imu.csv").write_text("")
    (tmp_path / "deeper" / "day").mkdir(parents=True)
    (tmp_path / "deeper" / "day" / "c.ulg").write_bytes(b"")
    missing = tmp_path / "missing.ulg"
    assert log_paths([tmp_path, tmp_path / "csv", missing]) == [
        tmp_path / name for name in ("a.bag", "b.ulg", "csv", "rosbag2", "csv")] + [missing]
    assert log_paths([tmp_path / "deeper" / "day"]) == [tmp_path / "deeper" / "day" / "c.ulg"]
    with pytest.raises(ValueError, match="no flight log in this folder") as raised:
        log_paths([tmp_path / "deeper"])
    assert "\n" not in str(raised.value)


def edited_csv_folder(logs: Logs, tmp_path: Path, edit) -> tuple[Path, Path]:
    """A copy of the dotted CSV export with edit(lines) applied to its rates file; the
    folder and that file."""
    folder = tmp_path / "csv"
    shutil.copytree(logs.folder / f"csv_{DOTTED}", folder)
    rates = next(path for path in folder.glob("*.csv") if "imu" in path.name)
    lines = rates.read_text().splitlines()
    rates.write_text("\n".join(edit(lines)) + "\n")
    return folder, rates


def with_time(lines: list[str], row: int, time_text: str) -> list[str]:
    """lines with the log time (the first cell) of data row `row` replaced."""
    cells = lines[row].split(",")
    return [*lines[:row], ",".join([time_text, *cells[1:]]), *lines[row + 1:]]


@pytest.mark.timeout(60)
@pytest.mark.parametrize("time_text, said", [
    ("1e300", "is not a log time"),
    ("nan", "is not a log time"),
    ("-7.5e9", "s after"),  # a negative time: back by 9e9 s
    ("1.0", "s after"),  # back to the epoch's first second: out of order
])
def test_a_csv_time_cell_out_of_place_is_one_line_naming_file_and_row(
        logs: Logs, tmp_path: Path, time_text: str, said: str) -> None:
    """One log time of the rates file replaced (taken unchecked, 1e300 would be replayed at
    -7.52e9 s)."""
    folder, rates = edited_csv_folder(logs, tmp_path, lambda lines: with_time(
        lines, 40, time_text))
    with pytest.raises(ValueError) as raised:
        read_log(folder)
    message = str(raised.value)
    print(message)
    assert message.startswith(f"{rates}: row 40: ") and said in message and "\n" not in message


@pytest.mark.timeout(60)
def test_a_csv_of_binary_data_or_too_large_is_one_line_naming_it(logs: Logs,
                                                                  tmp_path: Path) -> None:
    folder, rates = edited_csv_folder(logs, tmp_path, lambda lines: lines)
    rates.write_bytes(bytes(range(256)) * 64)
    with pytest.raises(ValueError, match=f"^{rates}: not a CSV text file"):
        read_log(folder)
    rates.write_bytes(b"")
    with open(rates, "wb") as file:  # sparse: the size without the disk
        file.truncate(csv_logs.MAX_FILE_BYTES + 1)
    with pytest.raises(ValueError, match=f"^{rates}: 256 MiB, more than the 256 MiB"):
        read_log(folder)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("damage", ["truncated", "bit_flipped"])
def test_a_damaged_ulog_is_read_with_a_warning_naming_it(logs: Logs, tmp_path: Path,
                                                         damage: str) -> None:
    data = bytearray((logs.folder / "flight.ulg").read_bytes())
    if damage == "truncated":
        data = data[: len(data) * 2 // 3 + 7]  # cut inside a message
    else:
        for offset in range(len(data) // 2, len(data) // 2 + 4000, 97):
            data[offset] ^= 0xFF
    path = tmp_path / f"{damage}.ulg"
    path.write_bytes(bytes(data))
    log = read_log(path)
    print(log.warnings)
    assert len(log.warnings) == 1 and str(path) in log.warnings[0]
    assert "damaged ULog" in log.warnings[0]
    assert read_log(logs.folder / "flight.ulg").warnings == ()
