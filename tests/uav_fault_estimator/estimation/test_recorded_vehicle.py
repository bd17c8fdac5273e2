"""The vehicle a recording says flew (its simulator's /diagnostics) is read back; the commands
that calibrate from recordings take it, and refuse a --vehicle that disagrees, or recordings
of two vehicles, in one line (status 2) before they write anything."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers.recordings import write_recording
from helpers.repo import SCRIPTS
from uav_common.channels import AIR_DATA_CHANNELS, CONTROL_CHANNELS, STATE_CHANNELS
from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.recording.project_bag import project_typestore, recorded_vehicle

SAMPLES = 40  # 2 s at 20 Hz: what is read here is the recording's vehicle, not its flight


def still_flight() -> SensorFlight:
    """A flight of zeros: enough to be recorded and read back."""
    times_s = np.arange(SAMPLES) * 0.05
    return SensorFlight("still", times_s, np.zeros((SAMPLES, len(STATE_CHANNELS))),
                        np.zeros((SAMPLES, len(CONTROL_CHANNELS))), np.zeros((SAMPLES, 3)),
                        np.zeros((SAMPLES, len(AIR_DATA_CHANNELS))))


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("recordings")
    return {said: write_recording(folder / said, still_flight(), vehicle=vehicle)
            for said, vehicle in (("carbon_z", "carbon_z"), ("aerosonde", "aerosonde"),
                                  ("unsaid", None))}


@pytest.mark.timeout(30)
def test_a_recording_says_which_vehicle_flew(bags):
    typestore = project_typestore()
    assert recorded_vehicle(bags["carbon_z"], typestore) == "carbon_z"
    assert recorded_vehicle(bags["unsaid"], typestore) is None


def run(script: str, *arguments: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPTS / script), *arguments],
                          capture_output=True, text=True, timeout=50, cwd=cwd)


@pytest.mark.timeout(60)
def test_calibrate_model_refuses_a_vehicle_the_recordings_contradict(bags, tmp_path):
    result = run("calibrate_model.py", str(bags["carbon_z"]), "--vehicle", "aerosonde",
                 "--out", "m.yaml", cwd=tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr == (f"calibrate_model.py: --vehicle aerosonde, but carbon_z flew "
                             f"{bags['carbon_z']}: leave out --vehicle or give carbon_z\n")
    mixed = run("calibrate_model.py", str(bags["carbon_z"]), str(bags["aerosonde"]),
                "--out", "m.yaml", cwd=tmp_path)
    assert mixed.returncode == 2 and len(mixed.stderr.splitlines()) == 1
    assert mixed.stderr.startswith("calibrate_model.py: different vehicles flew these: "
                                   f"aerosonde {bags['aerosonde']}; carbon_z ")
    assert not (tmp_path / "m.yaml").exists()


@pytest.mark.timeout(60)
def test_calibrate_detector_refuses_a_vehicle_the_recordings_contradict(bags, tmp_path):
    out = tmp_path / "cal.yaml"
    result = run("calibrate_detector.py", "--bags", str(bags["carbon_z"]), "--vehicle",
                 "aerosonde", "--out", str(out), cwd=tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr == (f"calibrate_detector.py: --vehicle aerosonde, but carbon_z flew "
                             f"{bags['carbon_z']}: leave out --vehicle or give carbon_z\n")
    assert not out.exists()
