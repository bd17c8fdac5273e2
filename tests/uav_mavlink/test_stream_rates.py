"""Which streams are too slow for the chain, and the one line that says how to raise each on
ArduPilot and on PX4."""

from __future__ import annotations

import pytest
from uav_mavlink.stream_rates import ARDUPILOT, PX4, advice, slow_messages

REQUIRED_HZ = {"ATTITUDE": 20.0, "GLOBAL_POSITION_INT": 2.0, "VFR_HUD": 1.0}
OPTIONAL_HZ = {"WIND": 0.5, "WIND_COV": 0.5}


@pytest.mark.timeout(10)
def test_arduplanes_one_hertz_defaults_are_too_slow_for_attitude_and_position():
    rates_hz = {"ATTITUDE": 1.0, "GLOBAL_POSITION_INT": 1.0, "VFR_HUD": 1.0, "WIND": 1.0}
    assert slow_messages(rates_hz, REQUIRED_HZ, OPTIONAL_HZ) == ["ATTITUDE",
                                                                 "GLOBAL_POSITION_INT"]


@pytest.mark.timeout(10)
def test_a_required_message_not_sent_is_slow_an_optional_one_is_not():
    rates_hz = {"ATTITUDE": 25.0, "GLOBAL_POSITION_INT": 5.0, "WIND_COV": 0.2}
    assert slow_messages(rates_hz, REQUIRED_HZ, OPTIONAL_HZ) == ["VFR_HUD", "WIND_COV"]


@pytest.mark.timeout(10)
def test_the_advice_names_the_setting_of_each_stack():
    assert advice("ATTITUDE", 1.0, 20.0, ARDUPILOT) == (
        "ATTITUDE arrives at 1.0 Hz; the chain needs 20 Hz: raise SRn_EXTRA1 (MAVm_EXTRA1 "
        "from ArduPilot 4.7, m = n + 1; n the MAVLink channel of this link) to 20 and reboot")
    assert "SRn_RC_CHAN" in advice("SERVO_OUTPUT_RAW", 1.0, 2.0, ARDUPILOT)
    assert "SRn_POSITION" in advice("GLOBAL_POSITION_INT", 1.0, 2.0, ARDUPILOT)
    assert advice("ATTITUDE", 4.0, 20.0, PX4) == (
        "ATTITUDE arrives at 4.0 Hz; the chain needs 20 Hz: add `mavlink stream -d <port> -s "
        "ATTITUDE -r 20` to the SD card's etc/extras.txt, or raise MAV_n_RATE if the link's "
        "data rate throttles it")
