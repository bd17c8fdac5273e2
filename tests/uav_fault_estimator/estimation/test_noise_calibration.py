"""The residual noise calibration: the shipped file is what its command makes, a bad file
is one clear message, and a sample's own Q is the configured Q for that sample."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import yaml
from helpers.nested import assert_same_numbers
from helpers.repo import REPO_ROOT
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator
from uav_fault_estimator.estimation.noise_model import load_noise_calibration, shipped_noise_path
from uav_fault_estimator.estimation.residuals import WIND_AIR_DATA, WIND_FILTERED


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_the_shipped_noise_calibration_is_what_the_command_makes(tmp_path):
    out = tmp_path / "residual_noise.yaml"
    subprocess.run([sys.executable, str(REPO_ROOT / "scripts/calibrate_estimator.py"),
                    "--out", str(out)], check=True, timeout=230)
    assert_same_numbers(yaml.safe_load(out.read_text()),
                        yaml.safe_load(shipped_noise_path().read_text()))
    calibration = load_noise_calibration(out)
    air, filtered = (calibration.q_diag(source, 1.0) for source in (WIND_AIR_DATA,
                                                                     WIND_FILTERED))
    print(f"fault-free residual variances, air data {air.round(5)}, filtered wind "
          f"{filtered.round(3)}; one-step correlations, air data "
          f"{calibration.correlations['air_data'].round(2)}")
    assert np.all(filtered > 10 * air)  # what the gusts the filtered wind misses add


def test_a_bad_calibration_file_is_one_message(tmp_path):
    path = tmp_path / "noise.yaml"
    path.write_text("vehicle: aerosonde\nair_data: {variances: [1, 2]}\npitot: {}\n"
                    "filtered_wind: {}\n")
    with pytest.raises(ValueError, match=f"noise calibration {path}: cannot be read"):
        load_noise_calibration(path)


def test_a_samples_own_noise_variances_weight_it():
    rng = np.random.default_rng(2)
    q_other = (0.5, 0.2, 0.1, 0.3, 0.4, 0.6)
    configured = MovingHorizonEstimator(EstimatorConfig(horizon=10))
    other = MovingHorizonEstimator(EstimatorConfig(horizon=10, q_diag=q_other))
    for _ in range(12):
        y, s = rng.normal(size=6), rng.normal(size=(6, 4))
        first = configured.update(y, s, None, np.array(q_other))
        second = other.update(y, s)
        np.testing.assert_allclose(first.fault_pct, second.fault_pct, atol=1e-9)


def test_a_noise_file_of_another_vehicle_is_refused_in_one_line(tmp_path):
    path = tmp_path / "noise.yaml"
    data = yaml.safe_load(shipped_noise_path().read_text())
    path.write_text(yaml.safe_dump({**data, "vehicle": "another_aircraft"}))
    with pytest.raises(ValueError) as refused:
        load_noise_calibration(path, "aerosonde")
    assert str(refused.value) == (f"noise calibration {path}: made for the vehicle "
                                  "'another_aircraft', not 'aerosonde'")
