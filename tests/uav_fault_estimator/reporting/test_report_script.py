"""scripts/report.py and recording.read_topics on recordings that are not whole: one line
naming the recording and exit status 2, never a traceback."""

from __future__ import annotations

import json
import os
import random
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers.repo import REPO_ROOT, SCRIPTS
from uav_aircraft.flown_aircraft import FlownAircraft, SensorBias
from uav_fault_estimator.recording.project_bag import (
    Recording,
    RecordingError,
    project_typestore,
    read_topics,
)
from uav_fault_estimator.reporting import report
from uav_fault_estimator.reporting.metrics import EstimateSeries, SeededSeries

REPORT = SCRIPTS / "report.py"
ESTIMATES = 200
ESTIMATE_TYPE = "uav_fault_msgs/msg/FaultEstimate"


def write_bag(path: Path) -> Path:
    """A rosbag2 folder as recorder_node writes it: ESTIMATES estimates on /faults/estimate
    (and nothing else the report needs)."""
    typestore = project_typestore()
    types = typestore.types
    recording = Recording(path, typestore)
    recording.add_topic("/faults/estimate", ESTIMATE_TYPE)
    for index in range(ESTIMATES):
        stamp = types["builtin_interfaces/msg/Time"](
            sec=index // 2, nanosec=index % 2 * 500_000_000)
        message = types[ESTIMATE_TYPE](
            header=types["std_msgs/msg/Header"](stamp=stamp, frame_id=""),
            names=["right_wing_lift_loss", "left_wing_lift_loss"],
            values_pct=np.array([0.1 * index, 0.0]), solver_status=0, updated=True,
            horizon=10, horizon_s=5.0, window_values_pct=np.zeros(20), iterations=3,
            solve_time_ms=0.4, update_cpu_time_ms=0.3)
        recording.write("/faults/estimate", 1_000_000 * index,
                        bytes(typestore.serialize_cdr(message, ESTIMATE_TYPE)))
    recording.close()
    return path


@pytest.fixture(scope="module")
def whole_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_bag(tmp_path_factory.mktemp("recordings") / "whole")


def damaged_copy(whole: Path, folder: Path, damage) -> Path:
    """A copy of the recording whose .mcap file has become damage(bytes)."""
    shutil.copytree(whole, folder)
    (mcap,) = folder.glob("*.mcap")
    mcap.write_bytes(damage(mcap.read_bytes()))
    return folder


DAMAGES = {
    "truncated_half": lambda data: data[: len(data) // 2],
    "truncated_end": lambda data: data[:-40],         # the summary's end cut off
    "truncated_to_header": lambda data: data[:10],
    "empty": lambda data: b"",
    "random_bytes": lambda data: random.Random(15).randbytes(len(data)),
}


def run_report(bag: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(REPORT), str(bag), "--out", str(out)],
                          capture_output=True, text=True, timeout=60)


def assert_one_line_naming(result: subprocess.CompletedProcess, bag: Path, words: str) -> None:
    lines = result.stderr.splitlines()
    assert result.returncode == 2, result
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"report.py: recording {bag}: "), lines
    assert words in lines[0], lines
    assert "Traceback" not in result.stderr and result.stdout == "", result


@pytest.mark.timeout(30)
def test_the_whole_recording_reads_back(whole_bag):
    messages = read_topics(whole_bag, project_typestore(), ("/faults/estimate",))
    assert len(messages["/faults/estimate"]) == ESTIMATES
    assert messages["/faults/estimate"][-1].values_pct[0] == pytest.approx(0.1 * (ESTIMATES - 1))


@pytest.mark.timeout(30)
@pytest.mark.parametrize("damage", sorted(DAMAGES))
def test_a_damaged_recording_is_one_recording_error(whole_bag, tmp_path, damage):
    bag = damaged_copy(whole_bag, tmp_path / damage, DAMAGES[damage])
    with pytest.raises(RecordingError) as error:
        read_topics(bag, project_typestore(), ("/faults/estimate",))
    message = str(error.value)
    assert isinstance(error.value, ValueError)
    assert message.startswith(f"recording {bag}: unreadable, damaged or not rosbag2 (")
    assert "\n" not in message


@pytest.mark.timeout(60)
def test_flipped_bytes_read_or_fail_with_one_recording_error(whole_bag, tmp_path):
    """Bytes changed anywhere in the file or its metadata: the messages come back or a
    RecordingError does, never another exception (seeded: the same cases every run)."""
    typestore = project_typestore()
    failures = 0
    for seed in range(60):
        rng = random.Random(seed)
        bag = tmp_path / f"flipped{seed}"
        shutil.copytree(whole_bag, bag)
        target = bag / "metadata.yaml" if seed % 3 == 0 else next(bag.glob("*.mcap"))
        data = bytearray(target.read_bytes())
        for _ in range(rng.choice((1, 4, 30))):
            data[rng.randrange(len(data))] = rng.randrange(256)
        target.write_bytes(bytes(data))
        try:
            read_topics(bag, typestore, ("/faults/estimate",))
        except RecordingError as error:
            assert str(error).startswith(f"recording {bag}: ") and "\n" not in str(error)
            failures += 1
    assert failures > 10  # the damage was seen, not skipped


@pytest.mark.slow
@pytest.mark.timeout(90)
@pytest.mark.parametrize("damage", ["truncated_half", "empty", "random_bytes"])
def test_report_py_on_a_damaged_recording_says_one_line_and_exits_2(
        whole_bag, tmp_path, damage):
    bag = damaged_copy(whole_bag, tmp_path / "bag", DAMAGES[damage])
    result = run_report(bag, tmp_path / "out")
    assert_one_line_naming(result, bag, "unreadable, damaged or not rosbag2")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_report_py_on_folders_that_are_no_recording(whole_bag, tmp_path):
    empty = tmp_path / "empty_folder"
    empty.mkdir()
    a_file = tmp_path / "bag.mcap"
    a_file.write_bytes(os.urandom(64))
    no_mcap = tmp_path / "no_mcap"
    shutil.copytree(whole_bag, no_mcap)
    for mcap in no_mcap.glob("*.mcap"):
        mcap.unlink()
    garbage_metadata = tmp_path / "garbage_metadata"
    shutil.copytree(whole_bag, garbage_metadata)
    (garbage_metadata / "metadata.yaml").write_bytes(random.Random(3).randbytes(300))
    cases = [(empty, "no metadata.yaml"), (tmp_path / "missing", "no such folder"),
             (a_file, "not a folder"), (no_mcap, "files are missing"),
             (garbage_metadata, "unreadable, damaged or not rosbag2")]
    for bag, words in cases:
        assert_one_line_naming(run_report(bag, tmp_path / "out"), bag, words)


@pytest.mark.timeout(60)
def test_report_py_on_a_recording_without_the_flight_names_the_missing_streams(
        whole_bag, tmp_path):
    result = run_report(whole_bag, tmp_path / "out")
    assert_one_line_naming(result, whole_bag, "no messages on /faults/seeded, /state")


@pytest.mark.timeout(30)
def test_the_table_of_a_flight_shorter_than_settling_shows_no_figures():
    """10 s of estimates, settle_s 20 s: no error figures (None in metrics.json), and the
    table says '-' for them rather than failing (demo.sh printed a traceback)."""
    stamps = np.arange(1, 21) * 0.5
    names = ["right_wing_lift_loss"]
    run = report.Run(
        estimates=EstimateSeries(names, stamps, np.full((20, 1), 1.0), np.zeros(20, dtype=int),
                                 np.full(20, 0.4)),
        seeded=SeededSeries(names, np.arange(0, 201) * 0.05, np.full((201, 1), 1.0)),
        duration_s=10.0, wall_s=1.0)
    metrics = report.run_metrics(run, "short", update_period_s=0.5, settle_s=20.0)
    fault = metrics["faults"]["right_wing_lift_loss"]
    assert fault["rmse_pct"] is None and fault["max_abs_error_pct"] is None
    lines = report.table(metrics).splitlines()
    assert lines[2].split() == ["right_wing_lift_loss", "yes", "1.00", "1.00", "-", "-", "-"]
    assert lines[1].index("delay s") + len("delay s") == len(lines[2])  # still aligned


@pytest.mark.timeout(30)
def test_the_table_tells_the_estimators_figures_from_the_detectors():
    """The Carbon-Z demo's metrics (docs/demo_carbon_z_default.json): its "none" is the
    estimator's false alarms, its lateral_force test's alarm 2.4 s after the first fault
    starts the detector's; each delay says what it counts from."""
    metrics = json.loads((REPO_ROOT / "docs" / "demo_carbon_z_default.json").read_text())
    lines = report.table(metrics).splitlines()
    rows = 2 + len(metrics["faults"])
    assert lines[rows:rows + 4] == [
        "  (the estimator, mhe_node, per fault [%]: the seeded value and its estimate at the end,",
        "  the estimate's RMS and largest error after settle; delay s: from the seeded value",
        "  reaching the threshold to the estimate reaching it)",
        "estimator false alarms (an estimate at the threshold while its seeded value was below "
        "it, after settle): none"]
    detector = lines.index("detector (detector_node's own alarms, apart from the estimates): "
                           "designed P_FA 0.01 per sample; 99 tested fault-free samples "
                           "before the first fault starts")
    assert lines[detector + 3] == ("  lateral_force fault-free alarms    0, first alarm after "
                                   "the first fault starts: 2.4 s")
    assert len(lines) == detector + 1 + len(metrics["alarms"]["tests"])


@pytest.mark.timeout(30)
def test_the_table_says_what_flew_and_what_the_models_were():
    """sim_node's flown aircraft (where it differs from the model) and residual_node's
    model on one line of the table."""
    flown = FlownAircraft(mass_scale=1.04, coefficients=(("CDmin", 1.1),),
                          sensor_bias=SensorBias(angle_of_attack_deg=0.5))
    assert flown.differences() == {"mass_scale": 1.04, "coefficients": {"CDmin": 1.1},
                                   "sensor_bias": {"angle_of_attack_deg": 0.5}}
    assert FlownAircraft().differences() == {}
    stamps = np.arange(1, 61) * 0.5
    names = ["right_wing_lift_loss"]
    run = report.Run(
        estimates=EstimateSeries(names, stamps, np.zeros((60, 1)), np.zeros(60, dtype=int),
                                 np.full(60, 0.4)),
        seeded=SeededSeries(names, stamps, np.zeros((60, 1))), duration_s=30.0, wall_s=1.0,
        aircraft={"flown": flown.differences(), "model": "runs/model.yaml"})
    table = report.table(report.run_metrics(run, "flown", update_period_s=0.5))
    assert ("flown aircraft: mass_scale 1.04, CDmin 1.1, angle_of_attack_deg 0.5; models: "
            "runs/model.yaml") in table.splitlines()
