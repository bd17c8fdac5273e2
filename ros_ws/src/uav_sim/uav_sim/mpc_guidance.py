"""Model predictive guidance: the embedded-estimation paper's autopilot (section V, "a
state-feedback model predictive control (MPC) guidance scheme [that] solves a constrained
quadratic programming problem at a sample time of two seconds to compute the yaw rate
command"), on ProxSuite.

Every sample_s, about the current leg of the waypoint loop (guidance.py's legs and leg
switch), with e the cross-track error (right of the leg positive) [m], psi the ground course's
error from the leg's course [rad], V the ground speed [m/s] (held over the horizon) and u the
yaw-rate command [rad/s], the kinematics e' = V sin(psi) ~ V psi, psi' = u are discretised
exactly with u held over each sample T (small angles: V psi grows with |psi|, so no plan
prefers flying a leg backwards, as a model in sin(psi), linearised about the plan, measured
did in the paper's wind):

    psi[k+1] = psi[k] + T u[k]
    e[k+1]   = e[k] + V T psi[k] + V T^2 / 2 u[k]

and the plan U = (u[0] .. u[N-1]) minimises

    sum_{k=1..N} q_e e[k]^2 + q_psi psi[k]^2  +  sum_{k=0..N-1} r u[k]^2

subject to |u[k]| <= g tan(phi_max) / V (the bank limit of a coordinated turn) and
|u[k] - u[k-1]| <= du_max (u[-1] the command being held), both as rows l <= C U <= u.
Condensed on U: X = A x0 + B U, H = 2 (Bᵀ Q B + R), g = 2 Bᵀ Q A x0. The first command
u[0] is held for T and flown as the bank of a coordinated turn at the current ground speed,
phi = atan(V u / g), by the existing inner loops; a leg switch starts a new sample at once.
The QP is warm-started from the previous plan and its duals shifted by one sample; the plan
is kept to the solver's tolerance, so that the same flight is flown twice. A step the
solver does not solve falls back to the vector field (guidance.WaypointGuidance) for that
sample, counted. No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import proxsuite
from uav_aircraft.frames import GRAVITY_MPS2

from uav_sim.guidance import WaypointGuidance, wrap_angle

MIN_SPEED_MPS = 5.0  # below it the yaw-rate limit g tan(phi) / V is meaningless


@dataclass(frozen=True)
class MpcSettings:
    """sample_s T [s], horizon_steps N, the weights q_e [1/m^2], q_psi [1/rad^2] and r
    [s^2/rad^2], du_max the largest change of the command between samples [rad/s], and the
    solver's tolerance eps_abs."""

    sample_s: float = 2.0
    horizon_steps: int = 12
    cross_track_weight: float = 1.0e-3
    course_weight: float = 1.0
    yaw_rate_weight: float = 10.0
    max_yaw_rate_change_radps: float = 0.15
    eps_abs: float = 1e-7


def prediction_matrices(speed_mps: float, sample_s: float,
                        steps: int) -> tuple[np.ndarray, np.ndarray]:
    """A (2N, 2) and B (2N, N) of the stacked states X = (e[1], psi[1], .., e[N], psi[N]) =
    A x0 + B U for the discretised kinematics (the module's docstring)."""
    t, v = sample_s, speed_mps
    step_a = np.array([[1.0, v * t], [0.0, 1.0]])
    step_b = np.array([v * t * t / 2.0, t])
    a = np.zeros((2 * steps, 2))
    b = np.zeros((2 * steps, steps))
    power = np.eye(2)
    for k in range(steps):
        power = step_a @ power
        a[2 * k:2 * k + 2] = power
    for k in range(steps):  # u[j]'s effect on x[k+1]: A^(k-j) b
        effect = step_b
        for j in range(k, steps):
            b[2 * j:2 * j + 2, k] = effect
            effect = step_a @ effect
    return a, b


def shifted(plan: np.ndarray) -> np.ndarray:
    """A plan one sample on: its steps from the second, the last repeated."""
    return np.concatenate([plan[1:], plan[-1:]])


class MpcGuidance:
    """Bank-angle commands for the waypoint loop from a yaw-rate plan made every sample_s."""

    def __init__(self, waypoints_ne_m: tuple[tuple[float, float], ...], max_bank_rad: float,
                 settings: MpcSettings = MpcSettings()) -> None:
        self.settings = settings
        self.max_bank_rad = max_bank_rad
        self.vector_field = WaypointGuidance(waypoints_ne_m)  # legs, and the fallback
        n = settings.horizon_steps
        # the bounds as rows of C, not ProxSuite's box constraints: with those, duals passed
        # to a warm start corrupt its memory (0.8.0), and duals not passed start from
        # whatever its memory held
        self.qp = proxsuite.proxqp.dense.QP(n, 0, 2 * n - 1)
        self.qp.settings.eps_abs = settings.eps_abs
        self.qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START
        self.qp.settings.compute_timings = True
        self.initialised = False
        # u[0] .. u[N-1], then u[k+1] - u[k]
        self.constraints = np.vstack([np.eye(n), np.eye(n - 1, n, 1) - np.eye(n - 1, n)])
        self.plan: np.ndarray | None = None
        self.command_radps = 0.0  # the yaw rate being held
        self.since_plan_s = math.inf
        self.fallbacks = 0  # samples flown on the vector field: the QP not solved
        self.solve_times_ms: list[float] = []
        self.largest_command_ratio = 0.0  # |u| / its limit, the largest the solver planned

    def roll_command(self, position_ne_m: np.ndarray, ground_velocity_ne_mps: np.ndarray,
                     dt_s: float) -> float:
        """Bank angle [rad] for the aircraft at position_ne_m flying ground_velocity_ne_mps,
        called every dt_s [s]: a new plan every sample_s, its first yaw rate held between."""
        speed_mps = max(float(np.linalg.norm(ground_velocity_ne_mps)), MIN_SPEED_MPS)
        # turn onto the next leg a turn radius ahead of its corner
        self.vector_field.switch_ahead_m = self.turn_radius_m(speed_mps)
        leg = self.vector_field.leg
        state = self.leg_state(position_ne_m, ground_velocity_ne_mps)  # the leg switched here
        self.since_plan_s += dt_s
        # a new leg is a new problem: planned at once, not up to sample_s late
        if self.since_plan_s >= self.settings.sample_s - 1e-9 or self.vector_field.leg != leg:
            self.since_plan_s = 0.0
            if not self.replan(state, speed_mps):
                self.fallbacks += 1
                self.plan = None
        if self.plan is None:  # this sample flies the vector field
            fallback = self.vector_field.roll_command(position_ne_m, ground_velocity_ne_mps)
            self.command_radps = fallback * GRAVITY_MPS2 / speed_mps  # its turn, as a rate
            return fallback
        return math.atan(speed_mps * self.command_radps / GRAVITY_MPS2)

    def turn_radius_m(self, speed_mps: float) -> float:
        """The radius of a turn at the bank limit at speed_mps [m/s] [m]."""
        return speed_mps ** 2 / (GRAVITY_MPS2 * math.tan(self.max_bank_rad))

    def leg_state(self, position_ne_m: np.ndarray,
                  ground_velocity_ne_mps: np.ndarray) -> np.ndarray:
        """(e, psi): cross-track error [m] and course error [rad] about the current leg
        (the vector field's legs, moved to the next one when it is time)."""
        cross_track_m, leg_course = self.vector_field.leg_errors(position_ne_m)
        course = math.atan2(ground_velocity_ne_mps[1], ground_velocity_ne_mps[0])
        return np.array([cross_track_m, wrap_angle(course - leg_course)])

    def replan(self, state: np.ndarray, speed_mps: float) -> bool:
        """A new plan from the leg state (e, psi) at speed_mps [m/s]; False when the solver
        does not solve the QP (the plan is then left to the caller)."""
        s = self.settings
        n = s.horizon_steps
        a, b = prediction_matrices(speed_mps, s.sample_s, n)
        weights = np.tile([s.cross_track_weight, s.course_weight], n)
        hessian = 2.0 * (b.T @ (weights[:, None] * b) + s.yaw_rate_weight * np.eye(n))
        gradient = 2.0 * b.T @ (weights * (a @ state))
        limit = GRAVITY_MPS2 * math.tan(self.max_bank_rad) / speed_mps
        change = s.max_yaw_rate_change_radps
        # the first step's change is about the command being held: a bound on u[0]
        low = np.full(n, -limit)
        high = np.full(n, limit)
        low[0] = max(-limit, self.command_radps - change)
        high[0] = min(limit, self.command_radps + change)
        if low[0] > high[0]:  # the held command lies outside a smaller limit: move to it
            low[0] = high[0] = float(np.clip(self.command_radps, -limit, limit))
        arguments = (hessian, gradient, None, None, self.constraints,
                     np.concatenate([low, np.full(n - 1, -change)]),
                     np.concatenate([high, np.full(n - 1, change)]))
        if self.initialised:
            self.qp.update(*arguments)
        else:
            self.qp.init(*arguments)
            self.initialised = True
        if self.plan is None:
            guess, duals = np.zeros(n), np.zeros(2 * n - 1)
        else:  # one sample on
            z = self.qp.results.z
            guess = np.clip(shifted(self.plan), low, high)
            duals = np.concatenate([shifted(z[:n]), shifted(z[n:])])
        self.qp.solve(guess, None, duals)
        results = self.qp.results
        self.solve_times_ms.append(results.info.run_time * 1e-3)
        if results.info.status != proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED or not (
                np.all(np.isfinite(results.x))):
            return False
        # kept to the solver's tolerance: below it ProxSuite's answer to the same QP differs
        # in its last bits from one QP object to the next (its vectorised sums follow where
        # its workspace lies in memory), and a flight would not be the same twice
        answer = np.round(results.x / s.eps_abs) * s.eps_abs
        self.largest_command_ratio = max(self.largest_command_ratio,
                                         float(np.max(np.abs(answer))) / limit)
        self.plan = np.clip(answer, low, high)  # within the solver's tolerance already
        self.command_radps = float(self.plan[0])
        return True
