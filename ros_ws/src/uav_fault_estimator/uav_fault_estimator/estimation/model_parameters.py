"""The prediction model's parameters a model calibration identifies, and what a value of them
does to the model aircraft.

Every parameter is a change from the vehicle's XML as shipped, in a unit of its own: a scale's
change in percent (CDmin at +10 % is the file's CDmin times 1.10), a vane's bias in degrees.
So the nominal model is 0 in every parameter, and a calibrated model is a FlownAircraft
(uav_aircraft.flown_aircraft) that the residual node's model copies load: the scenario's
`aircraft:` block read the other way round, one schema for both.

- every aerodynamic coefficient of the vehicle's XML by its name there (coefficient_names());
- mass_scale, thrust_scale, inertia_{x,y,z}_scale: of the empty mass, the propeller's thrust
  and the empty inertia about each body axis;
- cg_x_cm, cg_y_cm, cg_z_cm: the empty CG's offset along each body axis [cm] (a payload
  off the centre line rolls the aircraft, which no coefficient of the file can take);
- airspeed_scale, angle_of_attack_deg, sideslip_deg: the air-data sensors' errors, which the
  residual generator takes out of the measured air data.

No ROS here.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from uav_aircraft.flown_aircraft import (
    BIAS_LIMIT_DEG,
    CG_OFFSET_LIMIT_M,
    SCALE_RANGE,
    FlownAircraft,
    coefficient_names,
)
from uav_aircraft.vehicles import Vehicle

MASS_AND_THRUST = ("mass_scale", "thrust_scale")
INERTIA = ("inertia_x_scale", "inertia_y_scale", "inertia_z_scale")
CG = ("cg_x_cm", "cg_y_cm", "cg_z_cm")
CG_PRIOR_STD_CM = 2.0  # a CG is known within about this much per axis
# SensorBias's fields, in its units (a scale, degrees)
AIR_DATA_BIASES = ("airspeed_scale", "angle_of_attack_deg", "sideslip_deg")
# every parameter that is not one of the vehicle's aerodynamic coefficients
AIRCRAFT_PARAMETERS = MASS_AND_THRUST + INERTIA + CG + AIR_DATA_BIASES
# What calibrate_model.py identifies unless told otherwise: what a real airframe differs in
# that three ordinary fault-free flights show (docs/model_calibration.md), the weak ones held
# near their prior rather than left out, so that a difference in one of them is not pushed
# into another. Pairs the flights cannot separate (|correlation| above 0.95: mass_scale and
# thrust_scale, Cmalpha and Cmde, CL0 with CDinduced and the alpha vane's bias) are split by
# the prior. Left out, each for a bias of the method rather than of the aircraft (the model's
# own flights fit them far from 0): the inertias (+25-42 %: the residual generator's filtered
# angular accelerations lag the predicted ones) and the CG along x and z (-1.8 and -1.8 cm,
# 3 posterior deviations, with Cm0 at -14 %, and then drag false alarms in the default
# flight); cg_y_cm, which nothing else can take (a payload off the centre line), stays.
DEFAULT_PARAMETERS = ("CL0", "CLalpha", "CDmin", "CDinduced", "Cm0", "Cmalpha", "Cmq", "Cmde",
                      "Clp", "Clda", "Cnbeta", "Cnr", "mass_scale", "thrust_scale", "cg_y_cm",
                      "airspeed_scale", "angle_of_attack_deg", "sideslip_deg")
SCALE_STEP_PCT = 1.0  # secant step of a scale [%]
BIAS_STEP_DEG = 0.2  # secant step of a vane bias [deg]
_SCALE_LIMITS_PCT = (100.0 * (SCALE_RANGE[0] - 1.0), 100.0 * (SCALE_RANGE[1] - 1.0))


@dataclass(frozen=True)
class ModelParameter:
    """One parameter: its unit ("%" of a scale, or "deg"), the prior's standard deviation
    about the nominal 0, the secant step of its sensitivity and its bounds, all in its unit."""

    name: str
    unit: str
    prior_std: float
    step: float
    bounds: tuple[float, float]

    @property
    def native_per_unit(self) -> float:
        """The FlownAircraft field's change per unit of the parameter: a scale's per %, 0.01;
        a bias's per degree, 1."""
        return 0.01 if self.unit in ("%", "cm") else 1.0

    @property
    def is_bias(self) -> bool:
        """An air-data sensor's error (taken out of the air data, not a model copy's)."""
        return self.name in AIR_DATA_BIASES


def parameter_names(vehicle: Vehicle) -> tuple[str, ...]:
    """Every parameter a calibration of the vehicle can identify, coefficients first in the
    file's order."""
    return coefficient_names(vehicle) + AIRCRAFT_PARAMETERS


def model_parameter(name: str, vehicle: Vehicle) -> ModelParameter:
    """The parameter's definition; ValueError naming it when it is not one of the vehicle's."""
    if name not in parameter_names(vehicle):
        raise ValueError(f"unknown model parameter '{name}' of {vehicle.name}; known: "
                         f"{', '.join(parameter_names(vehicle))}")
    return _definition(name)


def _definition(name: str) -> ModelParameter:
    """The definition of a parameter known to be one (model_parameter checks)."""
    if name in CG:
        limit_cm = 100.0 * CG_OFFSET_LIMIT_M
        return ModelParameter(name, "cm", prior_std=CG_PRIOR_STD_CM, step=SCALE_STEP_PCT,
                              bounds=(-limit_cm, limit_cm))
    if name.endswith("_deg"):
        return ModelParameter(name, "deg", prior_std=1.0, step=BIAS_STEP_DEG,
                              bounds=(-BIAS_LIMIT_DEG, BIAS_LIMIT_DEG))
    # A priori a real aircraft is within about 10 % of its model in each (the errors of
    # docs/model_calibration.md's table); a pitot's scale within 3 %.
    prior_std = 3.0 if name == "airspeed_scale" else 10.0
    return ModelParameter(name, "%", prior_std=prior_std, step=SCALE_STEP_PCT,
                          bounds=_SCALE_LIMITS_PCT)


# In a parameter list: every aerodynamic coefficient of the vehicle's XML
EVERY_COEFFICIENT = "coefficients"


def parameter_list(text: str, vehicle: Vehicle) -> tuple[str, ...]:
    """The parameters a comma-separated list names ("CDmin, Cmalpha"; EVERY_COEFFICIENT for
    all of the vehicle's coefficients); ValueError naming what is wrong when it names none,
    an unknown one or one twice."""
    names = tuple(expanded for name in text.split(",") if name.strip()
                  for expanded in (coefficient_names(vehicle)
                                   if name.strip() == EVERY_COEFFICIENT else (name.strip(),)))
    for name in names:
        model_parameter(name, vehicle)
    if len(set(names)) != len(names) or not names:
        raise ValueError(f"the parameters must name each parameter once, got {list(names)}")
    return names


def changed(aircraft: FlownAircraft, changes: Mapping[str, float]) -> FlownAircraft:
    """The aircraft with each named parameter (model_parameter's, checked) moved by its
    change [its unit]."""
    coefficients = dict(aircraft.coefficients)
    inertia, cg = list(aircraft.inertia_scale), list(aircraft.cg_offset_m)
    fields: dict[str, object] = {}
    bias: dict[str, float] = {}
    for name, change in changes.items():
        parameter = _definition(name)
        step = float(change) * parameter.native_per_unit
        if name not in AIRCRAFT_PARAMETERS:
            coefficients[name] = coefficients.get(name, 1.0) + step
        elif name in INERTIA:
            inertia[INERTIA.index(name)] += step
        elif name in CG:
            cg[CG.index(name)] += step
        elif parameter.is_bias:
            bias[name] = getattr(aircraft.sensor_bias, name) + step
        else:
            fields[name] = getattr(aircraft, name) + step
    return dataclasses.replace(
        aircraft, coefficients=tuple(coefficients.items()), inertia_scale=tuple(inertia),
        cg_offset_m=tuple(cg), sensor_bias=dataclasses.replace(aircraft.sensor_bias, **bias),
        **fields)


def values_of(aircraft: FlownAircraft, names: tuple[str, ...]) -> dict[str, float]:
    """The aircraft's value of each named parameter [its unit]: how it differs from the
    shipped model."""
    coefficients = dict(aircraft.coefficients)
    values = {}
    for name in names:
        if name not in AIRCRAFT_PARAMETERS:
            value = coefficients.get(name, 1.0)
        elif name in INERTIA:
            value = aircraft.inertia_scale[INERTIA.index(name)]
        elif name in CG:
            value = aircraft.cg_offset_m[CG.index(name)]
        elif name in AIR_DATA_BIASES:
            value = getattr(aircraft.sensor_bias, name)
        else:
            value = getattr(aircraft, name)
        parameter = _definition(name)
        nominal = 1.0 if parameter.unit == "%" else 0.0  # a scale is 1 in the model, a bias 0
        values[name] = (value - nominal) / parameter.native_per_unit
    return values
