"""flight_logs.screening_run called as a package function, on the shipped example flight:
asked for no output file, calibrate_from_logs returns the calibration and writes nothing
(scripts/screen_logs.py's tests run the commands, which always write); screened with a
calibration whose generators need the autopilot's setpoints, which the log lacks, screen
says so in one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.repo import REPO_ROOT
from uav_aircraft.vehicles import load_vehicle
from uav_fault_estimator.campaigns.campaign import CampaignOptions
from uav_fault_estimator.detection.calibration import DEFAULT_WINDOW
from uav_fault_estimator.detection.calibration_file import shipped_calibration_path
from uav_fault_estimator.detection.generators import SURFACE_GENERATORS
from uav_fault_estimator.flight_logs.loading import BadInputError
from uav_fault_estimator.flight_logs.screening_run import (
    CalibrationRequest,
    ScreeningRequest,
    calibrate_from_logs,
    screen,
)

EXAMPLE = REPO_ROOT / "examples" / "flights"
AIRFRAME = load_vehicle("aerosonde").airframe_files["aerosonde_sim"]


@pytest.mark.timeout(60)
def test_calibrate_from_logs_without_an_output_returns_the_calibration_only(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    calibration = calibrate_from_logs(CalibrationRequest(
        log_paths=(EXAMPLE,), airframe_path=AIRFRAME, out_path=None, schedule="none",
        generators=SURFACE_GENERATORS, truth_table_path=None, forgetting_factor=0.99,
        window_samples=DEFAULT_WINDOW, settle_s=20.0,
        campaign=CampaignOptions(workers=0, progress=False)))
    assert calibration.airframe == "aerosonde_sim"
    assert calibration.channel_names == SURFACE_GENERATORS
    assert (calibration.forgetting_factor, calibration.window, calibration.settle_s) == (
        0.99, DEFAULT_WINDOW, 20.0)
    assert not calibration.scheduled
    printed = capsys.readouterr().out
    assert "airspeed schedule: none" in printed and "calibrated on" not in printed
    assert list(tmp_path.iterdir()) == []


@pytest.mark.timeout(60)
def test_a_log_without_what_the_generators_take_is_one_line(tmp_path: Path) -> None:
    request = ScreeningRequest(
        log_paths=(EXAMPLE,), calibration_path=shipped_calibration_path(),
        airframe_path=AIRFRAME, out_dir=tmp_path / "screened", false_alarm_probability=0.01,
        truth_table_path=None, campaign=CampaignOptions(workers=0, progress=False))
    with pytest.raises(BadInputError, match=r"ran on none of its samples.*setpoints"):
        screen(request)
