"""Waypoint guidance: a closed path of straight legs, followed with a course vector field.

For the leg from waypoint a to b, with course chi_q and cross-track error e (right of the
leg positive), the commanded course is (Beard & McLain, Small Unmanned Aircraft, eq. 10.8)

    chi_cmd = chi_q - chi_inf (2/pi) atan(k_path e),

and the bank angle turns the ground course onto it: phi_cmd = k_course wrap(chi_cmd - chi).
Flying the ground course (not the heading) is what makes the law hold the path in wind.
A leg ends when the aircraft crosses the line through b normal to the leg.
"""

from __future__ import annotations

import math

import numpy as np


def wrap_angle(angle_rad: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


class WaypointGuidance:
    """Bank-angle commands that fly the waypoints as a closed loop, starting at leg 0 -> 1."""

    def __init__(
        self,
        waypoints_ne_m: tuple[tuple[float, float], ...],
        approach_angle_rad: float = math.radians(60.0),
        path_gain_perm: float = 0.02,
        course_gain: float = 1.2,
        switch_ahead_m: float = 0.0,
    ) -> None:
        self.waypoints = np.asarray(waypoints_ne_m, dtype=float)
        self.approach_angle_rad = approach_angle_rad
        self.path_gain_perm = path_gain_perm
        self.course_gain = course_gain
        # the next leg is taken this far before the line through the leg's end normal to it
        # (0: on it; the MPC guidance turns onto the next leg a turn radius ahead)
        self.switch_ahead_m = switch_ahead_m
        self.leg = 0
        # each leg's unit direction, computed once (leg_errors runs at the control rate)
        self.directions = []
        for leg in range(len(self.waypoints)):
            self.leg = leg
            start, end = self.leg_points()
            self.directions.append((end - start) / np.linalg.norm(end - start))
        self.leg = 0

    def leg_points(self) -> tuple[np.ndarray, np.ndarray]:
        """The current leg's start and end waypoints (north, east) [m]."""
        count = len(self.waypoints)
        return self.waypoints[self.leg % count], self.waypoints[(self.leg + 1) % count]

    def roll_command(self, position_ne_m: np.ndarray, ground_velocity_ne_mps: np.ndarray,
                     dt_s: float = 0.0) -> float:
        """Bank angle [rad] for the aircraft at position_ne_m flying ground_velocity_ne_mps
        (dt_s, the time since the last call, is the MPC guidance's: the field has no memory
        but its leg)."""
        cross_track_m, leg_course = self.leg_errors(position_ne_m)
        course_cmd = leg_course - self.approach_angle_rad * (2.0 / math.pi) * math.atan(
            self.path_gain_perm * cross_track_m
        )
        course = math.atan2(ground_velocity_ne_mps[1], ground_velocity_ne_mps[0])
        return self.course_gain * wrap_angle(course_cmd - course)

    def leg_errors(self, position_ne_m: np.ndarray) -> tuple[float, float]:
        """The cross-track error (right of the leg positive) [m] and the leg's course [rad]
        at position_ne_m, after moving to the next leg when the aircraft has come within
        switch_ahead_m of the line through the current leg's end normal to it."""
        start, end = self.leg_points()
        direction = self.directions[self.leg]
        if np.dot(position_ne_m - end, direction) >= -self.switch_ahead_m:
            self.leg = (self.leg + 1) % len(self.waypoints)
            start, end = self.leg_points()
            direction = self.directions[self.leg]
        offset = position_ne_m - start
        return (float(direction[0] * offset[1] - direction[1] * offset[0]),
                math.atan2(direction[1], direction[0]))


def route_errors(waypoints_ne_m: tuple[tuple[float, float], ...],
                 positions_ne_m: np.ndarray) -> tuple[np.ndarray, int]:
    """The cross-track error [m] of each position (K, 2) of a flight along the waypoint loop:
    its distance to the nearest leg (segment), right of it positive; and the corners passed
    forwards, less those passed backwards (the nearest leg's changes: a flight that turned
    back along a leg passes fewer). The nearest leg, not the guidance's own leg switch, so
    that a corner cut short is measured as flown."""
    starts = np.asarray(waypoints_ne_m, dtype=float)
    legs = np.roll(starts, -1, axis=0) - starts  # (L, 2)
    lengths = np.linalg.norm(legs, axis=1)
    offsets = positions_ne_m[:, None, :] - starts[None, :, :]  # (K, L, 2)
    along = np.clip(np.einsum("kld,ld->kl", offsets, legs) / lengths ** 2, 0.0, 1.0)
    distances = np.linalg.norm(offsets - along[..., None] * legs[None], axis=2)
    nearest = np.argmin(distances, axis=1)
    rows = np.arange(len(nearest))
    right = np.sign(legs[nearest, 0] * offsets[rows, nearest, 1]
                    - legs[nearest, 1] * offsets[rows, nearest, 0])
    steps = (np.diff(nearest) + 1) % len(starts) - 1  # +1 forwards, -1 backwards
    return right * distances[rows, nearest], int(np.sum(steps[np.abs(steps) == 1]))
