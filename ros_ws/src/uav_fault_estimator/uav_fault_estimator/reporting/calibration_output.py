"""Writing a calibration file, the calibration scripts' one way to save what they found
(calibrate_estimator.py, calibrate_detector.py, calibrate_model.py, screen_logs.py)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import yaml


def write_calibration(path: os.PathLike | str, header: str, calibration: Mapping[str, Any],
                      flights: str, seconds: float) -> None:
    """Write a calibration file, the calibration scripts' output: header (its comment lines,
    saying what it was made from), then the calibration's file mapping as YAML in its own
    key order; and say on stdout that it was made on `flights` ("12 flights") in
    `seconds` of wall time [s]."""
    with open(path, "w") as stream:
        stream.write(header + yaml.safe_dump(dict(calibration), sort_keys=False))
    print(f"calibrated on {flights} in {seconds:.1f} s: {path}")
