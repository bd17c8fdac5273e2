"""scripts/screen_logs.py as a user runs it: calibrate from fault-free PX4 logs at three
airspeeds, screen them, a held-out fault-free log at another speed and the aileron-fault
flight; a calibration of another airframe and a file that is not a log are refused with one
line and status 2. The logs are simulated flights written as ULog (tests/helpers)."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from helpers import simulated_logs
from helpers.repo import SCRIPTS
from uav_aircraft.vehicles import load_vehicle
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import Scenario, load_scenario

SCRIPT = SCRIPTS / "screen_logs.py"
CALIBRATION_SPEEDS_MPS = (21.0, 25.0, 29.0)
HELD_OUT_SPEED_MPS = 27.0
FAULT_FREE_DURATION_S = 150.0  # 600 tested samples after the 30 s settling
FIRST_SEED = 501
OTHER_AIRFRAME = load_vehicle("aerosonde").airframe_files["aerosonde_sim"]
FAULT = load_scenario(scenarios_dir() / "aileron_loss.yaml")


def at_airspeed(scenario: Scenario, airspeed_mps: float, seed: int) -> Scenario:
    """scenario flown at airspeed_mps [m/s] (the autopilot holds the initial airspeed), with
    seed's turbulence and noise, for FAULT_FREE_DURATION_S."""
    return dataclasses.replace(
        scenario, seed=seed, duration_s=FAULT_FREE_DURATION_S,
        initial=dataclasses.replace(scenario.initial, airspeed_mps=airspeed_mps))


def write_log(path: Path, scenario: Scenario, seed: int) -> Path:
    simulated_logs.write_ulog(path, simulated_logs.simulate_truth(scenario, seed))
    return path


@pytest.fixture(scope="session")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """fault_free/ff_21.ulg, ff_25.ulg, ff_29.ulg, held_out/ff_27.ulg and
    aileron_loss.ulg (300 s, the fault at 150 s), about 8 s."""
    folder = tmp_path_factory.mktemp("screen_logs")
    fault_free = load_scenario(scenarios_dir() / "fault_free.yaml")
    (folder / "fault_free").mkdir()
    (folder / "held_out").mkdir()
    for k, speed in enumerate(CALIBRATION_SPEEDS_MPS):
        write_log(folder / "fault_free" / f"ff_{speed:.0f}.ulg",
                  at_airspeed(fault_free, speed, FIRST_SEED + k), FIRST_SEED + k)
    write_log(folder / "held_out" / f"ff_{HELD_OUT_SPEED_MPS:.0f}.ulg",
              at_airspeed(fault_free, HELD_OUT_SPEED_MPS, FIRST_SEED + 10), FIRST_SEED + 10)
    write_log(folder / "aileron_loss.ulg", FAULT, FAULT.seed)
    return folder


def screen_logs(*arguments: object) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, arguments)],
                          capture_output=True, text=True, timeout=60)


def assert_refused(result: subprocess.CompletedProcess, *words: str) -> None:
    """Status 2 and one line on stderr holding every word."""
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for word in words:
        assert word in lines[0]


@pytest.fixture(scope="session")
def calibration(logs: Path) -> Path:
    path = logs / "calibration.yaml"
    result = screen_logs("calibrate", logs / "fault_free", "--airframe",
                         simulated_logs.FIXTURE_AIRFRAME, "--out", path)
    assert result.returncode == 0, result.stderr
    print(result.stdout)
    return path


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_calibrate_names_the_airframe_and_logs_and_is_scheduled(calibration: Path) -> None:
    text = calibration.read_text()
    data = yaml.safe_load(text)
    assert data["airframe"] == "aerosonde_test_logs"  # fixture_airframe.yaml's name
    assert data["reference_airspeed_mps"] == pytest.approx(25.0, abs=1.0)
    assert all(channel["parameter_slope_per_mps"] is not None
               for channel in data["channels"].values())
    header = [line for line in text.splitlines() if line.startswith("#")]
    for speed in CALIBRATION_SPEEDS_MPS:
        assert any(f"ff_{speed:.0f}.ulg" in line for line in header)


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_screen_writes_tables_figures_summaries(logs: Path, calibration: Path) -> None:
    out = logs / "screened"
    result = screen_logs("screen", logs / "aileron_loss.ulg", logs / "fault_free",
                         logs / "held_out", "--calibration", calibration, "--airframe",
                         simulated_logs.FIXTURE_AIRFRAME, "--out", out)
    assert result.returncode == 0, result.stderr
    print(result.stdout)
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["airframe"], summary["airspeed_schedule"],
            summary["false_alarm_probability"]) == ("aerosonde_test_logs", True, 0.01)
    names = [log["log"] for log in summary["logs"]]
    assert names == ["aileron_loss", "ff_21", "ff_25", "ff_29", "ff_27"]
    for log in summary["logs"]:
        name = log["log"]
        assert json.loads((out / f"{name}.json").read_text()) == log
        assert (out / f"{name}.png").stat().st_size > 0
        assert (out / f"{name}.alarms.csv").read_text().splitlines()[0] == (
            "start_s,end_s,channel,test,samples,start_stamp_s,end_stamp_s")
        assert set(log) >= {"samples", "tested_samples", "alarm_samples", "alarm_rate",
                            "first_combined_alarm_s", "intervals", "warnings"}
        counts = {test: log["alarm_samples"][test]["any"]
                  for test in ("glrt", "parameter", "combined")}
        print(f"{name}: {log['tested_samples']} tested, alarm samples {counts}, "
              f"first combined alarm {log['first_combined_alarm_s']} s")
    fault = summary["logs"][0]
    fault_start_s = FAULT.faults[0].start_s
    assert fault["first_combined_alarm_s"] is not None
    assert fault["first_combined_alarm_s"] > fault_start_s
    print(f"aileron_loss: first combined alarm "
          f"{fault['first_combined_alarm_s'] - fault_start_s:.1f} s after the fault")
    assert "aileron_loss: " in result.stdout and "start_s" in result.stdout

    # The same logs against a truth table (onsets in the log's clock: its start stamp on)
    truth = logs / "truth.csv"
    truth.write_text("log,failure,onset_stamp_s\n"
                     f"aileron_loss,aileron,{fault['start_stamp_s'] + fault_start_s!r}\n"
                     + "".join(f"{name},,\n" for name in names[1:]))
    judged = screen_logs("screen", logs / "aileron_loss.ulg", logs / "fault_free",
                         logs / "held_out", "--calibration", calibration, "--airframe",
                         simulated_logs.FIXTURE_AIRFRAME, "--out", logs / "judged",
                         "--truth", truth)
    assert judged.returncode == 0, judged.stderr
    evaluated = json.loads((logs / "judged" / "summary.json").read_text())
    outcomes = {log["log"]: log["outcome"] for log in evaluated["logs"]}
    assert outcomes["aileron_loss"]["outcome"] == "tp"
    assert outcomes["aileron_loss"]["delay_s"] == pytest.approx(
        fault["first_combined_alarm_s"] - fault_start_s, abs=1e-6)
    for log in summary["logs"][1:]:  # without failure: fp exactly when an alarm was raised
        assert outcomes[log["log"]]["outcome"] == (
            "tn" if log["first_combined_alarm_s"] is None else "fp")
    tp = evaluated["evaluation"]["tp"]
    assert (tp, evaluated["evaluation"]["recall"]) == (1, 1.0)
    assert "precision" in judged.stdout.splitlines()[-2]


@pytest.mark.slow  # the logs and their calibration: about 25 s when no other test made them
@pytest.mark.timeout(60)
def test_a_calibration_of_another_airframe_is_refused(logs: Path, calibration: Path) -> None:
    result = screen_logs("screen", logs / "aileron_loss.ulg", "--calibration", calibration,
                         "--airframe", OTHER_AIRFRAME, "--out", logs / "refused")
    assert_refused(result, "aerosonde_test_logs", "aerosonde_sim")
    assert not (logs / "refused").exists()


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_a_file_that_is_not_a_log_is_refused(logs: Path, calibration: Path) -> None:
    notes = logs / "notes.txt"
    notes.write_text("a flight\n")
    result = screen_logs("screen", notes, "--calibration", calibration, "--airframe",
                         simulated_logs.FIXTURE_AIRFRAME, "--out", logs / "refused")
    assert_refused(result, str(notes), "not a flight log")
    result = screen_logs("calibrate", notes, "--airframe", simulated_logs.FIXTURE_AIRFRAME,
                         "--out", logs / "refused.yaml")
    assert_refused(result, str(notes), "not a flight log")


@pytest.mark.timeout(60)
def test_the_alfa_benchmark_refuses_a_folder_without_alfa_flights(logs: Path) -> None:
    result = subprocess.run([sys.executable, str(SCRIPT.parent / "alfa_benchmark.py"),
                             logs / "fault_free"], capture_output=True, text=True, timeout=60)
    assert_refused(result, "no ALFA flight folder")
