#!/usr/bin/env python3
"""The aircraft that is not its model: the diagnosis without and with a model calibration,
through the graph.

    python -m studies.model_error [--aircraft NAME ...] [--json FILE] [--work DIR]

For each flown aircraft of FLOWN (how it differs from aerosonde.xml): three fault-free
calibration flights of it (the fault_free scenario at 22, 25 and 28 m/s, turbulence and noise
seeds 501-503, background winds of 5.0-6.0 m/s towards 30, 150 and 270 deg) flown with
scripts/demo.sh; scripts/calibrate_model.py on their bags (default parameters); then the
test flights, the shipped default and fault_free scenarios (seed 7, the paper's wind) of the
same aircraft, flown with demo.sh without and with --model-calibration. Prints per aircraft
the fault-free flight's largest estimate after settle_s and the default flight's finals, RMS
errors, detection delays and false alarms, both ways (docs/model_calibration.md's table).
The flights run one after the other (one ROS graph at a time); about 2.5 minutes per
aircraft on the 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import yaml
from uav_sim.scenario import default_scenario_path

REPO_ROOT = Path(__file__).resolve().parent.parent
DRAGS = ("CDmin", "CDinduced", "CDflap", "CDde", "CDda", "CDdr")
# name -> the scenario's aircraft block (the table, and the target aircraft)
FLOWN: dict[str, dict] = {
    "model": {},
    "mass+5%": {"mass_scale": 1.05},
    "drag+10%": {"coefficients": dict.fromkeys(DRAGS, 1.10)},
    "CLalpha-5%": {"coefficients": {"CLalpha": 0.95}},
    "Cmalpha+10%": {"coefficients": {"Cmalpha": 1.10}},
    "Cm0+10%": {"coefficients": {"Cm0": 1.10}},
    "inertia+10%,Clp-10%,Clda-5%": {"inertia_scale": [1.1, 1.1, 1.1],
                                   "coefficients": {"Clp": 0.90, "Clda": 0.95}},
    "half of mass,drag,CLalpha,inertia": {
        "mass_scale": 1.025, "inertia_scale": [1.05, 1.05, 1.05],
        "coefficients": {**dict.fromkeys(DRAGS, 1.05), "CLalpha": 0.975}},
    "target": {"mass_scale": 1.04, "thrust_scale": 0.95,
               "coefficients": {"CDmin": 1.10, "CLalpha": 0.95, "Cmalpha": 1.10, "Cm0": 1.10},
               "sensor_bias": {"angle_of_attack_deg": 0.5}},
}
CALIBRATION_FLIGHTS = ((22.0, 501, 30.0, 5.0), (25.0, 502, 150.0, 5.5), (28.0, 503, 270.0, 6.0))


def scenario_file(folder: Path, base_name: str, aircraft: dict, name: str,
                  changes: dict | None = None) -> Path:
    """A copy of a shipped scenario with the aircraft block (and other top-level changes)."""
    data = yaml.safe_load((default_scenario_path().parent / f"{base_name}.yaml").read_text())
    data.update(changes or {})
    data["name"] = name
    if aircraft:
        data["aircraft"] = aircraft
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def demo(scenario: Path, out: Path, model: Path | None = None) -> dict:
    """Fly a scenario through the graph (scripts/demo.sh); its metrics.json."""
    command = [str(REPO_ROOT / "scripts/demo.sh"), str(scenario), "--out", str(out)]
    if model is not None:
        command += ["--model-calibration", str(model)]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return json.loads((out / "metrics.json").read_text())


def summary(fault_free: dict, default: dict) -> dict:
    """The table's figures of a fault-free and a default run's metrics."""
    faults = default["faults"]
    return {
        "fault_free_largest_pct": {name: fault["max_abs_error_pct"]
                                   for name, fault in fault_free["faults"].items()},
        "fault_free_false_alarms": fault_free["false_alarms"],
        "default_final_pct": {name: fault["estimate_final_pct"] for name, fault in faults.items()},
        "default_rmse_pct": {name: fault["rmse_pct"] for name, fault in faults.items()},
        "default_delay_s": {name: fault["detection_delay_s"] for name, fault in faults.items()},
        "default_false_alarms": default["false_alarms"],
    }


def study_aircraft(name: str, aircraft: dict, work: Path) -> dict:
    """Calibrate on the calibration flights, then the test flights without and with it."""
    folder = work / name.replace(",", "_").replace("%", "pct")
    folder.mkdir(parents=True, exist_ok=True)
    bags = []
    for airspeed_mps, seed, towards_deg, speed_mps in CALIBRATION_FLIGHTS:
        direction = math.radians(towards_deg)
        wind = yaml.safe_load((default_scenario_path().parent / "fault_free.yaml").read_text())[
            "wind"]
        wind.update(north_mps=round(speed_mps * math.cos(direction), 3),
                    east_mps=round(speed_mps * math.sin(direction), 3))
        flight = f"calibration_{airspeed_mps:g}"
        initial = yaml.safe_load((default_scenario_path().parent / "fault_free.yaml").read_text())[
            "initial"] | {"airspeed_mps": airspeed_mps}
        scenario = scenario_file(folder, "fault_free", aircraft, flight,
                                 {"seed": seed, "wind": wind, "initial": initial})
        demo(scenario, folder / flight)
        bags.append(str(folder / flight / "bag"))
    model = folder / "model.yaml"
    started = time.monotonic()
    subprocess.run([sys.executable, str(REPO_ROOT / "scripts/calibrate_model.py"), *bags,
                    "--out", str(model)], check=True)
    calibration_s = time.monotonic() - started
    runs = {}
    for label, calibration in (("without", None), ("with", model)):
        metrics = {base: demo(scenario_file(folder, base, aircraft, f"{base}_test"),
                              folder / f"{base}_{label}", calibration)
                   for base in ("fault_free", "default")}
        runs[label] = summary(metrics["fault_free"], metrics["default"])
    parameters = yaml.safe_load(model.read_text())["parameters"]
    return {"flown": aircraft, "calibration_wall_s": round(calibration_s, 1),
            "calibrated": {key: [entry["value"], entry["posterior_std"]]
                           for key, entry in parameters.items()}, **runs}


def print_row(name: str, result: dict) -> None:
    for label in ("without", "with"):
        run = result[label]
        print(f"{name:<34} {label:<8} fault-free largest "
              + "/".join(f"{v:.2f}" for v in run["fault_free_largest_pct"].values())
              + " | finals " + "/".join(f"{v:.2f}" for v in run["default_final_pct"].values())
              + " | rmse " + "/".join(f"{v:.2f}" for v in run["default_rmse_pct"].values())
              + " | delays " + "/".join("-" if v is None else f"{v:g}"
                                         for v in run["default_delay_s"].values())
              + f" | false {run['fault_free_false_alarms'] + run['default_false_alarms']}",
              flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", nargs="*", choices=list(FLOWN), default=list(FLOWN))
    parser.add_argument("--json", type=Path, help="also write the results here (updated "
                        "aircraft by aircraft: the other aircraft's results in it are kept)")
    parser.add_argument("--work", type=Path, default=REPO_ROOT / "runs" / "model_error")
    arguments = parser.parse_args()
    results = {}
    if arguments.json and arguments.json.exists():
        results = json.loads(arguments.json.read_text())
    for name in arguments.aircraft:
        results[name] = study_aircraft(name, FLOWN[name], arguments.work)
        print_row(name, results[name])
        if arguments.json:
            ordered = {key: results[key] for key in FLOWN if key in results}
            arguments.json.write_text(json.dumps(ordered, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
