"""The aircraft the project can fly and model: one folder each (docs/aircraft.md).

A vehicle's folder, `aircraft/<vehicle>/` in uav_aircraft's share, holds everything that is
particular to that aircraft:

- `<vehicle>.xml`: its JSBSim definition, with the `fault/<name>-pct` properties, the
  `aero/coefficients/*` properties, the `propeller_model` reactions and the FCS properties
  the simulator and the prediction model set (docs/aircraft.md lists them);
- the engine (or motor) and propeller files its `<engine file=...>` and `<thruster file=...>`
  name;
- `vehicle.yaml`: the autopilot's gains and limits, the trim solver's starting point, the
  air data the model holds for, and the vehicle's default and fault-free scenarios (files
  of the simulator's scenarios/);
- `airframes/<name>.yaml`: the servo mappings of its logs' outputs (uav_aircraft.airframe);
- `residual_noise.yaml` and `detector_calibration.yaml`: the estimator's noise model and the
  detector's calibration, made by scripts/calibrate_estimator.py and calibrate_detector.py on
  this aircraft's own fault-free flights; `failure_signatures.yaml`: which failure a detector
  alarm resembles, made by scripts/learn_signatures.py on its simulated failures.

The surface deflection limits are read from the XML's FCS (one home). No module outside the
folders names an aircraft: code takes a Vehicle, or a vehicle name to load_vehicle. No ROS here.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar
from xml.etree import ElementTree

from uav_common.strict_yaml import FileKind, Reader, is_number, load_yaml

from uav_aircraft.paths import aircraft_dir

DEFAULT_VEHICLE = "aerosonde"
VEHICLE_FILE = "vehicle.yaml"
NOISE_FILE = "residual_noise.yaml"
DETECTOR_CALIBRATION_FILE = "detector_calibration.yaml"
# The paper's three generators' calibration: for flights and logs without the autopilot's
# setpoints, which the shipped generators read.
SURFACE_DETECTOR_CALIBRATION_FILE = "detector_calibration_surfaces.yaml"
# Which failure a detector alarm resembles, learned on this aircraft's simulated failures.
FAILURE_SIGNATURES_FILE = "failure_signatures.yaml"
AIRFRAMES = "airframes"  # the folder of its airframe files
CALIBRATION_PLAN = "calibration_plan"  # its folder of calibration flights
MAX_VEHICLE_BYTES = 16 * 1024
# The FCS outputs whose range is the deflection at a command of 1 (docs/aircraft.md).
SURFACE_POSITIONS = ("fcs/elevator-pos-rad", "fcs/aileron-pos-rad", "fcs/rudder-pos-rad")
FLAP_POSITION = "fcs/flap-pos-rad"


T = TypeVar("T")
# (low, high) of airspeed [m/s], angle of attack and sideslip [rad]
AirDataRange = tuple[tuple[float, float], tuple[float, float], tuple[float, float]]
AIR_DATA_RANGE_KEYS = ("airspeed_mps", "angle_of_attack_rad", "sideslip_rad")


class VehicleError(ValueError):
    """An unknown vehicle, or a vehicle folder that cannot be flown; one line."""


VEHICLE_YAML = FileKind("vehicle file", VehicleError, MAX_VEHICLE_BYTES,
                        "the shipped ones are under 2 kB")


@dataclass(frozen=True)
class AutopilotGains:
    """The autopilot's loop gains and limits (SI, radians; uav_sim.autopilot), from the
    vehicle's vehicle.yaml."""

    altitude_p_radpm: float
    altitude_i_radpms: float
    climb_rate_d_radspm: float
    pitch_limit_rad: float
    pitch_p: float
    pitch_rate_d_s: float
    airspeed_p_permps: float
    airspeed_i_permps_s: float
    roll_p: float
    roll_rate_d_s: float
    roll_limit_rad: float
    sideslip_p: float


@dataclass(frozen=True)
class TrimGuess:
    """Where the trim's solver starts: angle of attack and elevator [rad], throttle 0..1."""

    alpha_rad: float
    elevator_rad: float
    throttle: float


@dataclass(frozen=True)
class Vehicle:
    """One aircraft folder, read: its name, files, limits, autopilot gains and trim guess."""

    name: str
    folder: Path
    description: str
    surface_limit_rad: float  # elevator, aileron and rudder at command 1
    flap_limit_rad: float  # flap at command 1
    engine_file: Path
    propeller_file: Path
    autopilot: AutopilotGains
    trim_guess: TrimGuess
    air_data_range: AirDataRange  # what the model's data covers: the residuals' air data
    # Its flights, files of the simulator's scenarios/ (uav_sim.scenario.vehicle_scenario_path):
    default_scenario_file: str  # its main flight, faults seeded
    fault_free_scenario_file: str  # the same flight without faults: calibrations fly it

    @property
    def model_file(self) -> Path:
        """The JSBSim aircraft definition, `<vehicle>.xml`."""
        return self.folder / f"{self.name}.xml"

    @property
    def model_sha256(self) -> str:
        """The SHA-256 of its XML as shipped: a model calibration holds for this file only."""
        return hashlib.sha256(self.model_file.read_bytes()).hexdigest()

    @property
    def noise_file(self) -> Path:
        """The estimator's residual noise model of this aircraft."""
        return self.folder / NOISE_FILE

    @property
    def calibration_plan_files(self) -> list[Path]:
        """Its calibration plan: the scenario files of the flights that calibrate its model
        (system-identification manoeuvres; docs/model_calibration.md), in name order."""
        return sorted((self.folder / CALIBRATION_PLAN).glob("*.yaml"))

    @property
    def airframe_files(self) -> dict[str, Path]:
        """Its airframe files (the servo mappings of its logs' outputs) by name."""
        return {path.stem: path for path in sorted((self.folder / AIRFRAMES).glob("*.yaml"))}

    def only_airframe_file(self) -> Path:
        """Its airframe file when it has exactly one; VehicleError (one line) when it has
        none or several: then the caller has to be told which."""
        files = self.airframe_files
        if len(files) != 1:
            raise VehicleError(f"vehicle {self.name} has {len(files)} airframe files "
                               f"({', '.join(files) or 'none'}): name one (the airframe "
                               "parameter)")
        return next(iter(files.values()))

    @property
    def simulated_airframe_file(self) -> Path:
        """The airframe file of the simulator's outputs (`<vehicle>_sim.yaml`): how the
        autopilot the simulator plays (autopilot_node) maps its surfaces to PWM."""
        return self.folder / AIRFRAMES / f"{self.name}_sim.yaml"

    @property
    def detector_calibration_file(self) -> Path:
        """The detector's calibration on this aircraft's fault-free flights."""
        return self.folder / DETECTOR_CALIBRATION_FILE

    @property
    def surface_detector_calibration_file(self) -> Path:
        """The detector's calibration of the paper's three generators (roll, pitch, yaw: the
        surfaces and body rates alone) on the same flights."""
        return self.folder / SURFACE_DETECTOR_CALIBRATION_FILE

    @property
    def failure_signatures_file(self) -> Path:
        """The failure signatures over the detector calibration's channels, learned on this
        aircraft's simulated failures (scripts/learn_signatures.py)."""
        return self.folder / FAILURE_SIGNATURES_FILE


def vehicle_names() -> tuple[str, ...]:
    """The vehicles shipped: every folder under aircraft/ with a vehicle.yaml, sorted."""
    return tuple(sorted(path.parent.name for path in aircraft_dir().glob(f"*/{VEHICLE_FILE}")))


def check_vehicle_name(name: str) -> str:
    """name if it is a shipped vehicle; VehicleError naming the known ones otherwise."""
    known = vehicle_names()
    if name not in known:
        raise VehicleError(f"unknown vehicle {name!r} (known: {', '.join(known)})")
    return name


def vehicle_of_sources(said: Mapping[str, str | None], given: str | None,
                       given_as: str = "--vehicle",
                       say: Callable[[str], None] = lambda line: None) -> str:
    """The vehicle that flew what a command reads (recordings, logs): the one the sources
    say (said: each source's name -> the vehicle it says flew, None where it says none),
    else given, else DEFAULT_VEHICLE (and say(line) tells so). VehicleError, one line, when
    the sources name different vehicles, or given (the option given_as) names another than
    they say."""
    sources_of: dict[str, list[str]] = {}
    for source, vehicle in said.items():
        if vehicle is not None:
            sources_of.setdefault(vehicle, []).append(source)
    if len(sources_of) > 1:
        raise VehicleError("different vehicles flew these: " + "; ".join(
            f"{vehicle} {', '.join(sources)}" for vehicle, sources in sorted(sources_of.items()))
            + ": give one vehicle's at a time")
    if not sources_of:
        vehicle = check_vehicle_name(given or DEFAULT_VEHICLE)
        say(f"{', '.join(said)}: no vehicle said; taken as {vehicle}"
            + ("" if given else f" (the default; {given_as} NAME if another flew)"))
        return vehicle
    (vehicle, sources), = sources_of.items()
    if given is not None and given != vehicle:
        raise VehicleError(f"{given_as} {given}, but {vehicle} flew {', '.join(sources)}: "
                           f"leave out {given_as} or give {vehicle}")
    return check_vehicle_name(vehicle)


@functools.cache
def load_vehicle(name: str = DEFAULT_VEHICLE) -> Vehicle:
    """The vehicle's folder read and checked; VehicleError with one line otherwise."""
    folder = aircraft_dir() / check_vehicle_name(name)
    reader = load_yaml(VEHICLE_YAML, folder / VEHICLE_FILE)
    reader.check_keys({"vehicle", "description", "trim_guess", "autopilot", "air_data_range",
                       "scenarios"})
    if reader.text("vehicle") != name:
        reader.fail(f"'vehicle' is {reader.data['vehicle']!r}, but the folder is {name!r}")
    model = _parse_xml(reader, folder / f"{name}.xml")
    surface_limit_rad = _single_limit(reader, model, SURFACE_POSITIONS)
    flap_limit_rad = _single_limit(reader, model, (FLAP_POSITION,))
    engine, thruster = model.find("propulsion/engine"), model.find("propulsion/engine/thruster")
    if engine is None or thruster is None:
        reader.fail(f"{name}.xml has no <propulsion><engine><thruster>")
    return Vehicle(
        name=name, folder=folder, description=reader.text("description"),
        surface_limit_rad=surface_limit_rad, flap_limit_rad=flap_limit_rad,
        engine_file=_existing(reader, folder / f"{engine.get('file')}.xml"),
        propeller_file=_existing(reader, folder / f"{thruster.get('file')}.xml"),
        autopilot=_numbers(reader.child("autopilot"), AutopilotGains),
        trim_guess=_numbers(reader.child("trim_guess"), TrimGuess),
        air_data_range=_air_data_range(reader.child("air_data_range")),
        **_scenarios(reader.child("scenarios")))


def _parse_xml(reader: Reader, path: Path) -> ElementTree.Element:
    try:
        return ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError) as error:
        reader.fail(f"cannot read {path.name}: {error}")
        raise  # fail() raises; for the type checker


def _single_limit(reader: Reader, model: ElementTree.Element, outputs: tuple[str, ...]) -> float:
    """The one deflection [rad] at command 1 of these FCS aerosurface_scale outputs."""
    limits = set()
    for output in outputs:
        element = model.find(f".//aerosurface_scale[@name='{output}']/range/max")
        if element is None:
            reader.fail(f"the XML has no aerosurface_scale '{output}' with a range")
        limits.add(float(element.text))
    if len(limits) != 1:
        reader.fail(f"the XML's {', '.join(outputs)} must share one range, got {sorted(limits)}")
    return limits.pop()


def _air_data_range(reader: Reader) -> AirDataRange:
    """air_data_range: {airspeed_mps: [low, high], angle_of_attack_rad: [...], sideslip_rad:
    [...]}, each low below high."""
    reader.check_keys(set(AIR_DATA_RANGE_KEYS))
    limits = []
    for key in AIR_DATA_RANGE_KEYS:
        pair = reader.data[key]
        if not (isinstance(pair, list) and len(pair) == 2 and all(map(is_number, pair))
                and pair[0] < pair[1]):
            reader.fail(f"'{reader.key(key)}' must be [low, high] with low < high, got {pair!r}")
        limits.append((float(pair[0]), float(pair[1])))
    return tuple(limits)


def _scenarios(reader: Reader) -> dict[str, str]:
    """scenarios: {default: FILE, fault_free: FILE}, file names in the simulator's
    scenarios/ (the simulator checks that they are there)."""
    reader.check_keys({"default", "fault_free"})
    return {f"{key}_scenario_file": reader.text(key) for key in ("default", "fault_free")}


def _existing(reader: Reader, path: Path) -> Path:
    if not path.is_file():
        reader.fail(f"{path.name} is not in {path.parent}")
    return path


def _numbers(reader: Reader, kind: type[T]) -> T:
    """A dataclass of numbers from a mapping with exactly its field names."""
    names = {field.name for field in dataclasses.fields(kind)}
    reader.check_keys(names)
    return kind(**{name: reader.number(name) for name in sorted(names)})
