"""System-identification manoeuvres: each kind's signal as the autopilots define it, the
scenario key's strictness, and the inputs reaching the aircraft with the loops still flying."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml
from uav_aircraft.vehicles import load_vehicle
from uav_sim.manoeuvres import NO_EXCITATION, Manoeuvre, excitation
from uav_sim.scenario import ScenarioError, default_scenario_path, load_scenario
from uav_sim.simulation import Simulation

CHIRP = Manoeuvre(start_s=10.0, kind="chirp", axis="roll", level="attitude", magnitude=5.0,
                  f_start_hz=0.5, f_stop_hz=4.0, duration_s=20.0, fade_in_s=4.0,
                  fade_out_s=2.0)


def signal(manoeuvre: Manoeuvre, rate_hz: float = 400.0) -> tuple[np.ndarray, np.ndarray]:
    times = np.arange(manoeuvre.start_s - 1.0, manoeuvre.end_s + 1.0, 1.0 / rate_hz)
    return times, np.array([manoeuvre.value(t) for t in times])


def crossing_frequency_hz(times: np.ndarray, values: np.ndarray, around_s: float) -> float:
    """Half the rate of sign changes within 0.5 s of around_s [Hz]."""
    near = np.abs(times - around_s) < 0.5
    return np.count_nonzero(np.diff(np.sign(values[near])) != 0) / 2.0


@pytest.mark.timeout(30)
def test_a_chirp_sweeps_exponentially_under_its_fades():
    times, values = signal(CHIRP)
    assert np.all(values[(times < 10.0) | (times > 30.0)] == 0.0)
    assert np.max(np.abs(values)) == pytest.approx(5.0, abs=0.01)
    # the exponential sweep: 0.5 * 8^(t/20) Hz; at 10 s into it, 0.5 * sqrt(8) = 1.41 Hz
    assert crossing_frequency_hz(times, values, 20.0) == pytest.approx(1.41, abs=0.15)
    assert crossing_frequency_hz(times, values, 28.0) == pytest.approx(0.5 * 8 ** 0.9,
                                                                       abs=0.3)
    # the raised-cosine fade in: a quarter of the way in at half its length is half height
    assert abs(CHIRP._window(2.0)) == pytest.approx(0.5)
    assert CHIRP._window(19.0) == pytest.approx(0.5)


@pytest.mark.timeout(30)
def test_a_multisine_holds_its_band_and_its_peak():
    multisine = dataclasses.replace(CHIRP, kind="multisine", fade_in_s=0.0, fade_out_s=0.0)
    _, values = signal(multisine, rate_hz=100.0)
    assert np.max(np.abs(values)) == pytest.approx(5.0, rel=0.01)
    # one period of its base frequency, 1/20 s: the FFT's bins are its harmonics
    period = np.array([multisine.value(10.0 + n / 100.0) for n in range(2000)])
    amplitudes = np.abs(np.fft.rfft(period))
    in_band = amplitudes[10:81]  # 0.5 to 4 Hz
    assert np.ptp(in_band) / np.mean(in_band) < 1e-6  # every harmonic, one amplitude
    assert np.sum(in_band ** 2) / np.sum(amplitudes ** 2) > 0.999


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("kind", "pulses"), [("doublet", [1, -1]),
                                               ("3211", [1, 1, 1, -1, -1, 1, -1])])
def test_steps_take_their_signs_for_their_lengths(kind, pulses):
    steps = Manoeuvre(start_s=5.0, kind=kind, axis="yaw", level="surface", magnitude=0.3,
                      step_s=0.5)
    assert steps.end_s == pytest.approx(5.0 + 0.5 * len(pulses))
    assert [steps.value(5.25 + 0.5 * k) / 0.3 for k in range(len(pulses))] == pulses
    assert steps.value(4.9) == 0.0 and steps.value(steps.end_s + 0.1) == 0.0


@pytest.mark.timeout(30)
def test_each_axis_and_level_drives_its_own_input():
    limit_rad = 0.35
    plan = (Manoeuvre(0.0, "doublet", "roll", "attitude", 10.0, step_s=1.0),
            Manoeuvre(0.0, "doublet", "pitch", "rate", 20.0, step_s=1.0),
            Manoeuvre(0.0, "doublet", "yaw", "surface", 0.5, step_s=1.0),
            Manoeuvre(0.0, "doublet", "throttle", "surface", 0.2, step_s=1.0))
    added = excitation(plan, 0.5, limit_rad)
    assert added.roll_rad == pytest.approx(math.radians(10.0))
    assert added.pitch_rate_radps == pytest.approx(math.radians(20.0))
    assert added.rudder_rad == pytest.approx(0.5 * limit_rad)
    assert added.throttle == pytest.approx(0.2)
    assert added.aileron_rad == added.elevator_rad == added.sideslip_rad == 0.0
    assert excitation(plan, 2.5, limit_rad) is NO_EXCITATION


def scenario_with(tmp_path, manoeuvres: list[dict]):
    data = yaml.safe_load(default_scenario_path().read_text())
    data["manoeuvres"] = manoeuvres
    path = tmp_path / "manoeuvres.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


SWEEP = {"start_s": 20, "kind": "chirp", "axis": "roll", "level": "rate", "magnitude": 20,
         "f_start_hz": 0.2, "f_stop_hz": 2, "duration_s": 30, "fade_in_s": 3, "fade_out_s": 2}


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("entry", "message"), [
    ({**SWEEP, "step_s": 1}, "unknown key 'manoeuvres[0].step_s'"),
    ({**SWEEP, "kind": "sawtooth"}, "'manoeuvres[0].kind' must be one of chirp, multisine"),
    ({**SWEEP, "axis": "yaw"}, "'manoeuvres[0].level' must be one of attitude, surface"),
    ({**SWEEP, "f_stop_hz": 0.1}, "'manoeuvres[0].f_stop_hz' must be from f_start_hz to 30"),
    ({**SWEEP, "fade_in_s": 29}, "fade_in_s' and fade_out_s together exceed duration_s"),
    ({**SWEEP, "level": "attitude", "magnitude": 60}, "'manoeuvres[0].magnitude' must be at "
                                                        "most 45"),
    ({"start_s": 5, "kind": "doublet", "axis": "pitch", "magnitude": 0.1, "step_s": 1},
     "missing required key 'manoeuvres[0].level' (one of attitude, rate, surface)"),
    ({"start_s": 5, "kind": "doublet", "axis": "throttle", "level": "rate", "magnitude": 0.1,
      "step_s": 1}, "'manoeuvres[0].level' must be one of surface"),
    ({"start_s": 5, "kind": "3211", "axis": "roll", "level": "surface", "magnitude": 0.1},
     "missing required key 'manoeuvres[0].step_s'"),
])
def test_a_wrong_manoeuvre_is_one_line_naming_its_key(tmp_path, entry, message):
    with pytest.raises(ScenarioError) as error:
        load_scenario(scenario_with(tmp_path, [entry]))
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.timeout(30)
def test_two_manoeuvres_on_one_axis_at_once_are_refused(tmp_path):
    overlapping = [SWEEP, {"start_s": 40, "kind": 3211, "axis": "roll", "level": "surface",
                           "magnitude": 0.1, "step_s": 0.5}]
    with pytest.raises(ScenarioError, match=r"'manoeuvres\[1\]' overlaps 'manoeuvres\[0\]' on "
                                            r"the roll axis \(20-50 s\)"):
        load_scenario(scenario_with(tmp_path, overlapping))
    beside = [SWEEP, {**overlapping[1], "axis": "yaw", "kind": "3211"}]
    assert [m.axis for m in load_scenario(scenario_with(tmp_path, beside)).manoeuvres] == [
        "roll", "yaw"]


@pytest.mark.timeout(60)
def test_a_rudder_doublet_reaches_the_rudder_and_the_loops_recover(tmp_path):
    """On the surface the doublet adds to what the loops command; afterwards the aircraft
    is back to the sideslip and rudder of the same flight without it."""
    base = dataclasses.replace(load_scenario(default_scenario_path()), faults=(),
                               duration_s=30.0)
    doublet = Manoeuvre(10.0, "doublet", "yaw", "surface", 0.3, step_s=2.0)
    limit_rad = load_vehicle(base.vehicle).surface_limit_rad

    def rudder_and_sideslip(scenario):
        simulation = Simulation(scenario)
        rows = []
        while not simulation.finished:
            sample = simulation.step()
            rows.append((sample.time_s, sample.true_controls[3], sample.true_air_data[2]))
        return np.array(rows)

    plain = rudder_and_sideslip(base)
    flown = rudder_and_sideslip(dataclasses.replace(base, manoeuvres=(doublet,)))
    times = flown[:, 0]
    during = (times > 10.5) & (times < 12.0)
    assert np.all(flown[during, 1] - plain[during, 1] > 0.5 * 0.3 * limit_rad)
    assert np.max(np.abs(flown[during, 2] - plain[during, 2])) > math.radians(2.0)
    assert np.array_equal(flown[times < 10.0], plain[times < 10.0])
    after = times > 25.0
    assert np.max(np.abs(flown[after, 2] - plain[after, 2])) < math.radians(1.0)


@pytest.mark.timeout(30)
def test_each_vehicle_plan_loads_and_flies_each_axis():
    for vehicle in ("aerosonde", "carbon_z"):
        plan = [load_scenario(path) for path in load_vehicle(vehicle).calibration_plan_files]
        assert plan and all(not flight.faults and flight.vehicle == vehicle for flight in plan)
        assert sum(flight.duration_s for flight in plan) <= 15 * 60
        for flight in plan:
            assert {m.axis for m in flight.manoeuvres} == {"roll", "pitch", "yaw", "throttle"}
