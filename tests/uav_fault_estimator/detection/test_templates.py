"""The template test: whitening, the matched filter, its sample-by-sample form, thresholds
for a rate per hour from block maxima, learning which templates to keep, the file, and the
detector's alarms and causes from it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml
from test_self_tuning import small_calibration
from uav_fault_estimator.detection.calibration_file import shipped_calibration_path
from uav_fault_estimator.detection.change_detection import Weibull
from uav_fault_estimator.detection.detector import SelfTuningDetector
from uav_fault_estimator.detection.detector_settings import (
    DetectorSettings,
    detector_calibration,
    learned_failures,
)
from uav_fault_estimator.detection.signatures import CAUSES
from uav_fault_estimator.detection.templates import (
    TEMPLATES_KEY,
    WHITENING_ORDER,
    FailureTemplates,
    LearningFlight,
    TemplateTest,
    learn_templates,
    matched_filter,
    maxima_distribution,
    read_templates,
    templates_to_dict,
    whitened,
    whitening_filters,
)

PERIOD_S = 0.2
REFERENCE = 150


def autoregressive(rng: np.random.Generator, samples: int, generators: int,
                   pole: float = 0.8, spread: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Residuals r[k] = pole r[k-1] + e[k] (K, G) and their innovations e."""
    e = rng.normal(0.0, spread, (samples, generators))
    r = np.zeros_like(e)
    for k in range(1, samples):
        r[k] = pole * r[k - 1] + e[k]
    return r, e


@pytest.mark.timeout(30)
def test_the_whitening_filter_of_an_autoregressive_residual_leaves_its_innovations():
    """r[k] = 0.8 r[k-1] + e[k] on three flights: the fitted filter is [1, -0.8, 0, 0, 0] to
    within sampling, and the whitened residuals are e again after the filter's first
    samples."""
    rng = np.random.default_rng(11)
    flights = [autoregressive(rng, 3000, 1) for _ in range(3)]
    filters = whitening_filters([r for r, _ in flights])
    assert filters.shape == (1, WHITENING_ORDER + 1)
    assert filters[0] == pytest.approx([1.0, -0.8, 0.0, 0.0, 0.0], abs=0.03)
    residuals, innovations = flights[0]
    assert np.std(whitened(residuals, filters)[10:] - innovations[10:]) < 0.01


@pytest.mark.timeout(30)
def test_the_matched_filter_slides_as_a_unit_normal_on_white_residuals():
    """On white residuals of spread 0.3 and a shape whose samples sum to zero per generator
    (so the reference mean takes nothing away), the slid statistic is N(0, 1); a copy of the
    shape added at one place raises it there by the shape's norm."""
    rng = np.random.default_rng(5)
    residuals = rng.normal(0.0, 0.3, (20_000, 2))
    shape = np.tile([[0.2, -0.1], [-0.2, 0.1]], (10, 1))  # (20, 2), zero sum
    spread = np.array([0.3, 0.3])
    statistic = matched_filter(shape, spread, residuals, REFERENCE)
    assert np.isnan(statistic[:168]).all() and np.isfinite(statistic[169:]).all()
    assert abs(np.mean(statistic[169:])) < 0.05 and np.std(statistic[169:]) == pytest.approx(
        1.0, abs=0.03)
    with_signal = residuals.copy()
    with_signal[1000:1020] += shape
    raised = matched_filter(shape, spread, with_signal, REFERENCE)[1019] - statistic[1019]
    assert raised == pytest.approx(math.sqrt(np.sum((shape / spread) ** 2)), rel=1e-9)


UNIT_MAXIMA = Weibull(1.0, 2.0)


def two_templates(rng: np.random.Generator, maxima: Weibull = UNIT_MAXIMA) -> FailureTemplates:
    return FailureTemplates(
        whitening=np.array([[1.0, -0.8, 0.0, 0.0, 0.0], [1.0, -0.5, 0.1, 0.0, 0.0]]),
        spread=np.array([0.1, 0.2]), reference=REFERENCE, kinds=("engine_cut", "elevator_stuck"),
        causes=("engine", "elevator"), shapes=rng.normal(0.0, 0.1, (2, 25, 2)),
        maxima=(maxima, maxima))


@pytest.mark.timeout(30)
def test_sample_by_sample_the_test_is_the_matched_filter_over_whitened_residuals():
    """Fed one sample at a time (offset residuals, so that the reference mean matters), each
    template's statistic is matched_filter's over the whole flight whitened, to rounding,
    from the first sample with a full window and reference on; after a reset, again."""
    rng = np.random.default_rng(3)
    templates = two_templates(rng)
    residuals = autoregressive(rng, 600, 2)[0] + np.array([0.3, -0.2])
    test = TemplateTest(templates)
    for _ in range(2):
        fed = [test.update(sample) for sample in residuals]
        first = templates.length + REFERENCE - 1
        assert all(value is None for value in fed[:first])
        for n, shape in enumerate(templates.shapes):
            batch = matched_filter(shape, templates.spread,
                                   whitened(residuals, templates.whitening), REFERENCE)
            assert np.array([value[n] for value in fed[first:]]) == pytest.approx(
                batch[first:], abs=1e-12)
        test.reset()


@pytest.mark.timeout(60)
def test_thresholds_from_block_maxima_keep_a_smooth_shape_under_the_designed_rate():
    """White residuals, a failure-like shape (a ramp on one generator, the other's opposite
    and half): its block maxima over 20 h fitted, its thresholds for 5 and 1 false alarms
    per hour are crossed upwards on 20 other hours at most that often (measured 1.7 and 0.1
    an hour: the Weibull of the maxima lies above their tail, so the designed rate is an
    upper bound, not an estimate), at 5 an hour at least once an hour; a lower rate gives a
    higher threshold."""
    rng = np.random.default_rng(8)
    hour = round(3600 / PERIOD_S)
    shape = np.column_stack([np.linspace(0.0, 1.0, 25), np.linspace(0.0, -0.5, 25)])
    spread = np.array([1.0, 1.0])
    fitted = [rng.normal(0.0, 1.0, (hour, 2)) for _ in range(20)]
    templates = FailureTemplates(np.array([[1.0, 0.0], [1.0, 0.0]]), spread, REFERENCE,
                                 ("engine_cut",), ("engine",), shape[None],
                                 (maxima_distribution(shape, spread, REFERENCE, fitted),))
    judged = [matched_filter(shape, spread, rng.normal(0.0, 1.0, (hour, 2)), REFERENCE)
              for _ in range(20)]
    for rate in (5.0, 1.0):
        threshold = templates.thresholds(rate, PERIOD_S)[0]
        crossings = sum(int(np.sum((statistic[1:] > threshold) & ~(statistic[:-1] > threshold)))
                        for statistic in judged) / 20
        assert crossings <= rate, rate
        assert rate < 5.0 or crossings >= 1.0
    assert templates.thresholds(0.1, PERIOD_S)[0] > templates.thresholds(1.0, PERIOD_S)[0]


@pytest.mark.timeout(60)
def test_a_template_is_kept_where_it_finds_its_kind_and_keeps_fault_free_flights_quiet():
    """Twelve white fault-free flights; two kinds of ten failures each: a thrust loss whose
    shape (a step of 1.2 spreads on one generator over 5 s) is the same on every flight, kept;
    a 'wobble' whose shape changes sign from flight to flight (its mean shape is near zero),
    dropped. The kept template's threshold lies above every fault-free flight's statistic."""
    rng = np.random.default_rng(21)
    fault_free = [rng.normal(0.0, 1.0, (1500, 2)) for _ in range(12)]
    filters = np.array([[1.0, 0.0, 0.0, 0.0, 0.0]] * 2)
    step = np.column_stack([np.full(25, -1.2), np.zeros(25)])
    flights = []
    for n in range(20):
        kind, cause, shape = (("engine_cut", "engine", step) if n < 10 else
                              ("wobble", "elevator", step[:, ::-1] * (-1) ** n * (1 + n / 10)))
        residuals = rng.normal(0.0, 1.0, (600, 2))
        residuals[400:] += np.vstack([shape, np.repeat(shape[-1:], 175, axis=0)])
        in_time = np.zeros(600, bool)
        in_time[400:425] = True
        flights.append(LearningFlight(kind, cause, residuals, shape, in_time))
    templates = learn_templates(filters, REFERENCE, fault_free, flights, 0.1, PERIOD_S, "test")
    assert templates is not None and templates.kinds == ("engine_cut",)
    assert templates.causes == ("engine",) and templates.learned_from == "test"
    assert templates.shapes[0] == pytest.approx(step)
    threshold = templates.thresholds(0.1, PERIOD_S)[0]
    assert all(np.nanmax(matched_filter(templates.shapes[0], templates.spread, residuals,
                                        REFERENCE)) < threshold
               for residuals in fault_free)


@pytest.mark.timeout(30)
def test_the_templates_round_trip_through_the_signatures_file_and_a_bad_one_is_named(tmp_path):
    templates = two_templates(np.random.default_rng(2), Weibull(1.5, 2.5))
    path = tmp_path / "failure_signatures.yaml"
    path.write_text(yaml.safe_dump({"features": [], TEMPLATES_KEY: templates_to_dict(templates)}))
    read = read_templates(path)
    assert read.kinds == templates.kinds and read.causes == templates.causes
    assert read.maxima == templates.maxima and read.reference == REFERENCE
    assert read.shapes == pytest.approx(templates.shapes, abs=1e-8)
    assert read.whitening == pytest.approx(templates.whitening)
    path.write_text(yaml.safe_dump({"features": []}))
    assert read_templates(path) is None  # signatures without templates
    data = templates_to_dict(templates)
    data["spread"] = [0.1]  # one generator short
    path.write_text(yaml.safe_dump({TEMPLATES_KEY: data}))
    with pytest.raises(ValueError, match=r"templates in .*failure_signatures\.yaml: ValueError: "
                                         r"templates: whitening \(2, 5\), spread \(1,\)"):
        read_templates(path)


@pytest.mark.timeout(30)
def test_the_detector_alarms_on_a_template_and_names_its_cause():
    """The roll channel's residual of test_self_tuning's calibration gets, from 40 s on, a
    template's shape (3 spreads at its peak, far under the fast test's threshold at a rate
    of 1e-3 per hour): the template test alarms within the shape's 5 s and the combined
    alarm names the template's cause; before the shape, no alarm. A calibration over other
    generators is refused."""
    calibration = small_calibration()
    rng = np.random.default_rng(4)
    length = 25
    shape = np.zeros((length, 3))
    shape[:, 0] = 0.1 * np.sin(np.linspace(0.0, 2 * np.pi, length))  # zero mean: no fast change
    fitted = [rng.normal(0.0, 0.1, (3000, 3)) for _ in range(4)]
    spread = np.full(3, 0.1)
    templates = FailureTemplates(np.tile([1.0, 0.0, 0.0, 0.0, 0.0], (3, 1)), spread, REFERENCE,
                                 ("right_wing_lift_loss_step",), ("right_wing_lift",),
                                 shape[None] * 3.0,
                                 (maxima_distribution(shape, spread, REFERENCE, fitted),))
    detector = SelfTuningDetector(calibration, 1e-9, 1e-3, templates=templates,
                                  template_false_alarms_per_hour=1.0)
    state, controls = np.zeros(14), np.zeros(7)
    alarms = []
    for k in range(1, 300):
        time_s = 0.2 * k
        controls[2] = rng.normal(0.0, 0.1)  # aileron
        after = k - 200
        bump = 3.0 * shape[after, 0] if 0 <= after < length else 0.0
        state[9] = 0.5 * controls[2] + 0.5 + bump + rng.normal(0.0, 0.1)  # roll rate
        state[11] = 0.5 * controls[2] + 0.5 * state[11] + 0.5  # yaw rate, as calibrated
        sample = detector.update(time_s, state, controls)
        if sample is not None and sample.combined_alarm:
            assert not sample.fast_alarm.any() and sample.template_alarm.tolist() == [True]
            alarms.append((sample.time_s, sample.cause))
    assert alarms and 40.0 <= alarms[0][0] <= 45.0
    assert {cause for _, cause in alarms} == {"right_wing_lift"}
    other = two_templates(rng)
    with pytest.raises(ValueError, match="templates over 2 generators: the calibration has 3"):
        SelfTuningDetector(calibration, 0.01, templates=other)


@pytest.mark.timeout(30)
def test_the_shipped_templates_go_with_the_shipped_calibration_only():
    """Each vehicle's signatures file holds templates over its calibration's generators,
    the engine cut's among them (docs/detector.md); with a calibration file named, none."""
    for vehicle in ("carbon_z", "aerosonde"):
        shipped = DetectorSettings(vehicle=vehicle)
        calibration = detector_calibration(shipped)
        _, templates = learned_failures(shipped, calibration)
        assert templates is not None and "engine_cut" in templates.kinds, vehicle
        assert templates.shapes.shape[2] == len(calibration.channels)
        assert set(templates.causes) <= set(CAUSES)
        own = dataclasses.replace(shipped,
                                  calibration_file=str(shipped_calibration_path(vehicle)))
        assert learned_failures(own, calibration) == (None, None)
