"""The autopilot's link as mavlink_node judges it: a loss is one line when it starts and one
when it ends, with its length; a heartbeat late while the streams arrive is no loss; a stream
is judged slow only on the time the link was alive, so a relay stopped and restarted gives
no stream-rate advice, and a truly slow stream gives its advice once."""

from __future__ import annotations

import pytest
from uav_mavlink.link_watch import LinkWatch
from uav_mavlink.stream_rates import ARDUPILOT

pytestmark = pytest.mark.timeout(10)
REQUIRED_HZ = {"ATTITUDE": 20.0, "GLOBAL_POSITION_INT": 2.0}
OPTIONAL_HZ = {"WIND": 0.5}


def fly(watch: LinkWatch, start_s: float, end_s: float, attitude_hz: float = 25.0,
        heartbeat_period_s: float = 1.0, check_period_s: float = 0.1) -> list[str]:
    """ArduPlane's streams from start_s to end_s [s] (ATTITUDE at attitude_hz, position at
    10 Hz, a heartbeat each heartbeat_period_s), the watch checked every check_period_s;
    the lines said."""
    events = sorted(
        [(start_s + k / attitude_hz, "ATTITUDE")
         for k in range(round((end_s - start_s) * attitude_hz))]
        + [(start_s + k / 10.0, "GLOBAL_POSITION_INT")
           for k in range(round((end_s - start_s) * 10.0))]
        + [(start_s + k * heartbeat_period_s, "HEARTBEAT")
           for k in range(int((end_s - start_s) / heartbeat_period_s))])
    return quiet(watch, start_s, end_s, check_period_s, events)


def quiet(watch: LinkWatch, start_s: float, end_s: float, check_period_s: float = 0.1,
          events: list[tuple[float, str]] = ()) -> list[str]:
    """The events [(s, type)], each heard at the first check at or after it (as the node
    reads its socket), the watch checked every check_period_s from start_s to end_s [s];
    the lines said."""
    lines, events = [], list(events)
    check_s = start_s
    while check_s < end_s:
        while events and events[0][0] <= check_s:
            watch.heard(check_s, events.pop(0)[1])
        lines += [line.text for line in watch.check(check_s, 1, ARDUPILOT)]
        check_s += check_period_s
    return lines


def new_watch() -> LinkWatch:
    return LinkWatch(lost_after_s=3.0, rate_window_s=5.0, required_hz=REQUIRED_HZ,
                     optional_hz=OPTIONAL_HZ)


def test_a_relay_stopped_for_ten_seconds_is_one_loss_and_one_return_and_no_advice():
    watch = new_watch()
    lines = fly(watch, 0.0, 14.3)  # a window judged at 5 and 10 s, the third cut off
    lines += quiet(watch, 14.3, 24.3)  # the relay stopped
    lines += fly(watch, 24.3, 40.0)
    assert lines == [
        "link lost: nothing from system 1 for 3 s; its streams are missing until it "
        "returns (stream rates are not judged meanwhile)",
        "link back after 10.0 s of silence"], lines
    assert watch.losses == 1 and watch.alive and watch.slow == []
    assert watch.rates_hz["ATTITUDE"] == pytest.approx(25.0, rel=0.05)


def test_a_late_heartbeat_while_the_streams_arrive_is_no_loss():
    watch = new_watch()
    lines = fly(watch, 0.0, 30.0, heartbeat_period_s=4.5)
    assert lines == [] and watch.losses == 0


def test_a_node_held_up_reads_a_burst_not_a_silence():
    watch = new_watch()
    lines = fly(watch, 0.0, 30.0, check_period_s=2.5)  # checked only every 2.5 s
    assert lines == [] and watch.losses == 0 and watch.slow == []


def test_a_truly_slow_stream_is_said_once_with_its_setting():
    watch = new_watch()
    lines = fly(watch, 0.0, 30.0, attitude_hz=4.0)
    assert len(lines) == 1 and lines[0].startswith("ATTITUDE arrives at 4."), lines
    assert lines[0].endswith("the chain needs 20 Hz: raise SRn_EXTRA1 (MAVm_EXTRA1 from "
                             "ArduPilot 4.7, m = n + 1; n the MAVLink channel of this "
                             "link) to 20 and reboot"), lines
    assert watch.slow == ["ATTITUDE"]
    assert watch.rates_hz["ATTITUDE"] == pytest.approx(4.0, rel=0.1)


def test_a_required_stream_that_stops_while_the_link_lives_is_advised_at_zero():
    watch = new_watch()
    heard = [(k / 10.0, "GLOBAL_POSITION_INT") for k in range(100)]
    lines = quiet(watch, 0.0, 10.0, events=heard)
    assert lines == [
        "ATTITUDE arrives at 0.0 Hz; the chain needs 20 Hz: raise SRn_EXTRA1 (MAVm_EXTRA1 "
        "from ArduPilot 4.7, m = n + 1; n the MAVLink channel of this link) to 20 and "
        "reboot"], lines
