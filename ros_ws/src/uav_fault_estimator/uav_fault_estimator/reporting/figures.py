"""The run's figures (PNG) from a recording: states, north-east track, the wind (true, the
paper's filtered estimate and, with air data, the wind triangle),
residuals, one sensitivity column, each fault's estimate over its seeded value, and when
detector_node ran, its statistics against their thresholds; its combined alarms are marked
on the estimates too. matplotlib without a display (Agg); no ROS here."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from uav_aircraft.frames import north_east_m, wind_triangle_ned_mps
from uav_common.message_fields import air_data_array, stamp_nanoseconds, stamp_seconds, state_array

RESIDUAL_LABELS = ("x [m/s²]", "y [m/s²]", "z [m/s²]", "roll [rad/s²]", "pitch [rad/s²]",
                   "yaw [rad/s²]")


def save_figure(figure: plt.Figure, path: Path) -> Path:
    """Write figure to path as every figure of the project is (PNG, 110 dpi) and close it."""
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


TOPICS = ("/state", "/air_data", "/wind/true", "/wind/filtered", "/residuals",
          "/faults/estimate", "/faults/seeded", "/faults/alarm")
WIND_AXES = ("north", "east", "down")
ALARM_COLOR = "tab:red"


def _stamps(messages: list) -> np.ndarray:
    return np.array([stamp_seconds(m.header.stamp) for m in messages])


def plot_run(data: dict[str, list], out: Path) -> list[Path]:
    """Write every figure of a recording's messages (recording.read_topics of TOPICS) into
    out, each when its topics were recorded; the paths written."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    state = data["/state"]
    if state:
        written.append(_states_figure(state, out / "states.png"))
        written.append(_track_figure(state, out / "track.png"))
    if data["/wind/filtered"]:
        written.append(_wind_figure(data, out / "wind.png"))
    residuals = data["/residuals"]
    if residuals:
        written.append(_residuals_figure(residuals, out / "residuals.png"))
        written.append(_sensitivity_figure(residuals, out / "sensitivity.png"))
    alarms = data.get("/faults/alarm") or []
    if data["/faults/estimate"] and data["/faults/seeded"]:
        written.append(_estimates_figure(data["/faults/estimate"], data["/faults/seeded"],
                                         alarms, out / "estimates.png"))
    if alarms:
        written.append(_alarms_figure(alarms, data["/faults/seeded"], out / "alarms.png"))
    return written


def _states_figure(state: list, path: Path) -> Path:
    """Altitude [m], ground speed [m/s] and roll and pitch [deg] over sim time, from the
    AircraftState messages."""
    times = _stamps(state)
    figure, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    axes[0].plot(times, [m.altitude_m for m in state])
    axes[0].set_ylabel("altitude [m]")
    speed = [math.hypot(m.velocity_north_mps, m.velocity_east_mps) for m in state]
    axes[1].plot(times, speed)
    axes[1].set_ylabel("ground speed [m/s]")
    for name in ("roll", "pitch"):
        axes[2].plot(times, np.degrees([getattr(m, f"{name}_rad") for m in state]),
                     label=name)
    axes[2].set_ylabel("attitude [deg]")
    axes[2].legend()
    axes[2].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def _track_figure(state: list, path: Path) -> Path:
    """The ground track north over east [m] from the first AircraftState's position."""
    north, east = north_east_m([m.latitude_rad for m in state],
                               [m.longitude_rad for m in state],
                               (state[0].latitude_rad, state[0].longitude_rad))
    figure, axis = plt.subplots(figsize=(6, 6))
    axis.plot(east, north)
    axis.set_xlabel("east [m]")
    axis.set_ylabel("north [m]")
    axis.set_aspect("equal")
    axis.set_title("ground track from the start")
    return save_figure(figure, path)


def _residuals_figure(residuals: list, path: Path) -> Path:
    """Each of the six residual channels over sim time, from the Residuals messages."""
    times = _stamps(residuals)
    values = np.array([m.residual for m in residuals])
    figure, axes = plt.subplots(6, 1, figsize=(9, 10), sharex=True)
    for row, axis in enumerate(axes):
        axis.plot(times, values[:, row])
        axis.set_ylabel(RESIDUAL_LABELS[row], fontsize=8)
    axes[-1].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def _sensitivity_figure(residuals: list, path: Path) -> Path:
    """The first fault's sensitivity column (each channel per %) over sim time, from the
    Residuals messages."""
    times = _stamps(residuals)
    names = list(residuals[0].fault_names)
    column = np.array([np.reshape(m.sensitivity, (6, -1))[:, 0] for m in residuals])
    figure, axes = plt.subplots(6, 1, figsize=(9, 10), sharex=True)
    for row, axis in enumerate(axes):
        axis.plot(times, column[:, row])
        axis.set_ylabel(RESIDUAL_LABELS[row].replace("]", " per %]"), fontsize=8)
    axes[0].set_title(f"sensitivity column: {names[0]}")
    axes[-1].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def _estimates_figure(estimates: list, seeded: list, alarms: list, path: Path) -> Path:
    """Each estimated fault [%] over sim time with its seeded value dashed (when seeded) and
    the combined alarms shaded."""
    names = list(estimates[0].names)
    seeded_names = list(seeded[0].names)
    values = np.array([m.values_pct for m in estimates])
    truth = np.array([m.values_pct for m in seeded])
    figure, axes = plt.subplots(len(names), 1, figsize=(9, 2.4 * len(names)), sharex=True)
    for j, (name, axis) in enumerate(zip(names, np.atleast_1d(axes), strict=True)):
        if name in seeded_names:
            axis.plot(_stamps(seeded), truth[:, seeded_names.index(name)], "k--",
                      label="seeded")
        axis.plot(_stamps(estimates), values[:, j], label="estimate")
        _mark_alarms(axis, alarms)
        axis.set_ylabel(f"{name} [%]", fontsize=8)
        axis.legend(fontsize=8)
    np.atleast_1d(axes)[-1].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def _wind_triangle(state: list, air_data: list) -> tuple[np.ndarray, np.ndarray]:
    """Stamps [s] and NED winds [m/s] from the wind triangle of the state and air-data
    messages of equal stamps."""
    states = {stamp_nanoseconds(m.header.stamp): state_array(m) for m in state}
    stamps, winds = [], []
    for message in air_data:
        stamp_ns = stamp_nanoseconds(message.header.stamp)
        if stamp_ns in states:
            values = states[stamp_ns]
            stamps.append(stamp_seconds(message.header.stamp))
            winds.append(wind_triangle_ned_mps(values[6:9], *values[3:6],
                                               air_data_array(message)))
    return np.array(stamps), np.array(winds).reshape(-1, 3)


def _wind_figure(data: dict[str, list], path: Path) -> Path:
    """Each wind component: the true wind, the wind triangle from air data (when recorded)
    and the paper's filtered estimate."""
    figure, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    true_wind = data.get("/wind/true") or []
    triangle_t, triangle = _wind_triangle(data["/state"], data.get("/air_data") or [])
    filtered = data["/wind/filtered"]
    for k, (component, axis) in enumerate(zip(WIND_AXES, axes, strict=True)):
        if triangle.size:
            axis.plot(triangle_t, triangle[:, k], linewidth=0.6, alpha=0.6,
                      label="wind triangle (air data)")
        if true_wind:  # on top: the triangle's noise would hide it
            axis.plot(_stamps(true_wind), [(m.vector.x, m.vector.y, m.vector.z)[k]
                                           for m in true_wind],
                      color="k", linewidth=0.6, label="true")
        axis.plot(_stamps(filtered), [getattr(m, f"{component}_mps") for m in filtered],
                  linewidth=1.5, label=f"filtered, tau {filtered[0].filter_time_constant_s:g} s")
        axis.set_ylabel(f"wind {component} [m/s]")
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def shade_alarms(axis: plt.Axes, spans_s: list[tuple[float, float]],
                 label: str = "combined alarm") -> None:
    """Shade each (start, end) span [s] of an alarm, labelled once."""
    for k, (start_s, end_s) in enumerate(spans_s):
        axis.axvspan(start_s, end_s, color=ALARM_COLOR, alpha=0.3,
                     label=label if k == 0 else None)


def _mark_alarms(axis: plt.Axes, alarms: list, label: str = "combined alarm") -> None:
    """Shade the samples at which detector_node's combined alarm was raised."""
    raised = [stamp_seconds(m.header.stamp) for m in alarms if m.combined_alarm]
    shade_alarms(axis, [(time_s - 0.1, time_s + 0.1) for time_s in raised], label)


def _alarms_figure(alarms: list, seeded: list, path: Path) -> Path:
    """Each GLRT statistic and the largest parameter deviation over their thresholds (log
    scale), the combined alarms shaded, the first seeded fault's start dashed."""
    times = _stamps(alarms)
    names = list(alarms[0].channel_names)
    statistic = np.array([m.statistic for m in alarms])
    deviation = np.array([m.parameter_deviation for m in alarms])
    figure, axes = plt.subplots(len(names) + 1, 1, figsize=(9, 2.2 * (len(names) + 1)),
                                sharex=True)
    rows = [(f"GLRT {name}", statistic[:, k], [m.threshold[k] for m in alarms])
            for k, name in enumerate(names)]
    rows.append(("parameter deviation", deviation.max(axis=1),  # NaN until settled
                 [m.parameter_threshold for m in alarms]))
    onset = _first_fault_start(seeded)
    for axis, (label, values, threshold) in zip(axes, rows, strict=True):
        axis.semilogy(times, np.where(values > 0, values, np.nan), label="statistic")
        axis.semilogy(times, threshold, "k:", label="threshold")
        _mark_alarms(axis, alarms)
        if onset is not None:
            axis.axvline(onset, color="k", linestyle="--", label="fault starts")
        axis.set_ylabel(label, fontsize=8)
    axes[0].legend(fontsize=8, loc="upper left")
    axes[0].set_title(f"detector_node: designed P_FA {alarms[0].false_alarm_probability:g} "
                      "per sample and test")
    axes[-1].set_xlabel("simulation time [s]")
    return save_figure(figure, path)


def _first_fault_start(seeded: list) -> float | None:
    """The first stamp at which any seeded fault is non-zero; None if none ever is."""
    for message in seeded:
        if any(value != 0.0 for value in message.values_pct):
            return stamp_seconds(message.header.stamp)
    return None
