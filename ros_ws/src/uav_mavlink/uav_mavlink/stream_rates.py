"""Whether the autopilot streams each message the chain reads often enough, and if not, the
one line that says which setting raises it.

ArduPlane streams its groups at 1 Hz unless told otherwise (its SRn_* parameters: n the
MAVLink channel of the link, renamed MAV(n+1)_* in ArduPilot 4.7; a reboot applies them);
PX4's onboard mode streams ATTITUDE at 100 Hz and most others at 10-50 Hz, and a slow one is
raised with its `mavlink stream` command (in the SD card's etc/extras.txt to keep it) or, when
the link's data rate throttles every stream, with MAV_n_RATE. docs/onboard.md (Stream rates)
gives the groups and their defaults.
"""

from __future__ import annotations

from collections.abc import Mapping

# ArduPlane's stream group (SRn_<group>) of each message the chain reads.
ARDUPILOT_GROUPS = {
    "ATTITUDE": "EXTRA1", "RPM": "EXTRA1",
    "GLOBAL_POSITION_INT": "POSITION", "LOCAL_POSITION_NED": "POSITION",
    "VFR_HUD": "EXTRA2", "SERVO_OUTPUT_RAW": "RC_CHAN",
    "NAV_CONTROLLER_OUTPUT": "EXT_STAT", "WIND": "EXTRA3",
}
ARDUPILOT, PX4 = "ArduPilot", "PX4"


def advice(message: str, measured_hz: float, needed_hz: float, autopilot: str) -> str:
    """One line: the message's measured and needed rates, and how to raise it on this
    autopilot (ArduPilot or PX4)."""
    said = f"{message} arrives at {measured_hz:.1f} Hz; the chain needs {needed_hz:g} Hz"
    if autopilot == ARDUPILOT and message in ARDUPILOT_GROUPS:
        group = ARDUPILOT_GROUPS[message]
        return (f"{said}: raise SRn_{group} (MAVm_{group} from ArduPilot 4.7, m = n + 1; n "
                f"the MAVLink channel of this link) to {needed_hz:g} and reboot")
    if autopilot == PX4:
        return (f"{said}: add `mavlink stream -d <port> -s {message} -r {needed_hz:g}` to the "
                "SD card's etc/extras.txt, or raise MAV_n_RATE if the link's data rate "
                "throttles it")
    return f"{said}: raise its stream rate on the autopilot"


def slow_messages(rates_hz: Mapping[str, float], required_hz: Mapping[str, float],
                  optional_hz: Mapping[str, float], tolerance: float = 0.8) -> list[str]:
    """The messages streamed below tolerance times their needed rate [Hz]: a required one
    also when it does not arrive at all, an optional one (an alternative, or what the chain
    does without) only when it arrives."""
    slow = [message for message, needed in required_hz.items()
            if rates_hz.get(message, 0.0) < tolerance * needed]
    return slow + [message for message, needed in optional_hz.items()
                   if 0.0 < rates_hz.get(message, 0.0) < tolerance * needed]
