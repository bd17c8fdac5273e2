"""Every STATUSTEXT a ground station gets over the default flight (four wing faults, the
shipped detector: its GLRT, parameter, fast and template tests all alarm), as mavlink_node
makes them from faults/estimate and faults/alarm at the simulator's pace behind ArduPlane
(10 times real time), with mavlink_node's default interval and hold: none empty, none cut,
one onset and one end per alarm, each onset naming the cause faults/alarm gives, never two
texts within the interval."""

from __future__ import annotations

import numpy as np
import pytest
from uav_common.channels import DETECTION_THRESHOLD_PCT, PAPER_FAULT_NAMES
from uav_fault_estimator.chain.offline import fly_on_grid
from uav_fault_estimator.detection.detector import detector_samples
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    self_tuning_detector,
)
from uav_fault_estimator.detection.signatures import CAUSES
from uav_mavlink.ground_reports import (
    HOLD_S,
    TEST_WORDS,
    TEXT_CHARS,
    TEXT_INTERVAL_S,
    UNKNOWN_CAUSE,
    GroundTexts,
    alarm_tests,
)

pytestmark = pytest.mark.timeout(120)
SPEED = 10.0  # flight seconds per wall second: autopilot_node as ArduPlane
POLL_S = 0.1  # the node's text timer [s, wall time]


@pytest.fixture(scope="module")
def flight_texts(default_scenario):
    """(samples, [(wall s, severity, text)]) of the default flight, the estimates the
    seeded faults' values (what mhe_node tracks)."""
    flight = fly_on_grid(default_scenario, 0.2)
    samples = detector_samples(self_tuning_detector(DetectorSettings()),
                               flight.detector_flight)
    texts, said, poll_s = GroundTexts(TEXT_INTERVAL_S, HOLD_S), [], 0.0
    for sample in samples:
        seeded = default_scenario.faults_pct(sample.time_s)
        seeded_pct = [seeded.get(name, 0.0) for name in PAPER_FAULT_NAMES]
        texts.estimates(sample.time_s, PAPER_FAULT_NAMES, seeded_pct)
        texts.alarm(sample.time_s, sample.combined_alarm, sample.cause, alarm_tests(
            sample.alarm, sample.parameter_deviation, sample.parameter_threshold,
            sample.fast_alarm, sample.template_alarm))
        while poll_s <= sample.time_s / SPEED:
            if (text := texts.due(poll_s)) is not None:
                said.append((poll_s, text.severity, text.text))
            poll_s += POLL_S
    while (text := texts.due(poll_s)) is not None or texts.waiting:
        if text is not None:
            said.append((poll_s, text.severity, text.text))
        poll_s += POLL_S
    return samples, said


def test_all_four_tests_alarm_on_the_flight(flight_texts):
    samples, _ = flight_texts
    assert any(s.self_tuning_alarm for s in samples)
    assert any(s.parameter_alarm for s in samples)
    assert any(np.any(s.fast_alarm) for s in samples)
    assert any(np.any(s.template_alarm) for s in samples)


def test_no_text_is_empty_cut_or_sent_within_the_interval(flight_texts):
    _, said = flight_texts
    texts = [text for _, _, text in said]
    assert texts and all(0 < len(text) <= TEXT_CHARS for text in texts)
    causes = (*CAUSES, UNKNOWN_CAUSE)
    for text in texts:
        if text.startswith("UAV FDI alarm: "):
            cause, _, tests = text.removeprefix("UAV FDI alarm: ").partition(" (")
            assert cause in causes and tests.endswith(")"), text
            assert set(tests[:-1].split(",")) <= set(TEST_WORDS), text
        elif text.startswith("UAV FDI alarm over: "):
            cause, _, length = text.removeprefix("UAV FDI alarm over: ").partition(", ")
            assert cause in causes and length.endswith(" s"), text
        else:
            assert text.startswith("UAV FDI: ") and text.endswith(
                f"{DETECTION_THRESHOLD_PCT:g}%"), text
    wall_s = [wall for wall, _, _ in said]
    assert min(np.diff(wall_s)) >= TEXT_INTERVAL_S - 1e-9
    print("\n".join(f"{wall:6.1f} s  {text}" for wall, _, text in said))


def test_each_alarm_is_one_onset_naming_its_cause_and_one_end(flight_texts):
    samples, said = flight_texts
    onsets, ends = [], []
    on, off_s = False, None
    for sample in samples:  # the alarms as a pilot should hear of them
        if sample.combined_alarm and not on:
            on, off_s = True, None
            onsets.append(sample.cause or UNKNOWN_CAUSE)
        elif sample.combined_alarm:
            off_s = None
        elif on and off_s is None:
            off_s = sample.time_s
        elif on and sample.time_s - off_s >= HOLD_S:
            on = False
            ends.append(sample.time_s)
    alarm_texts = [text for _, _, text in said if text.startswith("UAV FDI alarm")]
    told = [text.removeprefix("UAV FDI alarm: ").partition(" (")[0]
            for text in alarm_texts if text.startswith("UAV FDI alarm: ")]
    assert told == onsets and len(onsets) >= 1
    assert len(alarm_texts) == len(onsets) + len(ends)
    # onsets and ends alternate
    assert all(text.startswith("UAV FDI alarm: ") == (k % 2 == 0)
               for k, text in enumerate(alarm_texts)), alarm_texts
