"""scripts/estimate_offline.py: metrics.json's figures of a scenario without ROS, and a bad
scenario refused in one line."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
import yaml
from helpers.repo import SCRIPTS
from uav_sim.paths import scenarios_dir

SCRIPT = SCRIPTS / "estimate_offline.py"


def run(*arguments: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *arguments], capture_output=True,
                          text=True, timeout=110)


@pytest.mark.timeout(120)
def test_a_short_calm_flight_gives_its_table_and_metrics(tmp_path):
    scenario = yaml.safe_load((scenarios_dir() / "calm_lift_loss.yaml").read_text())
    scenario.update(duration_s=60.0, faults=[
        {"name": "left_wing_lift_loss", "start_s": 15, "ramp_s": 0, "magnitude_pct": 10}])
    path, out = tmp_path / "calm.yaml", tmp_path / "metrics.json"
    path.write_text(yaml.safe_dump(scenario))
    result = run(str(path), "--json", str(out))
    print(result.stdout)
    assert result.returncode == 0, result.stderr
    assert "left_wing_lift_loss" in result.stdout and "120/120 estimates" in result.stdout
    lift = json.loads(out.read_text())["faults"]["left_wing_lift_loss"]
    assert lift["estimate_final_pct"] == pytest.approx(10.0, abs=1.0)
    assert lift["detection_delay_s"] <= 10.0


@pytest.mark.timeout(60)
def test_a_bad_scenario_is_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("name: bad\nduration_s: -1\n")
    result = run(str(path))
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, result
    assert str(path) in result.stderr
