"""What configures residual generation: residual_node's settings, which
prediction.residual_sampler takes (the generator of residuals.py on the update grid of
residual_sampling.py). Each field is the residual_node parameter of its name, declared here
once with its default, unit, range and meaning (uav_common.settings). No ROS here."""

from __future__ import annotations

from dataclasses import dataclass

from uav_aircraft.vehicle_parameter import VEHICLE_PARAMETER
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.settings import declared_setting, setting


@dataclass(frozen=True)
class ResidualSettings:
    """The residual generator's settings (embedded-estimation paper, eq. 5-8 and 15): the
    vehicle its model copies load, the faults whose sensitivities are S's columns, the
    secant step, F_a's time constant, the update and sensitivity periods, how long rows stay
    invalid after a start or a lost channel, the wind-error columns' step, and
    whether the engine speed is measured."""

    vehicle: str = declared_setting(VEHICLE_PARAMETER)
    fault_names: tuple[str, ...] = setting(
        "faults whose sensitivities are computed: the columns of S", list(PAPER_FAULT_NAMES))
    secant_step_pct: float = setting("secant step s of the sensitivity, eq. 8 / 15 [%]", 5.0,
                                     0.01, 100.0)
    tau_a_s: float = setting(
        "time constant of the smoothing filter F_a, eq. 5-6 (the paper's 4 s) [s]", 4.0, 0.1,
        100.0)
    tau_a_pitot_s: float = setting(
        "time constant of F_a on the samples whose models fly a pitot without vanes: short, "
        "so that one wind error per sample carries the gusts through it [s]", 1.0, 0.1, 100.0)
    update_period_s: float = setting(
        "residuals are published every this much simulation time [s]", 0.5, 0.01, 60.0)
    sensitivity_period_s: float = setting(
        "S is recomputed every this much simulation time; 0: every sample [s]", 0.5, 0.0, 60.0)
    recovery_s: float = setting(
        "rows stay invalid this long after the start and after a missing channel is "
        "back (3 tau_a) [s]", 12.0, 0.0, 600.0)
    wind_error_step_mps: float = setting(
        "secant step of the wind-error columns of S; 0: none [m/s]", 1.0, 0.0, 10.0)
    engine_speed_measured: bool = setting(
        "the state's engine speed is measured; false: the models turn the propeller at the "
        "speed where it absorbs the engine's power at the throttle (an autopilot that "
        "streams no engine speed, such as PX4)", True)
