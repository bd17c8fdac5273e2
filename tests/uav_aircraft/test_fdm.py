"""The JSBSim Aerosonde: symmetric without faults, each fault acting as docs/design.md defines,
and the propeller module reproducing JSBSim's own propeller."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_aircraft.fdm import M_PER_FT, create_fdm, set_faults
from uav_aircraft.flown_aircraft import COEFFICIENT_PROPERTY, FlownAircraft, coefficient_names
from uav_aircraft.propeller import Propeller
from uav_aircraft.trim import trim_level_flight
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import FAULT_NAMES
from uav_sim.simulation import spin_up_engine

AIRSPEED_MPS = 25.0
AEROSONDE = load_vehicle("aerosonde")


@pytest.fixture(scope="module")
def trimmed():
    """An executive trimmed at 25 m/s, 250 m, its engine running at the trim throttle."""
    fdm = create_fdm(AEROSONDE)
    fdm["ic/h-sl-ft"] = 250.0 / M_PER_FT
    fdm["fcs/mixture-cmd-norm"] = 1.0
    trim = trim_level_flight(fdm, AIRSPEED_MPS, AEROSONDE, Propeller.from_vehicle(AEROSONDE))
    fdm.run_ic()
    spin_up_engine(fdm)
    return fdm, trim


def aero_moments(fdm, faults_pct):
    """Aerodynamic roll, yaw moments [lbf ft], drag and lift [lbf] at the initial state.

    JSBSim's wind-axis forces/fwx-aero-lbs and fwz-aero-lbs hold drag and lift, positive.
    """
    set_faults(fdm, dict.fromkeys(FAULT_NAMES, 0.0) | faults_pct)
    fdm.run_ic()
    values = [
        fdm[name]
        for name in (
            "moments/l-aero-lbsft",
            "moments/n-aero-lbsft",
            "forces/fwx-aero-lbs",
            "forces/fwz-aero-lbs",
        )
    ]
    set_faults(fdm, dict.fromkeys(FAULT_NAMES, 0.0))
    return np.array(values)


def test_trim_is_physical(trimmed):
    _, trim = trimmed
    print(
        f"trim at 25 m/s: alpha {math.degrees(trim.alpha_rad):.2f} deg, elevator "
        f"{math.degrees(trim.elevator_rad):.2f} deg, throttle {trim.throttle:.3f}, "
        f"{trim.engine_rpm:.0f} rpm"
    )
    assert 0.0 < trim.alpha_rad < math.radians(8.0)
    assert 0.1 < trim.throttle < 0.8
    assert np.all(np.abs(trim.residual_accelerations) < 1e-4)


def test_propeller_module_matches_jsbsims_engine(trimmed):
    fdm, trim = trimmed
    print(
        f"engine speed: JSBSim {fdm['propulsion/engine/engine-rpm']:.3f} rpm, "
        f"propeller module {trim.engine_rpm:.3f} rpm"
    )
    assert fdm["propulsion/engine/engine-rpm"] == pytest.approx(trim.engine_rpm, abs=0.1)


def test_without_faults_the_aircraft_is_symmetric(trimmed):
    roll, yaw, _, _ = aero_moments(trimmed[0], {})
    assert abs(roll) < 1e-9 and abs(yaw) < 1e-9


@pytest.mark.parametrize(
    ("fault", "roll_sign", "yaw_sign", "lift_change", "drag_change"),
    [
        ("right_wing_lift_loss", +1, 0, -1, 0),  # right wing drops: roll right (+)
        ("left_wing_lift_loss", -1, 0, -1, 0),
        ("right_wing_drag_increase", 0, +1, 0, +1),  # right wing held back: nose right (+)
        ("left_wing_drag_increase", 0, -1, 0, +1),
    ],
)
def test_each_wing_fault_acts_on_its_own_side(
    trimmed, fault, roll_sign, yaw_sign, lift_change, drag_change
):
    fdm, _ = trimmed
    base = aero_moments(fdm, {})
    faulty = aero_moments(fdm, {fault: 10.0})
    change = faulty - base
    # A change below 1 % of the largest one is none (rounding of JSBSim's axis transforms).
    signs = np.where(np.abs(change) < 0.01 * np.abs(change).max(), 0, np.sign(change))
    print(f"{fault} at 10 %: roll, yaw [lbf ft], drag, lift [lbf] change by {change}")
    assert signs.tolist() == [roll_sign, yaw_sign, drag_change, lift_change]


def test_lift_loss_scales_that_wings_lift_as_design_md_defines(trimmed):
    """The wing's lift function, without the tail's alpha-dot lift (which follows wdot)."""
    fdm, _ = trimmed
    set_faults(fdm, {"right_wing_lift_loss": 10.0, "left_wing_lift_loss": 30.0})
    fdm.run_ic()
    faulty_lbf = fdm["aero/force/lift-wing"]
    wing_lift_lbf = fdm["aero/qbar-psf"] * fdm["metrics/Sw-sqft"] * fdm["aero/cl-wing"]
    set_faults(fdm, dict.fromkeys(FAULT_NAMES, 0.0))
    assert faulty_lbf == pytest.approx(wing_lift_lbf * (0.5 * 0.9 + 0.5 * 0.7), rel=1e-12)


def moment_of_surface(fdm, command, moment, fault, fault_pct):
    """The change of an aerodynamic moment [lbf ft] when a surface command goes 0 -> 0.2."""
    set_faults(fdm, {fault: fault_pct})
    values = []
    for value in (0.0, 0.2):
        fdm[command] = value
        fdm.run_ic()
        fdm.run_ic()  # once more, so that alpha-dot follows the same accelerations
        values.append(fdm[moment])
    set_faults(fdm, {fault: 0.0})
    fdm[command] = 0.0
    return values[1] - values[0]


@pytest.mark.parametrize(
    ("fault", "command", "moment"),
    [
        ("aileron_effectiveness_loss", "fcs/aileron-cmd-norm", "moments/l-aero-lbsft"),
        ("pitch_moment", "fcs/elevator-cmd-norm", "moments/m-aero-lbsft"),
    ],
)
def test_control_faults_scale_their_surface_moments(trimmed, fault, command, moment):
    fdm, _ = trimmed
    healthy = moment_of_surface(fdm, command, moment, fault, 0.0)
    faulty = moment_of_surface(fdm, command, moment, fault, 40.0)
    print(f"{fault} 40 %: surface moment {healthy:.4f} -> {faulty:.4f} lbf ft")
    assert faulty / healthy == pytest.approx(0.6, rel=0.02)


def test_propulsion_loss_takes_its_share_of_the_thrust(trimmed):
    fdm, _ = trimmed
    set_faults(fdm, {"propulsion_loss": 20.0})
    fdm.run()
    fdm.run()  # the FCS computes the loss from the thrust of the step before
    loss_lbf = fdm["external_reactions/propulsion_loss/magnitude"]
    thrust_lbf = fdm["propulsion/engine/thrust-lbs"]
    set_faults(fdm, {"propulsion_loss": 0.0})
    assert loss_lbf == pytest.approx(0.2 * thrust_lbf, rel=1e-3)


@pytest.mark.timeout(60)
def test_a_flown_aircraft_differs_where_it_says_and_only_there():
    """Mass, inertia and CG from an edited copy of the vehicle's XML; coefficients and thrust
    as scaled properties; every other coefficient the file's."""
    nominal = create_fdm(AEROSONDE)
    flown = create_fdm(AEROSONDE, aircraft=FlownAircraft(
        mass_scale=1.1, inertia_scale=(1.0, 1.2, 1.0), cg_offset_m=(0.01, 0.0, 0.0),
        thrust_scale=0.9, coefficients=(("CLalpha", 0.95), ("Cm0", 1.1))))
    for fdm in (nominal, flown):
        fdm["propulsion/fuel-loaded-lbs"] = 0.0  # the empty aircraft
        fdm.run_ic()
    assert flown["inertia/empty-weight-lbs"] == pytest.approx(
        1.1 * nominal["inertia/empty-weight-lbs"], rel=1e-12)
    # structural x points aft: 1 cm forward is 0.3937 in less
    assert flown["inertia/cg-x-in"] == pytest.approx(nominal["inertia/cg-x-in"] - 0.3937,
                                                     abs=1e-3)
    assert flown["propulsion/thrust-scale"] == 0.9
    for name in coefficient_names(AEROSONDE):
        prop = COEFFICIENT_PROPERTY.format(name=name)
        scale = {"CLalpha": 0.95, "Cm0": 1.1}.get(name, 1.0)
        assert flown[prop] == pytest.approx(scale * nominal[prop], rel=1e-12), name
    names = coefficient_names(AEROSONDE)
    assert len(names) == 31 and "CDinduced" in names
