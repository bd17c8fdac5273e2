"""Scenario files (docs/design.md schema): load, check every key, and fail with one clear message.

A scenario names the flight (start, waypoints, duration), the vehicle flown and modelled
(uav_aircraft.vehicles), the wind and turbulence, the
sensors on board, how the flown aircraft differs from the model (uav_aircraft.flown_aircraft),
the faults seeded into the aircraft, the system-identification manoeuvres the autopilot
flies (uav_sim.manoeuvres) and the sensor dropouts of the state and air-data
streams. Loading is
strict: an unknown or missing key, a wrong type or an impossible value stops with a
ScenarioError naming the file and the key, before anything starts.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft, read_aircraft
from uav_aircraft.vehicles import (
    DEFAULT_VEHICLE,
    VEHICLE_FILE,
    VehicleError,
    check_vehicle_name,
    load_vehicle,
)
from uav_common.channels import (
    ACTUATOR_FAULT_NAMES,
    AIR_DATA_CHANNELS,
    DROPOUT_CHANNELS,
    FAULT_NAMES,
    STUCK_SURFACE_FAULT_NAMES,
)
from uav_common.strict_yaml import FileKind, Reader, is_number, load_yaml

from uav_sim.manoeuvres import (
    AXES,
    AXIS_LEVELS,
    KINDS,
    MAX_MAGNITUDE,
    MAX_SWEEP_HZ,
    SWEEPS,
    Manoeuvre,
)
from uav_sim.mpc_guidance import MpcSettings
from uav_sim.paths import scenarios_dir

# from_wind: the paper's von Karman turbulence from the background wind (uav_sim.turbulence);
# the others: JSBSim's MIL-HDBK-1797 presets (uav_sim.wind).
TURBULENCE_LEVELS = ("from_wind", "none", "light", "moderate", "severe")
DEFAULT_SCENARIO = "default.yaml"
# Refused before parsing: the shipped scenarios are 0.8-1.5 kB, and 64 KiB still holds some
# 2000 hand-written waypoints with comments. PyYAML's pure-Python parser takes 200-250 bytes
# of memory and about 10 us per byte of a waypoint list (measured: 0.8 MiB, 10 s and 210 MB;
# 37 MB, 5 min and 7.7 GB), so a 64 KiB file parses in under a second and 20 MB.
MAX_SCENARIO_BYTES = 64 * 1024
# A 300 s flight at 25 m/s covers 7.5 km: a thousand waypoints are legs of 7.5 m, already
# shorter than the guidance can turn onto. More is a generated file, not a flight plan.
MAX_WAYPOINTS = 1000


class ScenarioError(ValueError):
    """A scenario file that cannot be flown; the message names the file and the key."""


SCENARIO_FILE = FileKind("scenario", ScenarioError, MAX_SCENARIO_BYTES,
                         "the shipped ones are under 2 kB")


@dataclass(frozen=True)
class InitialCondition:
    latitude_deg: float
    longitude_deg: float
    altitude_m: float
    airspeed_mps: float
    heading_deg: float


@dataclass(frozen=True)
class Wind:
    north_mps: float
    east_mps: float
    down_mps: float
    turbulence: str
    filter_time_constant_s: float


GUIDANCE_METHODS = ("vector_field", "mpc")


@dataclass(frozen=True)
class Guidance:
    """How the autopilot flies the waypoints: method (GUIDANCE_METHODS: the course vector
    field, guidance.py, or the paper's MPC yaw-rate guidance, mpc_guidance.py) and, for
    mpc, its settings. The vector field by default: the MPC tracks the route closer, but
    the estimator, tuned on the field's flights, keeps less margin to its threshold on the
    MPC's (docs/simulator.md)."""

    method: str = "vector_field"
    mpc: MpcSettings = field(default_factory=MpcSettings)


@dataclass(frozen=True)
class SensorSuite:
    """What the aircraft carries: air data (a pitot's airspeed, and the angle of attack and
    sideslip of flow-angle vanes where `vanes`) or none, and datasheet-typical sensor noise
    (uav_sim.sensors) or ideal sensors. A pitot without vanes is what ArduPlane and PX4
    aircraft carry, and what their MAVLink link gives: the flow angles NaN. `vanes` means
    nothing without air data; a scenario file's `vanes` defaults to its `air_data`."""

    air_data: bool = True
    noise: bool = True
    vanes: bool = True


@dataclass(frozen=True)
class SeededFault:
    """A fault ramping linearly from 0 at start_s to magnitude_pct at start_s + ramp_s; for
    an actuator fault (ACTUATOR_FAULT_NAMES) a step to 100 %, a stuck surface's output pinned
    at position (-1..1, a command's scale) from start_s on."""

    name: str
    start_s: float
    ramp_s: float
    magnitude_pct: float
    position: float = 0.0

    def value_pct(self, time_s: float) -> float:
        if time_s < self.start_s:
            return 0.0
        if self.ramp_s <= 0.0 or time_s >= self.start_s + self.ramp_s:
            return self.magnitude_pct
        return self.magnitude_pct * (time_s - self.start_s) / self.ramp_s


@dataclass(frozen=True)
class SensorDropout:
    """A state or air-data channel missing (NaN) for start_s <= t < end_s."""

    channel: str
    start_s: float
    end_s: float

    def active(self, time_s: float) -> bool:
        return self.start_s <= time_s < self.end_s


@dataclass(frozen=True)
class SetpointChange:
    """From start_s on, the autopilot holds this airspeed [m/s] and altitude [m] (None:
    the one it held before): speed steps, climbs and descents, which separate in a model
    calibration what steady level flight ties together (thrust against drag and mass)."""

    start_s: float
    airspeed_mps: float | None = None
    altitude_m: float | None = None


@dataclass(frozen=True)
class Scenario:
    name: str
    duration_s: float
    seed: int
    initial: InitialCondition
    waypoints_ne_m: tuple[tuple[float, float], ...]
    wind: Wind
    sensors: SensorSuite = SensorSuite()
    guidance: Guidance = Guidance()
    vehicle: str = DEFAULT_VEHICLE
    aircraft: FlownAircraft = NOMINAL
    faults: tuple[SeededFault, ...] = ()
    sensor_dropouts: tuple[SensorDropout, ...] = ()
    setpoints: tuple[SetpointChange, ...] = ()
    manoeuvres: tuple[Manoeuvre, ...] = ()
    estimator: dict[str, Any] = field(default_factory=dict)
    path: Path | None = None

    def __post_init__(self) -> None:
        # in start order once, not at each of commanded()'s 120 Hz calls
        object.__setattr__(self, "setpoints",
                           tuple(sorted(self.setpoints, key=lambda change: change.start_s)))

    def faults_pct(self, time_s: float) -> dict[str, float]:
        """Seeded value [%] of every fault name at time_s (several entries of a name add)."""
        values = dict.fromkeys(FAULT_NAMES, 0.0)
        for fault in self.faults:
            values[fault.name] += fault.value_pct(time_s)
        return values

    def dropped_channels(self, time_s: float) -> set[str]:
        return {dropout.channel for dropout in self.sensor_dropouts if dropout.active(time_s)}

    def commanded(self, time_s: float) -> tuple[float, float]:
        """The autopilot's airspeed [m/s] and altitude [m] at time_s: the initial ones,
        changed by each setpoint change begun by then, in time order."""
        airspeed_mps, altitude_m = self.initial.airspeed_mps, self.initial.altitude_m
        for change in self.setpoints:
            if change.start_s > time_s:
                break
            if change.airspeed_mps is not None:
                airspeed_mps = change.airspeed_mps
            if change.altitude_m is not None:
                altitude_m = change.altitude_m
        return airspeed_mps, altitude_m


def default_scenario_path() -> Path:
    return scenarios_dir() / DEFAULT_SCENARIO


def vehicle_scenario_path(vehicle: str, kind: str) -> Path:
    """The shipped scenario file of the vehicle's `kind` flight ("default": faults seeded,
    "fault_free": the same flight without them), as its vehicle.yaml names it; ScenarioError
    (one line) when that file is not among the shipped scenarios."""
    named = load_vehicle(vehicle)
    path = scenarios_dir() / getattr(named, f"{kind}_scenario_file")
    if not path.is_file():
        raise ScenarioError(f"vehicle file {named.folder / VEHICLE_FILE}: its {kind} scenario "
                            f"{path.name} is not in {path.parent}")
    return path


def _initial(reader: Reader) -> InitialCondition:
    names = {"latitude_deg", "longitude_deg", "altitude_m", "airspeed_mps", "heading_deg"}
    reader.check_keys(names)
    return InitialCondition(
        latitude_deg=reader.number("latitude_deg"),
        longitude_deg=reader.number("longitude_deg"),
        altitude_m=reader.number("altitude_m", positive=True),
        airspeed_mps=reader.number("airspeed_mps", positive=True),
        heading_deg=reader.number("heading_deg"),
    )


def _wind(reader: Reader) -> Wind:
    reader.check_keys({"north_mps", "east_mps", "down_mps", "turbulence", "filter_time_constant_s"})
    return Wind(
        north_mps=reader.number("north_mps"),
        east_mps=reader.number("east_mps"),
        down_mps=reader.number("down_mps"),
        turbulence=reader.choice("turbulence", TURBULENCE_LEVELS),
        filter_time_constant_s=reader.number("filter_time_constant_s", positive=True),
    )


def _sensors(reader: Reader) -> SensorSuite:
    reader.check_keys(set(), {"air_data", "noise", "vanes"})
    air_data = reader.flag("air_data", True)
    vanes = reader.flag("vanes", air_data)
    if vanes and not air_data:
        reader.fail("'sensors.vanes' is true but 'sensors.air_data' is false: vanes are air "
                    "data")
    return SensorSuite(air_data=air_data, noise=reader.flag("noise", True), vanes=vanes)


# The guidance block's MPC keys and their ranges (MpcSettings' fields).
_MPC_NUMBERS = {"sample_s": (0.1, 10.0), "cross_track_weight": (0.0, 1e3),
                "course_weight": (0.0, 1e3), "yaw_rate_weight": (1e-6, 1e6),
                "max_yaw_rate_change_radps": (1e-3, 10.0)}


def _guidance(reader: Reader) -> Guidance:
    """guidance: {method: vector_field | mpc, and for mpc optionally sample_s,
    horizon_steps, cross_track_weight, course_weight, yaw_rate_weight,
    max_yaw_rate_change_radps}."""
    data = reader.data
    reader.check_keys({"method"}, set(_MPC_NUMBERS) | {"horizon_steps"})
    method = reader.choice("method", GUIDANCE_METHODS)
    if method != "mpc" and len(data) > 1:
        reader.fail(f"'{reader.key('method')}' is {method}: the MPC settings "
                    f"({', '.join(sorted(set(data) - {'method'}))}) belong to method mpc")
    defaults = MpcSettings()
    settings = {name: reader.number(name, minimum=low, maximum=high)
                for name, (low, high) in _MPC_NUMBERS.items() if name in data}
    if "horizon_steps" in data:
        settings["horizon_steps"] = reader.integer("horizon_steps", 2, 100)
    return Guidance(method, dataclasses.replace(defaults, **settings))


def _vehicle(reader: Reader) -> str:
    """The `vehicle` key: a shipped vehicle's name (uav_aircraft.vehicles)."""
    try:
        return check_vehicle_name(reader.text("vehicle"))
    except VehicleError as error:
        reader.fail(f"'vehicle': {error}")
        raise  # fail() raises; for the type checker


def _waypoints(reader: Reader) -> tuple[tuple[float, float], ...]:
    points = reader.items("waypoints_ne_m")
    if len(points) < 2:
        reader.fail("'waypoints_ne_m' needs at least two [north_m, east_m] points")
    if len(points) > MAX_WAYPOINTS:
        reader.fail(f"'waypoints_ne_m' has {len(points)} points, more than the "
                    f"{MAX_WAYPOINTS} a scenario may have")
    for index, point in enumerate(points):
        if not (isinstance(point, list) and len(point) == 2 and all(map(is_number, point))):
            reader.fail(f"'waypoints_ne_m[{index}]' must be [north_m, east_m], got {point!r}")
    waypoints = tuple((float(north), float(east)) for north, east in points)
    for index, point in enumerate(waypoints):  # the legs close the loop: last to first
        following = (index + 1) % len(waypoints)
        if point == waypoints[following]:
            reader.fail(f"'waypoints_ne_m[{following}]' is the same point as "
                        f"'waypoints_ne_m[{index}]': a leg needs two distinct points")
    return waypoints


ACTUATOR_FAULT_PCT = 100.0  # an actuator fault's seeded value while active


def _fault(reader: Reader) -> SeededFault:
    """A `faults` entry: a model fault's ramp, or an actuator fault's start (and, for a stuck
    surface, its position)."""
    name = reader.choice("name", FAULT_NAMES) if "name" in reader.data else None
    if name in ACTUATOR_FAULT_NAMES:
        reader.check_keys({"name", "start_s"},
                          {"position"} if name in STUCK_SURFACE_FAULT_NAMES else set())
        return SeededFault(name=name, start_s=reader.number("start_s", minimum=0.0), ramp_s=0.0,
                           magnitude_pct=ACTUATOR_FAULT_PCT,
                           position=(reader.number("position", minimum=-1.0, maximum=1.0)
                                     if "position" in reader.data else 0.0))
    reader.check_keys({"name", "start_s", "ramp_s", "magnitude_pct"})
    return SeededFault(
        name=reader.choice("name", FAULT_NAMES),
        start_s=reader.number("start_s", minimum=0.0),
        ramp_s=reader.number("ramp_s", minimum=0.0),
        magnitude_pct=reader.number("magnitude_pct"),
    )


def _faults(reader: Reader) -> tuple[SeededFault, ...]:
    """The `faults` list; an actuator fault at most once (one position per surface)."""
    faults = tuple(_fault(reader.element("faults", index))
                   for index in range(len(reader.items("faults"))))
    names = [fault.name for fault in faults if fault.name in ACTUATOR_FAULT_NAMES]
    for index, fault in enumerate(faults):
        if fault.name in ACTUATOR_FAULT_NAMES and names.count(fault.name) > 1:
            reader.fail(f"'faults[{index}].name': {fault.name} is seeded more than once (an "
                        "actuator fault is one output pinned from its start on)")
    return faults


def _dropout(reader: Reader) -> SensorDropout:
    reader.check_keys({"channel", "start_s", "end_s"})
    dropout = SensorDropout(
        channel=reader.choice("channel", DROPOUT_CHANNELS),
        start_s=reader.number("start_s", minimum=0.0),
        end_s=reader.number("end_s", minimum=0.0),
    )
    if dropout.end_s <= dropout.start_s:
        reader.fail(f"'{reader.key('end_s')}' must be after start_s")
    return dropout


def _setpoint(reader: Reader) -> SetpointChange:
    reader.check_keys({"start_s"}, {"airspeed_mps", "altitude_m"})
    if not {"airspeed_mps", "altitude_m"} & set(reader.data):
        reader.fail(f"'{reader.key('start_s')}': a setpoint change needs airspeed_mps, "
                    "altitude_m or both")
    return SetpointChange(
        start_s=reader.number("start_s", minimum=0.0),
        airspeed_mps=(reader.number("airspeed_mps", positive=True)
                      if "airspeed_mps" in reader.data else None),
        altitude_m=(reader.number("altitude_m", positive=True)
                    if "altitude_m" in reader.data else None),
    )


_SWEEP_KEYS = {"f_start_hz", "f_stop_hz", "duration_s", "fade_in_s", "fade_out_s"}


def _manoeuvre(reader: Reader) -> Manoeuvre:
    """A `manoeuvres` entry (uav_sim.manoeuvres): start_s, kind, axis, level (throttle's
    may be left out: surface), magnitude, and a sweep's band, duration and fades or the
    steps' step_s."""
    data = reader.data
    if data.get("kind") == 3211 and type(data["kind"]) is int:  # YAML reads 3211 unquoted
        data["kind"] = "3211"
    kind = reader.choice("kind", KINDS) if "kind" in data else None
    shape = _SWEEP_KEYS if kind in SWEEPS else {"step_s"}
    reader.check_keys({"start_s", "kind", "axis", "magnitude"} | shape, {"level"})
    axis = reader.choice("axis", AXES)
    level = reader.choice("level", AXIS_LEVELS[axis]) if "level" in data else "surface"
    if "level" not in data and axis != "throttle":
        reader.fail(f"missing required key '{reader.key('level')}' (one of "
                    f"{', '.join(AXIS_LEVELS[axis])})")
    numbers = {name: reader.number(name, positive=True) for name in shape - {"fade_in_s",
                                                                           "fade_out_s"}}
    manoeuvre = Manoeuvre(
        start_s=reader.number("start_s", minimum=0.0), kind=kind, axis=axis, level=level,
        magnitude=reader.number("magnitude", positive=True, maximum=MAX_MAGNITUDE[level]),
        **numbers, **{name: reader.number(name, minimum=0.0)
                      for name in ("fade_in_s", "fade_out_s") if name in shape})
    if kind in SWEEPS:
        if not manoeuvre.f_start_hz <= manoeuvre.f_stop_hz <= MAX_SWEEP_HZ:
            reader.fail(f"'{reader.key('f_stop_hz')}' must be from f_start_hz to "
                        f"{MAX_SWEEP_HZ:g} Hz, got {manoeuvre.f_stop_hz!r}")
        if manoeuvre.fade_in_s + manoeuvre.fade_out_s > manoeuvre.duration_s:
            reader.fail(f"'{reader.key('fade_in_s')}' and fade_out_s together exceed "
                        "duration_s")
    return manoeuvre


def _manoeuvres(reader: Reader) -> tuple[Manoeuvre, ...]:
    """The `manoeuvres` list, in start order; two on one axis at one time are refused."""
    manoeuvres = [_manoeuvre(reader.element("manoeuvres", index))
                  for index in range(len(reader.items("manoeuvres")))]
    for index, later in enumerate(manoeuvres):
        for earlier_index, earlier in enumerate(manoeuvres[:index]):
            if (earlier.axis == later.axis and earlier.start_s < later.end_s
                    and later.start_s < earlier.end_s):
                reader.fail(f"'manoeuvres[{index}]' overlaps 'manoeuvres[{earlier_index}]' on "
                            f"the {later.axis} axis ({earlier.start_s:g}-{earlier.end_s:g} s)")
    return tuple(sorted(manoeuvres, key=lambda manoeuvre: manoeuvre.start_s))


def load_scenario(path: str | Path) -> Scenario:
    """Read and check a scenario file; raises ScenarioError with one clear message."""
    path = Path(path)
    reader = load_yaml(SCENARIO_FILE, path)
    data = reader.data
    reader.check_keys(
        {"name", "duration_s", "seed", "initial", "waypoints_ne_m", "wind"},
        {"sensors", "guidance", "vehicle", "aircraft", "faults", "sensor_dropouts",
         "setpoints", "manoeuvres", "estimator"},
    )
    if reader.text("name") in (".", "..") or any(c in data["name"] for c in "/\\\0"):
        # demo.sh's default output folder is runs/<name>/
        reader.fail(f"'name' must be usable as a folder name (no '/', '\\', NUL, not '.' "
                    f"or '..'), got {data['name']!r}")
    seed = data["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        reader.fail(f"'seed' must be a non-negative integer, got {seed!r}")
    estimator = data.get("estimator") or {}
    if not isinstance(estimator, dict):
        reader.fail("'estimator' must be a mapping of estimator parameters")
    sensors = _sensors(reader.child("sensors")) if "sensors" in data else SensorSuite()
    vehicle = _vehicle(reader) if "vehicle" in data else DEFAULT_VEHICLE
    dropouts = tuple(
        _dropout(reader.element("sensor_dropouts", index))
        for index in range(len(reader.items("sensor_dropouts")))
    )
    for index, dropout in enumerate(dropouts):
        if dropout.channel in AIR_DATA_CHANNELS and not sensors.air_data:
            reader.fail(f"'sensor_dropouts[{index}].channel' is {dropout.channel!r}, an air-data "
                        "channel, but sensors.air_data is false")
    return Scenario(
        name=data["name"],
        duration_s=reader.number("duration_s", positive=True),
        seed=seed,
        initial=_initial(reader.child("initial")),
        waypoints_ne_m=_waypoints(reader),
        wind=_wind(reader.child("wind")),
        sensors=sensors,
        guidance=_guidance(reader.child("guidance")) if "guidance" in data else Guidance(),
        vehicle=vehicle,
        aircraft=(read_aircraft(reader.child("aircraft"), load_vehicle(vehicle))
                  if "aircraft" in data else NOMINAL),
        faults=_faults(reader),
        sensor_dropouts=dropouts,
        setpoints=tuple(_setpoint(reader.element("setpoints", index))
                        for index in range(len(reader.items("setpoints")))),
        manoeuvres=_manoeuvres(reader),
        estimator=dict(estimator),
        path=path,
    )
