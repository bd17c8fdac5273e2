"""Failures seeded into a vehicle's fault-free flights, each beside its twin: the flights
of the failure-kinds study (studies/failure_kinds.py) and of the failure signatures
(scripts/learn_signatures.py).

The kinds: ALFA's failures (each surface stuck at 0, as ALFA's injection pins it, and the
engine cut), and the seven model faults each as a step and as a ramp over RAMP_S, at the
magnitude the vehicle's shipped scenarios seed (model_fault_magnitudes_pct). count
fault-free flights of the vehicle (offline.fault_free_flights: seeds from first_seed, winds
of 20-25 % of its airspeed in as many directions) are each flown as they are, and once per
kind with that kind seeded from an onset drawn in ONSET_RANGE_S (seeded) to
AFTER_REFERENCE_S after the reference time: the onset, or for a ramp the moment its seeded
value reaches DETECTION_THRESHOLD_PCT (the demo's target counts from there too). A failed
flight and its twin (the fault-free flight of the same seed) differ by the failure alone:
the same seed, wind and turbulence, and the simulation is causal. No ROS here.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np
from uav_common.channels import (
    ACTUATOR_FAULT_NAMES,
    DETECTION_THRESHOLD_PCT,
    MODEL_FAULT_NAMES,
)
from uav_sim.scenario import (
    ACTUATOR_FAULT_PCT,
    Scenario,
    SeededFault,
    load_scenario,
    scenarios_dir,
    vehicle_scenario_path,
)

from uav_fault_estimator.chain.offline import fault_free_flights

ONSET_RANGE_S = (60.0, 120.0)
RAMP_S = 30.0  # a model fault's ramp from 0 to its magnitude (the default scenario's drag ramp)
AFTER_REFERENCE_S = 30.0
FAULT_FREE = "fault_free"
SHAPES = ("step", "ramp")
# The scenarios whose faults give each model fault's magnitude, after the vehicle's default.
MAGNITUDE_SCENARIOS = ("propulsion_loss.yaml", "aileron_loss.yaml", "tail_damage.yaml")


class FailureFlight(NamedTuple):
    """One flight: its kind (FAULT_FREE, an actuator fault's name or
    '<model fault>_<shape>'), onset and reference time [s] (nan for a fault-free flight), the
    index of its twin among the fault-free flights, and its scenario."""

    kind: str
    onset_s: float
    reference_s: float
    twin: int
    scenario: Scenario


def model_fault_magnitudes_pct(vehicle: str) -> dict[str, float]:
    """Each model fault's magnitude [%]: the first a shipped scenario seeds, the vehicle's
    default scenario first, then MAGNITUDE_SCENARIOS; ValueError for one that none seeds."""
    found: dict[str, float] = {}
    paths = (vehicle_scenario_path(vehicle, "default"),
             *(scenarios_dir() / name for name in MAGNITUDE_SCENARIOS))
    for path in paths:
        for fault in load_scenario(path).faults:
            found.setdefault(fault.name, fault.magnitude_pct)
    missing = [name for name in MODEL_FAULT_NAMES if name not in found]
    if missing:
        raise ValueError(f"no shipped scenario seeds {', '.join(missing)}")
    return {name: found[name] for name in MODEL_FAULT_NAMES}


def kind_faults(vehicle: str) -> dict[str, SeededFault]:
    """Every kind of the study and its fault, starting at 0 s: ALFA's failures as the
    simulator seeds them, each model fault as a step and as a ramp over RAMP_S."""
    kinds = {name: SeededFault(name, 0.0, 0.0, ACTUATOR_FAULT_PCT)
             for name in ACTUATOR_FAULT_NAMES}
    for name, magnitude_pct in model_fault_magnitudes_pct(vehicle).items():
        for shape in SHAPES:
            kinds[f"{name}_{shape}"] = SeededFault(
                name, 0.0, RAMP_S if shape == "ramp" else 0.0, magnitude_pct)
    return kinds


def reference_after_onset_s(fault: SeededFault) -> float:
    """When, after its start [s], a fault counts as present: at once for a step or an
    actuator fault, when a ramp reaches DETECTION_THRESHOLD_PCT."""
    if fault.ramp_s <= 0.0:
        return 0.0
    return fault.ramp_s * min(DETECTION_THRESHOLD_PCT / fault.magnitude_pct, 1.0)


def failure_flights(vehicle: str, count: int, first_seed: int,
                    kinds: tuple[str, ...] | None = None) -> list[FailureFlight]:
    """count fault-free flights of the vehicle (the twins, seeds from first_seed), then
    count of each kind (all of kind_faults' by default), in that order; ValueError for a
    kind kind_faults does not have."""
    faults = kind_faults(vehicle)
    unknown = sorted(set(kinds or ()) - set(faults))
    if unknown:
        raise ValueError(f"kinds {', '.join(unknown)}: expected some of {', '.join(faults)}")
    longest_s = ONSET_RANGE_S[1] + RAMP_S + AFTER_REFERENCE_S
    bases = fault_free_flights(count, first_seed, 0.0, vehicle)
    table = [FailureFlight(FAULT_FREE, np.nan, np.nan, i,
                         dataclasses.replace(base, duration_s=longest_s))
             for i, base in enumerate(bases)]
    rng = np.random.default_rng(first_seed)
    for kind, fault in faults.items():
        onsets_s = rng.uniform(*ONSET_RANGE_S, size=count)  # drawn for every kind: seeded alike
        if kinds is not None and kind not in kinds:
            continue
        for i, (base, onset_s) in enumerate(zip(bases, onsets_s, strict=True)):
            reference_s = float(onset_s) + reference_after_onset_s(fault)
            seeded = dataclasses.replace(fault, start_s=float(onset_s))
            table.append(FailureFlight(kind, float(onset_s), reference_s, i, dataclasses.replace(
                base, duration_s=reference_s + AFTER_REFERENCE_S, faults=(seeded,))))
    return table
