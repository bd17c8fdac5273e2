"""The residual pipeline on a model whose true accelerations are known in closed form.

The test double's "aircraft" accelerates as a(t) = A sin(w t) + B f with time carried in
the latitude channel, so the observed derivative, the prediction and S can be checked
against exact values, without JSBSim.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_common.channels import STATE_CHANNELS
from uav_common.filters import LowPass
from uav_common.stamp_matching import (
    GuardedStream,
    StampGuard,
    StampMatcher,
)
from uav_fault_estimator.estimation.residuals import ResidualGenerator

FAULTS = ("right_wing_lift_loss", "left_wing_drag_increase")
AMPLITUDE = np.array([0.5, -0.3, 0.8, 0.05, -0.02, 0.03])   # A [m/s^2, rad/s^2]
OMEGA_RADPS = 0.7
SIGNATURE = np.array([                                       # B per % of each fault
    [0.00, -0.02], [0.00, 0.00], [0.09, 0.00], [0.20, 0.00], [0.00, 0.00], [0.00, -0.04],
])
CURVATURE = 1e-4   # a quadratic term, so that the secant step matters a little
DT_S, TAU_A_S = 0.05, 4.0
LAT, VEL = STATE_CHANNELS.index("latitude"), [6, 7, 8, 9, 10, 11]


def true_acceleration(time_s: float, fault_pct: np.ndarray) -> np.ndarray:
    return AMPLITUDE * math.sin(OMEGA_RADPS * time_s) + SIGNATURE @ fault_pct + CURVATURE * (
        SIGNATURE @ fault_pct**2
    )


def factory(faults_pct):
    vector = np.array([faults_pct.get(name, 0.0) for name in FAULTS])
    return lambda state, _controls, _wind: true_acceleration(state[LAT], vector)


def state_at(time_s: float, fault_pct: np.ndarray) -> np.ndarray:
    """Attitude zero (body = NED), velocity the exact integral of the true acceleration."""
    state = np.zeros(len(STATE_CHANNELS))
    state[LAT] = time_s
    linear = SIGNATURE @ fault_pct + CURVATURE * (SIGNATURE @ fault_pct**2)
    state[VEL] = -AMPLITUDE / OMEGA_RADPS * math.cos(OMEGA_RADPS * time_s) + linear * time_s
    return state


def generator(**overrides) -> ResidualGenerator:
    settings = dict(secant_step_pct=1.0, tau_a_s=TAU_A_S, sensitivity_period_s=0.5,
                    recovery_s=3 * TAU_A_S)
    settings.update(overrides)
    return ResidualGenerator(factory, FAULTS, **settings)


def fly(gen: ResidualGenerator, fault_pct, duration_s: float, dropout=None):
    samples = []
    for k in range(round(duration_s / DT_S) + 1):
        time_s = k * DT_S
        state = state_at(time_s, np.asarray(fault_pct, dtype=float))
        if dropout and dropout[1] <= time_s < dropout[2]:
            state[STATE_CHANNELS.index(dropout[0])] = np.nan
        samples.append(gen.update(time_s, state, np.zeros(7), np.zeros(3)))
    return samples


@pytest.mark.timeout(30)
def test_low_pass_is_the_exact_step_response() -> None:
    low_pass = LowPass(tau_s=2.0)
    low_pass.update(np.array([0.0]), 0.1)
    for _ in range(30):
        output = low_pass.update(np.array([1.0]), 0.1)
    assert output[0] == pytest.approx(1.0 - math.exp(-3.0 / 2.0), rel=1e-12)


@pytest.mark.timeout(30)
def test_fault_free_residual_vanishes_and_faulty_one_is_s_f() -> None:
    fault_free = fly(generator(), [0.0, 0.0], 30.0)[-1]
    faulty = fly(generator(), [10.0, 5.0], 30.0)[-1]
    print("fault-free |y| =", np.abs(fault_free.residual).max(), " faulty y =", faulty.residual)
    assert np.abs(fault_free.residual).max() < 1e-4
    assert faulty.valid.all()
    # the secant S differs from B by the curvature term: CURVATURE * s * B per column
    assert faulty.sensitivity == pytest.approx(SIGNATURE * (1 + CURVATURE * 1.0), abs=1e-9)
    fitted = faulty.sensitivity @ np.array([10.0, 5.0])
    assert np.linalg.norm(faulty.residual - fitted) / np.linalg.norm(faulty.residual) < 0.01


@pytest.mark.timeout(30)
def test_a_dropout_invalidates_the_rows_that_need_the_channel_then_recovers() -> None:
    samples = fly(generator(recovery_s=5.0), [10.0, 5.0], 40.0,
                  dropout=("pitch_rate", 20.0, 25.0))
    by_time = {round(sample.time_s, 2): sample for sample in samples if sample is not None}
    assert by_time[19.9].valid.all()
    assert list(by_time[22.0].valid) == [True, True, True, True, False, True]
    assert not by_time[29.9].valid[4] and by_time[30.0].valid.all()


@pytest.mark.timeout(30)
def test_a_gap_of_up_to_four_samples_is_bridged_and_a_longer_one_is_a_loss() -> None:
    """Velocity lost from 20.0 s: for 4 samples (0.2 s, BRIDGED_GAP_S) each gives the last
    complete sample's residuals, every row valid, and after the gap the residuals are
    within 1e-3 m/s^2 of the run without it (of about 1: F_a's one step over the gap
    instead of four) and fading with F_a; for 5 the rows that need it are invalid until
    recovery_s after it is back. A missing channel no row needs (fuel) is held, not
    bridged."""
    clean = {round(s.time_s, 2): s for s in fly(generator(), [10.0, 5.0], 30.0)
             if s is not None}
    bridged = fly(generator(), [10.0, 5.0], 30.0, dropout=("velocity_north", 20.0, 20.19))
    by_time = {round(s.time_s, 2): s for s in bridged if s is not None}
    assert sorted(by_time) == sorted(clean)
    for t in (20.0, 20.05, 20.1, 20.15):
        np.testing.assert_array_equal(by_time[t].residual, clean[19.95].residual)
    assert all(sample.valid.all() for t, sample in by_time.items() if t >= TAU_A_S * 3)
    moved = max(float(np.abs(sample.residual - clean[t].residual).max())
                for t, sample in by_time.items() if t >= 20.2)
    print(f"largest residual difference after the bridged gap: {moved:.1e}")
    assert moved < 1e-3
    assert np.abs(by_time[30.0].residual - clean[30.0].residual).max() < 0.1 * moved
    lost = fly(generator(recovery_s=5.0), [10.0, 5.0], 30.0,
               dropout=("velocity_north", 20.0, 20.24))
    lost_at = {round(s.time_s, 2): s for s in lost if s is not None}
    assert lost_at[20.15].valid.all() and not lost_at[20.2].valid[0]
    assert not lost_at[25.2].valid[0] and lost_at[25.25].valid.all()
    held = fly(generator(), [10.0, 5.0], 30.0, dropout=("fuel_mass", 20.0, 20.1))
    assert all(np.array_equal(s.residual, clean[round(s.time_s, 2)].residual)
               for s in held if s is not None)


@pytest.mark.timeout(30)
def test_time_going_backwards_is_refused_until_reset() -> None:
    gen = generator()
    fly(gen, [0.0, 0.0], 1.0)
    with pytest.raises(ValueError, match="reset first"):
        gen.update(0.5, state_at(0.5, np.zeros(2)), np.zeros(7), np.zeros(3))
    gen.reset()
    assert gen.update(0.5, state_at(0.5, np.zeros(2)), np.zeros(7), np.zeros(3)) is None


@pytest.mark.timeout(30)
def test_stamp_matcher_releases_complete_sets_in_stamp_order() -> None:
    matcher = StampMatcher(("state", "controls"))
    assert matcher.add("state", 200, "s2") == []
    assert matcher.add("state", 100, "s1") == []
    assert matcher.add("controls", 200, "c2") == [(200, {"state": "s2", "controls": "c2"})]
    assert matcher.dropped_sets == 1  # stamp 100 never got its controls
    assert matcher.released_ns == 200  # the newest released stamp


@pytest.mark.timeout(30)
def test_the_matcher_holds_at_most_pending_max_stamps() -> None:
    """A required stream that stopped: the sets waiting for it are dropped, oldest first,
    beyond pending_max, instead of piling up; when it comes back, its sets go out."""
    matcher = StampMatcher(("state", "controls"), pending_max=3)
    for stamp in range(1, 11):
        assert matcher.add("state", stamp, f"s{stamp}") == []
    assert sorted(matcher.pending) == [8, 9, 10] and matcher.dropped_sets == 7
    assert matcher.add("controls", 9, "c9") == [(9, {"state": "s9", "controls": "c9"})]
    assert matcher.dropped_sets == 8  # 8 never got its controls


@pytest.mark.timeout(30)
def test_an_optional_stream_is_waited_for_until_late_lost_or_waited_out() -> None:
    published = {"air": True}
    matcher = StampMatcher(("state",), ("air",), lambda stream: published[stream],
                           optional_wait=2)
    assert matcher.add("state", 100, "s1") == []                      # air may still come
    assert matcher.add("air", 100, "a1") == [(100, {"state": "s1", "air": "a1"})]
    assert matcher.add("state", 200, "s2") == []
    assert matcher.add("state", 300, "s3") == []
    # air silent for the whole wait: 200 goes without it, and so do the sets after it
    assert matcher.add("state", 400, "s4") == [(200, {"state": "s2"}), (300, {"state": "s3"}),
                                               (400, {"state": "s4"})]
    assert matcher.add("state", 500, "s5") == [(500, {"state": "s5"})]  # not waited for...
    assert matcher.add("air", 200, "a2") == [] and matcher.late_optional == 1  # ...until heard
    assert matcher.add("state", 600, "s6") == []                          # again, late or not
    assert matcher.add("air", 600, "a6") == [(600, {"state": "s6", "air": "a6"})]
    assert matcher.add("state", 700, "s7") == []
    assert matcher.released_ns == 600
    published["air"] = False  # its publisher gone: what it sent may still be queued
    assert matcher.add("air", 700, "a7") == [(700, {"state": "s7", "air": "a7"})]
    assert matcher.add("state", 800, "s8") == []
    assert matcher.add("state", 900, "s9") == []
    assert matcher.add("state", 1000, "s10") == [(800, {"state": "s8"}),  # waited out...
                                                 (900, {"state": "s9"}), (1000, {"state": "s10"})]
    assert matcher.add("state", 1100, "s11") == [(1100, {"state": "s11"})]  # ...then not
    assert matcher.dropped_sets == 0


@pytest.mark.timeout(30)
def test_an_optional_stream_never_heard_from_is_not_waited_for_without_a_publisher() -> None:
    matcher = StampMatcher(("state",), ("air",), lambda stream: False, optional_wait=2)
    assert matcher.add("state", 100, "s1") == [(100, {"state": "s1"})]
    assert matcher.add("air", 200, "a2") == []
    matcher.reset()  # heard before the restart: not after it
    assert matcher.add("state", 100, "s1") == [(100, {"state": "s1"})]


@pytest.mark.timeout(30)
def test_a_non_finite_prediction_skips_the_sample_and_keeps_the_state() -> None:
    def factory_with_a_hole(faults_pct):
        model = factory(faults_pct)
        return lambda state, controls, wind: (
            np.full(6, np.nan) if abs(state[LAT] - 5.0) < 1e-9 else model(state, controls, wind)
        )

    gen = ResidualGenerator(factory_with_a_hole, FAULTS, secant_step_pct=1.0, tau_a_s=TAU_A_S,
                            sensitivity_period_s=0.5, recovery_s=0.0)
    reference = generator(recovery_s=0.0)
    for k in range(round(10.0 / DT_S) + 1):
        time_s = k * DT_S
        state = state_at(time_s, np.array([10.0, 5.0]))
        expected = reference.update(time_s, state, np.zeros(7), np.zeros(3))
        if abs(time_s - 5.0) < 1e-9:
            with pytest.raises(ValueError, match="non-finite"):
                gen.update(time_s, state, np.zeros(7), np.zeros(3))
            continue
        sample = gen.update(time_s, state, np.zeros(7), np.zeros(3))
    # one interval of twice the length instead of two: the filters barely notice
    assert np.all(np.isfinite(sample.residual))
    assert sample.residual == pytest.approx(expected.residual, abs=1e-3)


@pytest.mark.timeout(30)
def test_a_stray_stamp_is_dropped_a_gap_taken_and_only_a_run_back_is_a_restart() -> None:
    s = 1_000_000_000
    guard = StampGuard(confirm_stamps=3, max_ahead_s=10.0)
    stamps = (1 * s, 2 * s, 2 * s, 1 * s, 3 * s,   # a duplicate, one back: strays
              50 * s, 4 * s,                         # one far ahead, then on from 3: a stray
              60 * s, 61 * s,                        # far ahead, and on from there: a gap
              1 * s, 1 * s, 2 * s, 3 * s, 4 * s)     # three distinct back in a row: a restart
    verdicts = [guard.check(stamp).value for stamp in stamps]
    assert verdicts == ["accept", "accept", "stray", "stray", "accept", "hold", "accept",
                        "hold", "gap", "stray", "stray", "stray", "restart", "accept"]
    assert guard.newest_ns == 4 * s and guard.last_gap_ns == 56 * s


@pytest.mark.timeout(30)
def test_a_guarded_stream_gives_back_what_it_held_at_a_gap_and_counts_strays() -> None:
    s = 1_000_000_000
    stream = GuardedStream(StampGuard(max_ahead_s=10.0))
    fed = [(1 * s, "a"), (50 * s, "stray"), (2 * s, "b"), (2 * s, "dup"),
           (30 * s, "c"), (31 * s, "d")]
    taken = [stream.feed(stamp, payload) for stamp, payload in fed]
    assert [(verdict.value, [p for _, p in out]) for verdict, out in taken] == [
        ("accept", ["a"]), ("hold", []), ("accept", ["b"]), ("stray", []), ("hold", []),
        ("gap", ["c", "d"])]
    assert stream.strays == 2


@pytest.mark.timeout(30)
def test_the_residual_models_are_rebuilt_after_giving_nan() -> None:
    """A model copy that once gives NaN is made anew (a JSBSim instance can keep giving it):
    the sample is refused, the next one is evaluated by fresh copies."""
    built = []

    def poisonable(faults_pct):
        model = factory(faults_pct)
        built.append(model)
        return lambda state, controls, wind: (np.full(6, np.nan) if len(built) <= 3
                                              and state[LAT] >= 1.0 else model(state, controls,
                                                                                wind))

    gen = ResidualGenerator(poisonable, FAULTS, secant_step_pct=1.0, tau_a_s=TAU_A_S,
                            sensitivity_period_s=0.5, recovery_s=1.0)
    times = [k * DT_S for k in range(40)]
    outcomes = []
    for time_s in times:
        try:
            gen.update(time_s, state_at(time_s, np.zeros(2)), np.zeros(7), np.zeros(3))
            outcomes.append("ok")
        except ValueError:
            outcomes.append("refused")
    assert outcomes.count("refused") == 1 and gen.model_rebuilds == 1
    assert len(built) == 6  # three copies, then three new ones
