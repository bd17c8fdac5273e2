"""A vehicle in JSBSim: loading it, unit conversions and the properties the project uses.

JSBSim works in feet, pounds and slugs; everything outside this module is SI.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import jsbsim
import numpy as np
from uav_common.channels import STUCK_SURFACE_FAULT_NAMES

from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft, aircraft_folder, apply_to
from uav_aircraft.propeller import PropellerForces

if TYPE_CHECKING:
    from uav_aircraft.vehicles import Vehicle

# 480 Hz: JSBSim's explicit propeller-speed update diverges at 120 Hz when the propeller
# spins up (inertia 0.002 kg m^2 against 1.4 kW); 480 Hz is stable (measured).
JSBSIM_DT_S = 1.0 / 480.0

M_PER_FT = 0.3048
N_PER_LBF = 4.4482216152605
NM_PER_LBFFT = N_PER_LBF * M_PER_FT
KG_PER_LB = 0.45359237
KG_PER_M3_PER_SLUG_PER_FT3 = 515.378818
MPS_PER_KT = 1852.0 / 3600.0

# Fault properties: percent change of the named coefficient, or 100 while an actuator fault
# is active (docs/design.md); a stuck surface's output while it is [-1..1].
FAULT_PROPERTY = "fault/{name}-pct"
STUCK_POSITION_PROPERTY = "fault/{name}-position-norm"
# The throttle the engine gets: the command, or 0 once an engine_cut pinned it (measured).
THROTTLE_OUTPUT = "fcs/throttle-out-norm"
# Propeller force and moment injected by the prediction model (aircraft XML).
MODEL_THRUST_LBF = "external_reactions/propeller_model/magnitude"
MODEL_MOMENT_LBFFT = "external_reactions/propeller_model/magnitude-lbsft"
MODEL_MOMENT_AXIS = tuple(f"external_reactions/propeller_model/{axis}" for axis in "lmn")
# 1: JSBSim's engine and propeller fly; 0: they are off and the propeller_model reactions
# carry the propeller (run_ic() never advances JSBSim's propeller speed).
JSBSIM_ENGINE_ON = "propulsion/jsbsim-engine-on"
EFFECTIVE_THROTTLE = "fcs/throttle-effective-norm"
FUEL_LOADED_LBS = "propulsion/fuel-loaded-lbs"

BODY_ACCELERATIONS = (
    "accelerations/udot-ft_sec2",
    "accelerations/vdot-ft_sec2",
    "accelerations/wdot-ft_sec2",
    "accelerations/pdot-rad_sec2",
    "accelerations/qdot-rad_sec2",
    "accelerations/rdot-rad_sec2",
)


def create_fdm(vehicle: Vehicle, dt_s: float = JSBSIM_DT_S,
               aircraft: FlownAircraft = NOMINAL) -> jsbsim.FGFDMExec:
    """A silent JSBSim executive with the vehicle loaded, at time step dt_s [s]; as the
    flown aircraft says where it differs (the prediction models keep the nominal one)."""
    os.environ.setdefault("JSBSIM_DEBUG", "0")  # no start-up banner on stdout
    fdm = jsbsim.FGFDMExec(str(vehicle.folder), None)
    fdm.set_debug_level(0)
    folder = aircraft_folder(vehicle, aircraft)
    fdm.set_aircraft_path(str(folder))
    fdm.set_engine_path(str(vehicle.folder))  # its engine and propeller sit beside its XML
    if not fdm.load_model(vehicle.name):
        raise RuntimeError(f"JSBSim could not load the aircraft '{vehicle.name}' from {folder}")
    apply_to(fdm, aircraft)
    fdm.set_dt(dt_s)
    return fdm


def loaded_fuel_kg(vehicle: Vehicle, aircraft: FlownAircraft = NOMINAL) -> float:
    """The fuel the aircraft carries at the start of a flight [kg]: its model's tanks, as
    the flown aircraft loads them (0 for an electric aircraft)."""
    return create_fdm(vehicle, aircraft=aircraft)[FUEL_LOADED_LBS] * KG_PER_LB


def fuel_on_board_kg(given_kg: float, vehicle: Vehicle) -> float:
    """The fuel on board [kg] where no log or link says it: given_kg where it is given (0 or
    more), else (a negative value: vehicle_parameter.VEHICLE_FUEL_KG) what the vehicle's
    model carries at the start of a flight (loaded_fuel_kg)."""
    return given_kg if given_kg >= 0.0 else loaded_fuel_kg(vehicle)


def set_faults(fdm: jsbsim.FGFDMExec, faults_pct: dict[str, float]) -> None:
    """Seed faults [%] by name into the aircraft's fault properties."""
    for name, value_pct in faults_pct.items():
        fdm[fault_property(name)] = value_pct


def set_stuck_positions(fdm: jsbsim.FGFDMExec, positions: Mapping[str, float]) -> None:
    """Where each stuck surface's output is pinned once its fault is active: stuck-surface
    fault name (STUCK_SURFACE_FAULT_NAMES) -> position [-1, 1]."""
    for name, position in positions.items():
        if name not in STUCK_SURFACE_FAULT_NAMES:
            raise ValueError(f"{name} is no stuck surface ({', '.join(STUCK_SURFACE_FAULT_NAMES)})")
        fdm[STUCK_POSITION_PROPERTY.format(name=name)] = position


def property_nodes(fdm: jsbsim.FGFDMExec, names: Sequence[str]) -> list[jsbsim.FGPropertyNode]:
    """The JSBSim nodes of existing properties, for a loop that reads or writes them often:
    node.set_double_value skips the path lookup that fdm[name] = value makes each time
    (0.05 us a write instead of 0.47); the value read or written is the same double."""
    manager = fdm.get_property_manager()
    nodes = [manager.get_node(name) for name in names]
    missing = [name for name, node in zip(names, nodes, strict=True) if node is None]
    if missing:
        raise KeyError(f"no JSBSim properties {', '.join(missing)}")
    return nodes


@functools.cache
def fault_property(name: str) -> str:
    """The JSBSim property of a fault, formatted once per name (set_faults is on the
    control loop's path)."""
    return FAULT_PROPERTY.format(name=name)


def apply_propeller_model(fdm: jsbsim.FGFDMExec, forces: PropellerForces) -> None:
    """Put a propeller force and moment on the aircraft's `propeller_model` reactions."""
    fdm[MODEL_THRUST_LBF] = forces.thrust_n / N_PER_LBF
    magnitude_nm = float(np.linalg.norm(forces.moment_nm))
    fdm[MODEL_MOMENT_LBFFT] = magnitude_nm / NM_PER_LBFFT
    axis = forces.moment_nm / magnitude_nm if magnitude_nm > 0 else np.array([1.0, 0.0, 0.0])
    for name, component in zip(MODEL_MOMENT_AXIS, axis, strict=True):
        fdm[name] = float(component)


def clear_propeller_model(fdm: jsbsim.FGFDMExec) -> None:
    apply_propeller_model(fdm, PropellerForces(0.0, np.zeros(3)))
