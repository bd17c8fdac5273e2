"""Autopilot of the simulated aircraft: attitude inner loops, altitude and airspeed hold.

Sign conventions are the project's, which every vehicle's XML follows (docs/aircraft.md): a
positive elevator pitches nose down, a positive aileron rolls left, a positive rudder yaws
left. Every loop starts from
the trim, so that straight and level flight needs no correction:

    theta_cmd = theta_trim + PI(h_cmd - h) - k_hdot hdot      altitude hold (PI, as the paper)
    delta_e   = delta_e_trim + k_theta (theta - theta_cmd) + k_q q
    throttle  = throttle_trim + PI(V_cmd - V)                  airspeed hold on throttle
    delta_a   = k_phi (phi - phi_cmd) + k_p p                  roll from the guidance
    delta_r   = -k_beta beta                                   turn coordination

A system-identification manoeuvre (uav_sim.manoeuvres) adds its input to a command (phi_cmd,
theta_cmd, a sideslip command beta_cmd in the coordination loop, a rate held by a damping
term: k_p (p - p_cmd), k_q (q - q_cmd)) or to an output after the loops.
"""

from __future__ import annotations

from dataclasses import dataclass

from uav_aircraft.trim import Trim
from uav_aircraft.vehicles import AutopilotGains

from uav_sim.manoeuvres import NO_EXCITATION, Excitation


def clamp(value: float, low: float, high: float) -> float:
    """value limited to [low, high] (scalars: np.clip costs microseconds per call, and the
    autopilot clamps six values at 120 Hz)."""
    return min(max(float(value), low), high)


@dataclass(frozen=True)
class FlightState:
    """What the autopilot measures, SI and radians."""

    altitude_m: float
    climb_rate_mps: float
    airspeed_mps: float
    roll_rad: float
    pitch_rad: float
    sideslip_rad: float
    body_rates_radps: tuple[float, float, float]  # p, q, r


@dataclass(frozen=True)
class SurfaceCommands:
    """The surfaces and throttle commanded, and the attitude the loops were asked for (the
    setpoints a detector's tracking generators hold the aircraft against) [rad]."""

    elevator_rad: float
    aileron_rad: float
    rudder_rad: float
    throttle: float
    roll_cmd_rad: float
    pitch_cmd_rad: float


class PI:
    """Proportional-integral law; the integrator stops while the output is saturated."""

    def __init__(self, kp: float, ki: float, low: float, high: float) -> None:
        self.kp, self.ki, self.low, self.high = kp, ki, low, high
        self.integral = 0.0

    def update(self, error: float, offset: float, dt_s: float) -> float:
        unclipped = offset + self.kp * error + self.ki * (self.integral + error * dt_s)
        output = clamp(unclipped, self.low, self.high)
        if output == unclipped:
            self.integral += error * dt_s
        return output


class Autopilot:
    """Holds altitude and airspeed, and banks to the roll angle the guidance asks for."""

    def __init__(
        self,
        trim: Trim,
        altitude_cmd_m: float,
        airspeed_cmd_mps: float,
        gains: AutopilotGains,
        surface_limit_rad: float,
    ) -> None:
        self.trim = trim
        self.gains = gains
        self.surface_limit_rad = surface_limit_rad
        self.altitude_cmd_m = altitude_cmd_m
        self.airspeed_cmd_mps = airspeed_cmd_mps
        g = self.gains
        self.altitude_hold = PI(
            g.altitude_p_radpm,
            g.altitude_i_radpms,
            trim.alpha_rad - g.pitch_limit_rad,
            trim.alpha_rad + g.pitch_limit_rad,
        )
        self.airspeed_hold = PI(g.airspeed_p_permps, g.airspeed_i_permps_s, 0.0, 1.0)

    def update(self, state: FlightState, roll_cmd_rad: float, dt_s: float,
               added: Excitation = NO_EXCITATION) -> SurfaceCommands:
        """Surface and throttle commands for one control period dt_s [s], with what a
        manoeuvre adds."""
        g = self.gains
        p, q, _ = state.body_rates_radps
        pitch_cmd_rad = added.pitch_rad + self.altitude_hold.update(
            self.altitude_cmd_m - state.altitude_m,
            self.trim.alpha_rad - g.climb_rate_d_radspm * state.climb_rate_mps,
            dt_s,
        )
        elevator_rad = (
            self.trim.elevator_rad
            + g.pitch_p * (state.pitch_rad - pitch_cmd_rad)
            + g.pitch_rate_d_s * (q - added.pitch_rate_radps)
            + added.elevator_rad
        )
        throttle = clamp(self.airspeed_hold.update(
            self.airspeed_cmd_mps - state.airspeed_mps, self.trim.throttle, dt_s
        ) + added.throttle, 0.0, 1.0)
        roll_cmd_rad = clamp(roll_cmd_rad + added.roll_rad, -g.roll_limit_rad, g.roll_limit_rad)
        aileron_rad = (g.roll_p * (state.roll_rad - roll_cmd_rad)
                       + g.roll_rate_d_s * (p - added.roll_rate_radps) + added.aileron_rad)
        rudder_rad = -g.sideslip_p * (state.sideslip_rad - added.sideslip_rad) + added.rudder_rad
        limit = self.surface_limit_rad
        return SurfaceCommands(
            elevator_rad=clamp(elevator_rad, -limit, limit),
            aileron_rad=clamp(aileron_rad, -limit, limit),
            rudder_rad=clamp(rudder_rad, -limit, limit),
            throttle=throttle,
            roll_cmd_rad=roll_cmd_rad,
            pitch_cmd_rad=pitch_cmd_rad,
        )
