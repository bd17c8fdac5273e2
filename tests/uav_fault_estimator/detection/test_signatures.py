"""Naming an alarm's cause by learned failure signatures: the nearest neighbours' vote, the
file's round trip and refusals, and the detector's alarms naming the signature's cause."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml
from test_self_tuning import small_calibration
from uav_common.channels import FAULT_NAMES
from uav_fault_estimator.detection.calibration_file import shipped_calibration_path
from uav_fault_estimator.detection.detector import SelfTuningDetector
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    detector_calibration,
    learned_failures,
)
from uav_fault_estimator.detection.signatures import (
    CAUSE_OF_FAULT,
    CAUSES,
    learned_signatures,
    read_signatures,
    signature_features,
    signatures_to_dict,
)

CHANNELS = ("roll", "pitch", "yaw")
# A wing that loses lift rolls one way; an aileron stuck rolls either way; the engine
# pitches.
EXAMPLES = [("right_wing_lift", [3.0, 0.1, 0.0]), ("right_wing_lift", [2.0, -0.2, 0.1]),
            ("left_wing_lift", [-3.0, 0.1, 0.0]), ("left_wing_lift", [-2.5, 0.0, -0.1]),
            ("aileron", [2.0, 0.0, 2.0]), ("aileron", [-2.0, 0.0, -2.0]),
            ("engine", [0.0, -4.0, 0.0]), ("engine", [0.2, -3.0, 0.0])]


@pytest.mark.timeout(30)
def test_every_seeded_fault_names_a_cause():
    assert set(CAUSE_OF_FAULT) == set(FAULT_NAMES)
    assert set(CAUSE_OF_FAULT.values()) == set(CAUSES)


@pytest.mark.timeout(30)
def test_a_change_is_named_by_its_nearest_signatures_whatever_its_size():
    nearest = learned_signatures(CHANNELS, EXAMPLES, neighbours=1)
    assert nearest.cause(np.array([30.0, 0.0, 0.0])) == "right_wing_lift"
    assert nearest.cause(np.array([-0.3, 0.0, 0.0])) == "left_wing_lift"
    assert nearest.cause(np.array([-1.0, 0.0, -1.2])) == "aileron"
    assert nearest.cause(np.array([0.0, -9.0, 0.1])) == "engine"
    # a change with no direction names nothing
    assert nearest.cause(np.zeros(3)) == nearest.cause(np.array([np.nan, 1.0, 0.0])) == ""
    # three neighbours: two engine signatures outvote the nearest (a right wing's)
    voters = [("right_wing_lift", [1.0, 0.0, 0.0]), ("engine", [0.6, 0.8, 0.0]),
              ("engine", [0.6, -0.8, 0.0])]
    change = np.array([2.0, 0.0, 0.0])
    assert learned_signatures(CHANNELS, voters, neighbours=1).cause(change) == "right_wing_lift"
    assert learned_signatures(CHANNELS, voters, neighbours=3).cause(change) == "engine"
    # a tie goes to the nearest
    assert learned_signatures(CHANNELS, voters, neighbours=2).cause(change) == "right_wing_lift"


@pytest.mark.timeout(30)
def test_signatures_round_trip_through_their_file_and_a_wrong_one_is_refused(tmp_path):
    learned = learned_signatures(CHANNELS, EXAMPLES, 3, "eight made-up failures")
    path = tmp_path / "signatures.yaml"
    path.write_text(yaml.safe_dump(signatures_to_dict(learned)))
    read = read_signatures(path)
    assert (read.features, read.causes, read.neighbours, read.learned_from) == (
        learned.features, learned.causes, 3, "eight made-up failures")
    np.testing.assert_allclose(read.directions, learned.directions, atol=1e-6)
    assert np.allclose(np.linalg.norm(read.directions, axis=1), 1.0)
    calibration = tmp_path / "calibration.yaml"
    calibration.write_text(yaml.safe_dump({"airframe": "x", "channels": {}}))
    with pytest.raises(ValueError, match=r"^signatures file .*calibration.yaml: .*failure "
                                         r"signatures file"):
        read_signatures(calibration)
    data = signatures_to_dict(learned)
    data["signatures"][0]["cause"] = "left_wing_flap"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match=r"signature of 'left_wing_flap'.*expected one of"):
        read_signatures(path)
    with pytest.raises(ValueError, match="2 signatures for 3 neighbours"):
        learned_signatures(CHANNELS, EXAMPLES[:2], 3)


@pytest.mark.timeout(30)
def test_the_detector_names_an_alarm_by_signatures_learned_with_its_calibration():
    """The fast test's step on the roll channel (test_self_tuning's), its change positive:
    named by the signatures (a right wing's lift), not by the roll channel's kind."""
    calibration = small_calibration()
    features = signature_features(calibration)
    assert features == ("roll", "pitch", "yaw", "roll.a_pa", "roll.b_pa", "pitch.a_qe",
                        "pitch.b_qe", "yaw.a_ra", "yaw.b_ra", "yaw.c_ra")
    roll_up = np.eye(len(features))[0]
    signatures = learned_signatures(features, [("right_wing_lift", roll_up),
                                               ("left_wing_lift", -roll_up)], neighbours=1)
    detector = SelfTuningDetector(calibration, 0.01, 2.0, signatures)
    rng = np.random.default_rng(4)
    state, controls = np.zeros(14), np.zeros(7)
    causes = []
    for k in range(1, 300):
        time_s = 0.2 * k
        controls[2] = rng.normal(0.0, 0.1)  # aileron
        state[9] = (0.5 * controls[2] + 0.5 + (1.0 if time_s >= 40.0 else 0.0)
                    + rng.normal(0.0, 0.1))  # roll rate
        state[11] = 0.5 * controls[2] + 0.5 * state[11] + 0.5  # yaw rate, as calibrated
        sample = detector.update(time_s, state, controls)
        if sample is not None and sample.combined_alarm:
            assert sample.fast_change[0] > 0.0 and sample.parameter_deviations.shape == (7,)
            causes.append(sample.cause)
    assert causes and set(causes) == {"right_wing_lift"}
    other = learned_signatures(features[:3], EXAMPLES, neighbours=1)
    with pytest.raises(ValueError, match=r"signatures over roll, pitch, yaw: the calibration's "
                                         r"are over roll, pitch, yaw, roll\.a_pa"):
        SelfTuningDetector(calibration, 0.01, 2.0, other)


@pytest.mark.timeout(30)
def test_the_shipped_signatures_go_with_the_shipped_calibration_and_a_named_file_must_fit(
        tmp_path):
    shipped = DetectorSettings(vehicle="carbon_z")
    calibration = detector_calibration(shipped)
    signatures, _ = learned_failures(shipped, calibration)
    assert signatures is not None and signatures.features == signature_features(calibration)
    assert set(signatures.causes) <= set(CAUSES) and signatures.neighbours == 3
    own = dataclasses.replace(shipped, calibration_file=str(shipped_calibration_path("carbon_z")))
    # a calibration named: none unless named
    assert learned_failures(own, calibration) == (None, None)
    path = tmp_path / "signatures.yaml"
    path.write_text(yaml.safe_dump(signatures_to_dict(
        learned_signatures(CHANNELS, EXAMPLES, neighbours=1))))
    with pytest.raises(ValueError, match=r"signatures file .* is over roll, pitch, yaw, the "
                                         r"calibration's signatures over roll_tracking, "):
        learned_failures(dataclasses.replace(own, signatures_file=str(path)), calibration)
