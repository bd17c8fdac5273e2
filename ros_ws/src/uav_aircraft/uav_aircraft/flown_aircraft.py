"""The aircraft the simulator flies, where it differs from the vehicle the models evaluate.

A real aircraft differs from its model by a few percent: payload and fuel, drag from
antennas and skin, lift slope, pitch stiffness, vane misalignment. A FlownAircraft says how
(a scenario's `aircraft:` block): scales of the empty mass, the empty inertia (per axis),
the thrust, and of any aerodynamic coefficient of the vehicle's XML by its name there
(`aero/coefficients/NAME`), an offset of the empty CG, and biases of the air-data sensors.
Only the simulator flies it; the prediction models stay nominal.

Coefficients and thrust are JSBSim properties, set on a loaded aircraft (apply_to). Mass,
inertia and CG are read-only in JSBSim once loaded: an aircraft that changes them is
loaded from an edited copy of the vehicle's XML (aircraft_folder), written once per process
and aircraft. No ROS here.
"""

from __future__ import annotations

import functools
import math
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from xml.etree import ElementTree

import jsbsim
import numpy as np
from uav_common.strict_yaml import Reader, is_number

if TYPE_CHECKING:
    from uav_aircraft.vehicles import Vehicle

COEFFICIENT_PROPERTY = "aero/coefficients/{name}"
THRUST_SCALE_PROPERTY = "propulsion/thrust-scale"
SCALE_RANGE = (0.5, 2.0)  # what a scale may be: a model this far off is another aircraft
BIAS_LIMIT_DEG = 5.0  # the largest vane bias [deg]
CG_OFFSET_LIMIT_M = 0.1  # the largest CG offset per axis [m] (a small UAV's chord: 0.2 m)
DIAGNOSTIC_KEY = "flown_aircraft"  # sim_node's /diagnostics key: differences() as JSON


@dataclass(frozen=True)
class SensorBias:
    """Air-data sensor errors of the flown aircraft: the pitot's scale on true airspeed and
    the vanes' offsets [deg]."""

    airspeed_scale: float = 1.0
    angle_of_attack_deg: float = 0.0
    sideslip_deg: float = 0.0


NO_BIAS = SensorBias()


def biased_air_data(air_data: np.ndarray, bias: SensorBias) -> np.ndarray:
    """(airspeed [m/s], alpha, beta [rad]) as sensors with this bias read them."""
    airspeed_mps, alpha_rad, beta_rad = air_data
    return np.array([airspeed_mps * bias.airspeed_scale,
                     alpha_rad + math.radians(bias.angle_of_attack_deg),
                     beta_rad + math.radians(bias.sideslip_deg)])


def true_air_data(measured: np.ndarray, bias: SensorBias) -> np.ndarray:
    """The (airspeed [m/s], alpha, beta [rad]) that sensors with this bias read as measured:
    biased_air_data's inverse."""
    airspeed_mps, alpha_rad, beta_rad = measured
    return np.array([airspeed_mps / bias.airspeed_scale,
                     alpha_rad - math.radians(bias.angle_of_attack_deg),
                     beta_rad - math.radians(bias.sideslip_deg)])


@dataclass(frozen=True)
class FlownAircraft:
    """How the flown aircraft differs from the model (all 1 or 0: it is the model).

    mass_scale, inertia_scale (x, y, z): of the empty mass and its inertia (the product
    Jxz scales with sqrt(x z)); cg_offset_m (x, y, z): of the empty CG [m], body axes (x
    forward, y right, z down); thrust_scale: of the propeller's thrust; coefficients: NAME
    -> scale of the vehicle XML's `aero/coefficients/NAME` (coefficient_names()); sensor_bias.
    """

    mass_scale: float = 1.0
    inertia_scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    cg_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    thrust_scale: float = 1.0
    coefficients: tuple[tuple[str, float], ...] = ()
    sensor_bias: SensorBias = NO_BIAS

    @property
    def changes_mass_balance(self) -> bool:
        """Whether mass, inertia or CG differ (the aircraft is loaded from an edited copy)."""
        return (self.mass_scale != 1.0 or self.inertia_scale != (1.0, 1.0, 1.0)
                or self.cg_offset_m != (0.0, 0.0, 0.0))

    def to_dict(self) -> dict:
        """As a scenario's `aircraft:` block (what a recording keeps of the flight)."""
        return {"mass_scale": self.mass_scale, "inertia_scale": list(self.inertia_scale),
                "cg_offset_m": list(self.cg_offset_m), "thrust_scale": self.thrust_scale,
                "coefficients": dict(self.coefficients),
                "sensor_bias": {"airspeed_scale": self.sensor_bias.airspeed_scale,
                                "angle_of_attack_deg": self.sensor_bias.angle_of_attack_deg,
                                "sideslip_deg": self.sensor_bias.sideslip_deg}}

    def differences(self) -> dict:
        """to_dict's entries where the aircraft is not the model ({}: it is the model)."""
        nominal, flown = FlownAircraft().to_dict(), self.to_dict()
        entries = {key: value for key, value in flown.items()
                   if key not in ("coefficients", "sensor_bias") and value != nominal[key]}
        if self.coefficients:
            entries["coefficients"] = dict(self.coefficients)
        bias = {key: value for key, value in flown["sensor_bias"].items()
                if value != nominal["sensor_bias"][key]}
        if bias:
            entries["sensor_bias"] = bias
        return entries


NOMINAL = FlownAircraft()


@functools.cache
def coefficient_names(vehicle: Vehicle) -> tuple[str, ...]:
    """The names of the vehicle XML's coefficient properties, in the file's order: the one
    home of the list."""
    prefix = COEFFICIENT_PROPERTY.format(name="")
    names = [element.text.strip()[len(prefix):]
             for element in ElementTree.parse(vehicle.model_file).iter("property")
             if element.get("value") is not None and element.text.strip().startswith(prefix)]
    return tuple(names)


def apply_to(fdm: jsbsim.FGFDMExec, aircraft: FlownAircraft) -> None:
    """Scale a freshly loaded aircraft's coefficients and thrust (its properties hold the
    file's values: each is set to the file's value times its scale)."""
    for name, scale in aircraft.coefficients:
        prop = COEFFICIENT_PROPERTY.format(name=name)
        fdm[prop] = fdm[prop] * scale
    fdm[THRUST_SCALE_PROPERTY] = aircraft.thrust_scale


def aircraft_folder(vehicle: Vehicle, aircraft: FlownAircraft) -> Path:
    """JSBSim's aircraft folder to load this aircraft from: the shipped one, or an edited
    copy of the vehicle's XML with the aircraft's mass, inertia and CG."""
    if not aircraft.changes_mass_balance:
        return vehicle.folder.parent
    return _edited_folder(vehicle.model_file, aircraft.mass_scale, aircraft.inertia_scale,
                          aircraft.cg_offset_m)


@functools.cache
def _edited_folder(model_file: Path, mass_scale: float,
                   inertia_scale: tuple[float, float, float],
                   cg_offset_m: tuple[float, float, float]) -> Path:
    """A temporary aircraft folder whose copy of model_file (`<vehicle>.xml` in its vehicle
    folder) has the empty mass, inertia and CG changed (kept for the process's life)."""
    text = model_file.read_text()
    x, y, z = inertia_scale
    for tag, scale in (("ixx", x), ("iyy", y), ("izz", z), ("ixz", math.sqrt(x * z)),
                       ("emptywt", mass_scale)):
        text = _scaled_element(text, model_file, tag, scale)
    # the XML's structural frame: x aft, y right, z up; the offset is in body axes
    north, east, down = cg_offset_m
    for axis, offset in (("x", -north), ("y", east), ("z", -down)):
        text = _shifted_cg(text, model_file, axis, offset)
    folder = Path(tempfile.mkdtemp(prefix="flown_aircraft_"))
    (folder / model_file.parent.name).mkdir()
    (folder / model_file.parent.name / model_file.name).write_text(text)
    return folder


def _scaled_element(text: str, model_file: Path, tag: str, scale: float) -> str:
    """The file with the number of its one <tag unit=...> NUMBER </tag> times scale."""
    pattern = re.compile(rf"(<{tag} unit=\"[^\"]+\">\s*)([-0-9.eE+]+)(\s*</{tag}>)")
    if len(pattern.findall(text)) != 1:
        raise ValueError(f"{model_file}: expected one <{tag}>")
    return pattern.sub(lambda m: f"{m[1]}{float(m[2]) * float(scale)!r}{m[3]}", text)


def _shifted_cg(text: str, model_file: Path, axis: str, offset_m: float) -> str:
    """The file with its CG location's axis coordinate [m] moved by offset_m."""
    block = re.compile(r"(<location name=\"CG\" unit=\"M\">.*?</location>)", re.S)
    match = block.search(text)
    if match is None:
        raise ValueError(f"{model_file}: no CG location in metres")
    moved = re.sub(rf"(<{axis}>\s*)([-0-9.eE+]+)(\s*</{axis}>)",
                   lambda m: f"{m[1]}{float(m[2]) + float(offset_m)!r}{m[3]}", match[1])
    return text[:match.start()] + moved + text[match.end():]


def _scale(reader: Reader, name: str) -> float:
    return reader.number(name, minimum=SCALE_RANGE[0], maximum=SCALE_RANGE[1])


def _triple(reader: Reader, name: str, low: float, high: float) -> tuple[float, float, float]:
    """[x, y, z], each in low..high."""
    values = reader.items(name)
    if len(values) != 3 or not all(map(is_number, values)) or not all(
            low <= value <= high for value in values):
        reader.fail(f"'{reader.key(name)}' must be [x, y, z], each in {low:g}..{high:g}, "
                    f"got {values!r}")
    return tuple(float(value) for value in values)


def read_aircraft(reader: Reader, vehicle: Vehicle) -> FlownAircraft:
    """An `aircraft:` block (a scenario's flown aircraft, a model calibration's model) of the
    vehicle, strictly: unknown keys and coefficient names refused, scales and biases
    within their limits."""
    reader.check_keys(set(), {"mass_scale", "inertia_scale", "cg_offset_m", "thrust_scale",
                              "coefficients", "sensor_bias"})
    data = reader.data
    known_coefficients = set(coefficient_names(vehicle))
    coefficients = reader.child("coefficients") if "coefficients" in data else None
    if coefficients is not None:
        coefficients.check_keys(set(), known_coefficients)
    bias = reader.child("sensor_bias") if "sensor_bias" in data else None
    if bias is not None:
        bias.check_keys(set(), {"airspeed_scale", "angle_of_attack_deg", "sideslip_deg"})

    def angle(name: str) -> float:
        if bias is None or name not in bias.data:
            return 0.0
        return bias.number(name, minimum=-BIAS_LIMIT_DEG, maximum=BIAS_LIMIT_DEG)

    return FlownAircraft(
        mass_scale=_scale(reader, "mass_scale") if "mass_scale" in data else 1.0,
        inertia_scale=(_triple(reader, "inertia_scale", *SCALE_RANGE)
                       if "inertia_scale" in data else (1.0, 1.0, 1.0)),
        cg_offset_m=(_triple(reader, "cg_offset_m", -CG_OFFSET_LIMIT_M, CG_OFFSET_LIMIT_M)
                     if "cg_offset_m" in data else (0.0, 0.0, 0.0)),
        thrust_scale=_scale(reader, "thrust_scale") if "thrust_scale" in data else 1.0,
        coefficients=tuple((name, _scale(coefficients, name))
                           for name in (coefficients.data if coefficients else ())),
        sensor_bias=SensorBias(
            airspeed_scale=(_scale(bias, "airspeed_scale")
                            if bias is not None and "airspeed_scale" in bias.data else 1.0),
            angle_of_attack_deg=angle("angle_of_attack_deg"),
            sideslip_deg=angle("sideslip_deg")),
    )
