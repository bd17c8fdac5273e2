"""ALFA's flights as they are exported: a flight folder of FOLDER-<topic>.csv files reads as
the same flight as any other CSV export, with its start stamp; its failure_status files are
its ground truth; a screening is counted per flight against it, and a calibration learns
only from the fault-free parts. Written from a simulated flight (the readers' test log), so
the values are known; the real flights are measured by scripts/alfa_benchmark.py."""

from __future__ import annotations

import csv
import dataclasses
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import simulated_logs
from helpers.simulated_logs import ALFA, ROSTOPIC
from uav_aircraft.airframe import load_airframe
from uav_aircraft.frames import GRAVITY_MPS2
from uav_fault_estimator.detection.detector import DetectorSample
from uav_fault_estimator.detection.generators import GridSample, regressions
from uav_fault_estimator.flight_logs.benchmark import (
    LabelledFlight,
    fault_free_part,
    flight_day,
    leave_out_folds,
)
from uav_fault_estimator.flight_logs.evaluation import (
    alfa_summary,
    evaluation_summary,
    flight_outcome,
    kind_lines,
    within_counts,
    within_limit,
)
from uav_fault_estimator.flight_logs.ground_truth import (
    NO_FAILURE,
    FlightTruth,
    alfa_truth,
    read_truth_table,
)
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.resample import detector_samples
from uav_fault_estimator.flight_logs.streams import AIRSPEED, BODY_RATES
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

SEED = 23
FLIGHT = "carbonZ_2018-09-11-17-27-13_2_both_ailerons_failure"
ONSET_NS = 1_700_000_030_000_000_000


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A simulated flight (30 s) as a plain rostopic export and as an ALFA flight folder
    with a failure_status file."""
    scenario = dataclasses.replace(load_scenario(scenarios_dir() / "aileron_loss.yaml"),
                                   duration_s=30.0)
    truth = simulated_logs.simulate_truth(scenario, SEED)
    folder = tmp_path_factory.mktemp("alfa")
    simulated_logs.write_mavros_bag(folder / "flight.bag", truth, SEED)
    simulated_logs.export_csv(folder / "flight.bag", folder / "plain", ROSTOPIC)
    simulated_logs.export_csv(folder / "flight.bag", folder / FLIGHT, ALFA)
    with (folder / FLIGHT / f"{FLIGHT}-failure_status-aileron.csv").open("w") as file:
        file.write(f"%time,field.data\n{ONSET_NS},3\n{ONSET_NS + 250_000_000},3\n")
    return folder / "plain", folder / FLIGHT


@pytest.mark.timeout(60)
def test_an_alfa_folder_reads_as_the_same_flight_with_its_start(exports) -> None:
    plain, alfa = (read_log(path) for path in exports)
    assert set(alfa.streams) == set(plain.streams) and BODY_RATES in alfa.streams
    for name, series in plain.streams.items():
        np.testing.assert_array_equal(alfa.streams[name].values, series.values)
        np.testing.assert_array_equal(alfa.streams[name].times_s, series.times_s)
    first_ns = min(int(row["%time"]) for path in exports[1].glob("*mavros*.csv")
                   for row in csv.DictReader(path.open()))
    assert alfa.start_stamp_s == pytest.approx(first_ns * 1e-9, abs=1e-6)


@pytest.mark.timeout(60)
def test_a_missing_topic_names_the_files_looked_for(exports, tmp_path: Path) -> None:
    folder = tmp_path / FLIGHT
    shutil.copytree(exports[1], folder)
    (folder / f"{FLIGHT}-mavros-imu-data.csv").unlink()
    with pytest.raises(ValueError, match=r"no body rates.*\[FOLDER-\]mavros-imu-data\.csv, "
                                         r"\[FOLDER-\]mavros-imu-data_raw\.csv"):
        detector_samples(read_log(folder), None, 0.2)


@pytest.mark.timeout(60)
def test_an_airspeed_of_zero_throughout_is_none_and_said(exports, tmp_path: Path) -> None:
    folder = tmp_path / FLIGHT
    shutil.copytree(exports[1], folder)
    path = folder / f"{FLIGHT}-mavros-vfr_hud.csv"
    rows = list(csv.DictReader(path.open()))
    with path.open("w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows({**row, "field.airspeed": "0.0"} for row in rows)
    log = read_log(folder)
    assert AIRSPEED not in log.streams and log.airspeed_source == ""
    assert [line for line in log.warnings if "airspeed is 0 throughout" in line]


@pytest.mark.timeout(30)
def test_the_truth_of_alfa_folders_and_of_a_table(exports, tmp_path: Path) -> None:
    assert alfa_truth(exports[1]) == FlightTruth("aileron", ONSET_NS * 1e-9)
    assert alfa_truth(exports[1]).expected_channels == ("roll", "roll_rudder", "roll_tracking")
    assert alfa_truth(exports[0]) == NO_FAILURE
    unlabelled = tmp_path / "carbonZ_2018-07-18-12-10-11_no_ground_truth"
    unlabelled.mkdir()
    assert not alfa_truth(unlabelled).labelled
    table = tmp_path / "truth.csv"
    table.write_text("log,failure,onset_stamp_s\na,engine,12.5\nb,,\n")
    assert read_truth_table(table) == {"a": FlightTruth("engine", 12.5), "b": NO_FAILURE}
    table.write_text("log,failure,onset_stamp_s\na,wing,12.5\n")
    with pytest.raises(ValueError, match="row 2: failure 'wing'"):
        read_truth_table(table)


def samples_alarmed_at(times_s: np.ndarray, alarmed: dict[float, int]) -> list[DetectorSample]:
    """Detector samples at times_s [s] on two channels: a combined alarm on channel c at
    each time of alarmed (time -> c), none elsewhere."""
    samples = []
    for time_s in times_s:
        channel = alarmed.get(round(float(time_s), 1))
        alarm = np.array([channel == 0, channel == 1])
        deviation = np.where(alarm, 9.0, 0.5)
        samples.append(DetectorSample(
            time_s=float(time_s), residual=np.zeros(2), statistic=np.where(alarm, 5.0, 1.0),
            threshold=np.full(2, 2.0), alarm=alarm, parameter_deviation=deviation,
            parameter_deviations=deviation, parameter_threshold=3.0,
            parameter_alarm=bool(alarm.any()), fixed_residual=np.zeros(2),
            fast_change=np.ones(2), fast_threshold=np.full(2, 2.0),
            fast_alarm=np.zeros(2, dtype=bool), combined_alarm=bool(alarm.any()), theta={},
            airspeed_mps=math.nan))
    return samples


@pytest.mark.timeout(30)
def test_flights_are_counted_once_each_against_their_truth() -> None:
    times_s, start_s, channels = np.arange(0.0, 60.0, 0.2), 1000.0, ("roll", "propulsion")
    cases = {  # flight: (truth, alarms: time [s from start] -> channel index)
        "detected": (FlightTruth("engine", 1030.0), {33.0: 1, 33.2: 0}),
        "early": (FlightTruth("aileron", 1030.0), {10.0: 0, 31.0: 0}),
        "missed": (FlightTruth("aileron", 1030.0), {}),
        "quiet": (NO_FAILURE, {}),
        "false": (NO_FAILURE, {50.0: 0}),
    }
    outcomes = {name: flight_outcome(name, truth, samples_alarmed_at(times_s, alarms),
                                     channels, start_s)
                for name, (truth, alarms) in cases.items()}
    assert {name: o.outcome for name, o in outcomes.items()} == {
        "detected": "tp", "early": "fp", "missed": "fn", "quiet": "tn", "false": "fp"}
    detected = outcomes["detected"]
    assert detected.delay_s == pytest.approx(3.0) and detected.first_alarm_channel == "propulsion"
    assert detected.right_channel and detected.flown_after_onset_s == pytest.approx(29.8)
    assert outcomes["early"].alarms_before_onset == 1
    summary = evaluation_summary(list(outcomes.values()))
    assert (summary["tp"], summary["fp"], summary["fn"], summary["tn"]) == (1, 2, 1, 1)
    assert summary["precision"] == pytest.approx(1 / 3) and summary["recall"] == 0.5
    assert summary["accuracy"] == pytest.approx(2 / 5) and summary["max_delay_s"] == 3.0


@pytest.mark.timeout(30)
def test_alfa_counts_a_first_alarm_past_5_s_as_a_miss_and_each_kind_apart() -> None:
    times_s, start_s, channels = np.arange(0.0, 60.0, 0.2), 1000.0, ("roll", "propulsion")
    cases = {  # flight: (truth, alarms: time [s from start] -> channel index)
        "engine_soon": (FlightTruth("engine", 1030.0), {32.0: 1}),
        "engine_late": (FlightTruth("engine", 1030.0), {37.0: 1}),
        "at_the_limit": (FlightTruth("aileron", 1030.0), {35.0: 0}),
        "both_parts": (FlightTruth("rudder+aileron", 1030.0), {}),
        "quiet": (NO_FAILURE, {}),
    }
    outcomes = [flight_outcome(name, truth, samples_alarmed_at(times_s, alarms), channels,
                               start_s) for name, (truth, alarms) in cases.items()]
    counted = [within_limit(outcome) for outcome in outcomes]
    assert [o.outcome for o in outcomes] == ["tp", "tp", "tp", "fn", "tn"]
    assert [o.outcome for o in counted] == ["tp", "fn", "tp", "fn", "tn"]
    assert counted[1].delay_s is None and counted[1].right_channel is None
    summary = alfa_summary(outcomes)
    assert (summary["tp"], summary["tp_5s"], summary["fn_5s"]) == (3, 2, 2)
    assert summary["recall_5s"] == 0.5 and summary["mean_delay_5s"] == pytest.approx(3.5)
    assert within_counts(summary, summary["detection_limit_s"])["tp"] == 2
    kinds = summary["by_kind"]
    assert list(kinds) == ["engine", "aileron", "aileron+rudder", "none"]
    engine = kinds["engine"]
    assert (engine["flights"], engine["tp_5s"], engine["fn_5s"]) == (2, 1, 1)
    assert engine["mean_delay_5s"] == pytest.approx(2.0)
    assert engine["max_delay_s"] == pytest.approx(7.0)
    lines = kind_lines(summary)
    assert len(lines) == 5 and lines[1].split() == ["engine", "2", "2", "4.5", "7.0", "1",
                                                    "2.0", "2.0", "0"]


@pytest.mark.timeout(10)
def test_leaving_a_day_out_calibrates_on_the_other_days_only() -> None:
    day_s = 86400.0
    starts_s = [1531900000.0, 1531900000.0 + 3600.0, 1531900000.0 + 12 * day_s,
                1531900000.0 + 12 * day_s + 60.0, 1531900000.0 + 55 * day_s]
    days = [flight_day(start_s) for start_s in starts_s]
    assert days[0] == "2018-07-18" and days[0] == days[1] and days[2] == days[3] != days[0]
    assert leave_out_folds(days) == [([0, 1], [2, 3, 4]), ([2, 3], [0, 1, 4]),
                                     ([4], [0, 1, 2, 3])]


@pytest.mark.timeout(60)
def test_a_calibration_learns_up_to_the_onset_less_the_margin(exports) -> None:
    airframe = load_airframe(Path(__file__).parent / "fixture_airframe.yaml")
    inputs = detector_samples(read_log(exports[1]), airframe, 0.2)
    onset_s = inputs.start_stamp_s + 20.0
    part = fault_free_part(LabelledFlight("f", inputs, FlightTruth("aileron", onset_s)), 5.0)
    assert part.times_s[-1] < 15.0 <= part.times_s[-1] + 0.2 + 1e-9
    whole = fault_free_part(LabelledFlight("f", inputs, NO_FAILURE))
    assert len(whole.times_s) == len(inputs.times_s)


@pytest.mark.timeout(30)
def test_the_tracking_and_propulsion_generators_regress_as_documented() -> None:
    """Setpoints: roll 0.3, pitch 0.15 [rad], velocity down 0.5 [m/s]."""
    state, controls = np.zeros(14), np.zeros(7)
    state[[3, 4, 9, 10]] = [0.1, 0.05, 0.2, -0.1]  # roll, pitch [rad]; p, q [rad/s]
    state[[6, 7, 8]] = [20.0, 0.0, -1.0]  # ground velocity north, east, down [m/s]
    controls[4] = 0.6  # throttle
    now = GridSample(1.0, state, controls, np.array([0.3, 0.15, 0.5]))
    found = regressions(("roll_tracking", "pitch_tracking", "climb_tracking", "propulsion"),
                        now, None)
    np.testing.assert_allclose(found["roll_tracking"][0], [0.2, 1.0])
    assert found["roll_tracking"][1] == 0.2
    np.testing.assert_allclose(found["pitch_tracking"][0], [0.1, 1.0])
    np.testing.assert_allclose(found["climb_tracking"][0], [-0.5, 1.0])  # climb up [m/s]
    assert found["climb_tracking"][1] == 1.0
    np.testing.assert_allclose(found["propulsion"][0],
                               [1.0 / math.hypot(20.0, 1.0), 1.0 / math.cos(0.1) ** 2 - 1.0, 1.0])
    assert found["propulsion"][1] == 0.6
    assert regressions(("yaw",), now, None) is None  # r[k-1] needed
    controls[[2, 3]] = [0.05, -0.02]  # aileron, rudder [rad]
    before = GridSample(0.8, state.copy(), controls, now.setpoints)
    before.state[11] = 0.3  # r[k-1] [rad/s]
    lateral = regressions(("roll_rudder", "yaw_rudder"), now, before)
    np.testing.assert_allclose(lateral["roll_rudder"][0], [0.05, -0.02, 1.0])
    np.testing.assert_allclose(lateral["yaw_rudder"][0], [0.05, 0.3, -0.02, 1.0])
    unknown = GridSample(1.0, state, controls, np.full(3, math.nan))
    assert regressions(("roll_tracking",), unknown, now) is None


@pytest.mark.timeout(30)
def test_the_body_forces_are_zero_in_a_coordinated_turn_and_read_a_sideslip_and_a_drag(
) -> None:
    """Heading north at 20 m/s, wings level, pitch and yaw 0, over 0.2 s."""
    before = GridSample(1.0, np.zeros(14), np.zeros(7), np.full(3, math.nan))
    before.state[6] = 20.0
    assert regressions(("lateral_force",), before, None) is None  # needs the sample before
    skid = GridSample(1.2, before.state.copy(), before.controls, before.setpoints)
    skid.state[7] = 0.4  # east [m/s]: 2 m/s^2 sideways with the wings level
    phi, force_mps2 = regressions(("lateral_force",), skid, before)["lateral_force"]
    np.testing.assert_allclose(phi, [1.0])
    assert force_mps2 == pytest.approx(2.0)
    bank_rad = 0.3
    turn = GridSample(1.2, before.state.copy(), before.controls, before.setpoints)
    turn.state[3] = bank_rad
    turn.state[7] = GRAVITY_MPS2 * math.tan(bank_rad) * 0.2  # the turn's centripetal pull
    assert regressions(("lateral_force",), turn, before)["lateral_force"][1] == pytest.approx(
        0.0, abs=1e-12)
    assert regressions(("longitudinal_force",), turn, before)["longitudinal_force"][1] == (
        pytest.approx(0.0, abs=1e-12))
    drag = GridSample(1.2, before.state.copy(), before.controls, before.setpoints)
    drag.state[6] = 19.8  # north [m/s]: 1 m/s^2 of deceleration, level, no thrust left
    phi, force_mps2 = regressions(("longitudinal_force",), drag, before)["longitudinal_force"]
    np.testing.assert_allclose(phi, [1.0])
    assert force_mps2 == pytest.approx(-1.0)
