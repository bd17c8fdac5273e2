"""Names, order and units of the state, control and fault channels.

The message field of a channel is ``<channel>_<unit>`` (``pitch_rate`` -> ``pitch_rate_radps``);
a unit of "" means a dimensionless field named as the channel.
"""

# The paper's p, v and zeta (embedded-estimation paper, eq. 1 and section IV).
STATE_CHANNELS: tuple[str, ...] = (
    "latitude",
    "longitude",
    "altitude",
    "roll",
    "pitch",
    "yaw",
    "velocity_north",
    "velocity_east",
    "velocity_down",
    "roll_rate",
    "pitch_rate",
    "yaw_rate",
    "fuel_mass",
    "engine_speed",
)
STATE_UNITS: tuple[str, ...] = (
    "rad",
    "rad",
    "m",
    "rad",
    "rad",
    "rad",
    "mps",
    "mps",
    "mps",
    "radps",
    "radps",
    "radps",
    "kg",
    "rpm",
)

# Air data (pitot-static airspeed, alpha and sideslip vanes): message AirData, whose fields
# are AIR_DATA_FIELDS (the airspeed field says that it is the true airspeed).
VANE_CHANNELS: tuple[str, ...] = ("angle_of_attack", "sideslip")  # a flow-angle vane's
AIR_DATA_CHANNELS: tuple[str, ...] = ("airspeed", *VANE_CHANNELS)
AIRSPEED_INDEX = AIR_DATA_CHANNELS.index("airspeed")  # the airspeed's index in an air-data vector
AIR_DATA_FIELDS: tuple[str, ...] = ("true_airspeed_mps", "angle_of_attack_rad", "sideslip_rad")
# Channels a scenario's sensor_dropouts may name.
DROPOUT_CHANNELS: tuple[str, ...] = STATE_CHANNELS + AIR_DATA_CHANNELS

# The autopilot's setpoints (message AutopilotSetpoints, whose fields these are): commanded
# roll and pitch [rad], commanded vertical velocity, down [m/s].
SETPOINT_FIELDS: tuple[str, ...] = ("roll_rad", "pitch_rad", "velocity_down_mps")

CONTROL_CHANNELS: tuple[str, ...] = (
    "flap",
    "elevator",
    "aileron",
    "rudder",
    "throttle",
    "mixture",
    "ignition",
)
CONTROL_UNITS: tuple[str, ...] = ("rad", "rad", "rad", "rad", "", "", "")
# The controls no autopilot's link or log carries, by CONTROL_CHANNELS index: the flap
# retracted (none mapped), mixture and ignition 1 (the engine runs).
UNREPORTED_CONTROLS: dict[int, float] = {CONTROL_CHANNELS.index("flap"): 0.0,
                                         CONTROL_CHANNELS.index("mixture"): 1.0,
                                         CONTROL_CHANNELS.index("ignition"): 1.0}

# Percent change of the named coefficient (docs/design.md); the first four are the paper's.
# What the estimator's model copies can carry.
MODEL_FAULT_NAMES: tuple[str, ...] = (
    "right_wing_lift_loss",
    "right_wing_drag_increase",
    "left_wing_lift_loss",
    "left_wing_drag_increase",
    "propulsion_loss",
    "pitch_moment",
    "aileron_effectiveness_loss",
)
# ALFA's failures: a surface's output pinned at the fault's position, or the engine cut;
# seeded as 100 % while active (docs/design.md).
STUCK_SURFACE_FAULT_NAMES: tuple[str, ...] = (
    "aileron_stuck",
    "left_aileron_stuck",
    "right_aileron_stuck",
    "elevator_stuck",
    "rudder_stuck",
)
ACTUATOR_FAULT_NAMES: tuple[str, ...] = (*STUCK_SURFACE_FAULT_NAMES, "engine_cut")
# Every fault a scenario can seed, in the order of the seeded fault vector.
FAULT_NAMES: tuple[str, ...] = MODEL_FAULT_NAMES + ACTUATOR_FAULT_NAMES
PAPER_FAULT_NAMES: tuple[str, ...] = FAULT_NAMES[:4]
# A fault estimate at or above this is reported [%] (metrics.json's detection_threshold_pct;
# what mavlink_node tells a ground station).
DETECTION_THRESHOLD_PCT = 2.0


def state_indices(*channels: str) -> list[int]:
    """Where the named channels are in a state array (STATE_CHANNELS order), in the order
    given."""
    return [STATE_CHANNELS.index(channel) for channel in channels]


def field_name(channel: str, unit: str) -> str:
    """Message field name of a channel: ``<channel>_<unit>``, or the channel alone."""
    return f"{channel}_{unit}" if unit else channel
