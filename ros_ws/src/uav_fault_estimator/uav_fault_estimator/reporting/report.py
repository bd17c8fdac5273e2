"""A run's metrics.json (docs/design.md) from its recording's messages (recording.read_topics).
No ROS here: metrics.py computes the figures."""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uav_aircraft.flown_aircraft import DIAGNOSTIC_KEY as FLOWN_AIRCRAFT_KEY
from uav_common.channels import DETECTION_THRESHOLD_PCT
from uav_common.health import CPU_KEY, GUIDANCE_FALLBACKS_KEY, GUIDANCE_KEY, hardware_id
from uav_common.message_fields import stamp_seconds

from uav_fault_estimator.estimation.estimator_config import SOLVER_METHOD_KEY
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.estimation.model_file import MODEL_KEY
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.recording.project_bag import WALL_S, RecordingError
from uav_fault_estimator.reporting.metrics import (
    AlarmSeries,
    EstimateSeries,
    SeededSeries,
    alarm_metrics,
    fault_metrics,
    solver_metrics,
)

ESTIMATE_TOPIC = "/faults/estimate"
SEEDED_TOPIC = "/faults/seeded"
STATE_TOPIC = "/state"
ALARM_TOPIC = "/faults/alarm"  # optional: only when detector_node ran
# Every node's health, CPU time included: read on its own (global, and kept out of the
# recording's wall span: the nodes report on it before and after the flight)
DIAGNOSTICS_TOPIC = "/diagnostics"
TOPICS = (ESTIMATE_TOPIC, SEEDED_TOPIC, STATE_TOPIC, ALARM_TOPIC)
REQUIRED_TOPICS = (ESTIMATE_TOPIC, SEEDED_TOPIC, STATE_TOPIC)


@dataclass(frozen=True)
class Run:
    """What a recording holds for the metrics: estimates, seeded faults, the flight's
    simulated duration [s], the wall time the recording spans [s], and the detector's
    alarms (None when it did not run)."""

    estimates: EstimateSeries
    seeded: SeededSeries
    duration_s: float
    wall_s: float
    alarms: AlarmSeries | None = None
    cpu_s: Mapping[str, float] | None = None  # each node's CPU time over the run [s]
    aircraft: Mapping[str, object] | None = None  # report.aircraft: what flew, the models


def run_from(messages: dict[str, list], bag: Path) -> Run:
    """The Run of a recording's messages (recording.read_topics of at least TOPICS);
    RecordingError (a ValueError) naming the bag when a stream is missing."""
    missing = [topic for topic in REQUIRED_TOPICS if not messages.get(topic)]
    if missing:
        raise RecordingError(f"recording {bag}: no messages on {', '.join(missing)}")
    estimates, seeded = messages[ESTIMATE_TOPIC], messages[SEEDED_TOPIC]
    return Run(
        estimates=EstimateSeries(
            names=list(estimates[0].names),
            stamps_s=np.array([stamp_seconds(m.header.stamp) for m in estimates]),
            values_pct=np.array([m.values_pct for m in estimates]),
            statuses=np.array([m.solver_status for m in estimates]),
            solve_times_ms=np.array([m.solve_time_ms for m in estimates]),
            cpu_times_ms=np.array([m.update_cpu_time_ms for m in estimates]),
        ),
        seeded=SeededSeries(
            names=list(seeded[0].names),
            stamps_s=np.array([stamp_seconds(m.header.stamp) for m in seeded]),
            values_pct=np.array([m.values_pct for m in seeded]),
        ),
        duration_s=stamp_seconds(messages[STATE_TOPIC][-1].header.stamp),
        wall_s=messages[WALL_S],
        alarms=alarm_series(messages.get(ALARM_TOPIC) or []),
    )


def alarm_series(alarms: list) -> AlarmSeries | None:
    """The FaultAlarm messages as an AlarmSeries; None for none."""
    if not alarms:
        return None
    return AlarmSeries(
        channel_names=list(alarms[0].channel_names),
        stamps_s=np.array([stamp_seconds(m.header.stamp) for m in alarms]),
        alarm=np.array([m.alarm for m in alarms], dtype=bool),
        parameter_alarm=np.array([m.parameter_alarm for m in alarms], dtype=bool),
        combined_alarm=np.array([m.combined_alarm for m in alarms], dtype=bool),
        tested=np.array([np.isfinite(m.statistic).all() for m in alarms], dtype=bool),
        false_alarm_probability=float(alarms[0].false_alarm_probability),
        fast_alarm=np.array([m.fast_alarm for m in alarms], dtype=bool),
        template_kinds=list(alarms[0].template_kinds),
        template_alarm=np.array([m.template_alarm for m in alarms], dtype=bool),
    )


def node_cpu_s(diagnostics: list, namespace: str = "") -> dict[str, float]:
    """Each node's CPU time over the run [s], by node name, from the CPU times on its
    /diagnostics statuses (uav_common.health.CPU_KEY): its last less its first, which leaves
    out the start-up before the first status (imports, JSBSim's loading), of the nodes in
    namespace ("" for none; the recorder's and other vehicles' left out)."""
    first, last = {}, {}
    for name, values in _node_statuses(diagnostics, namespace):
        if CPU_KEY in values:
            first.setdefault(name, float(values[CPU_KEY]))
            last[name] = float(values[CPU_KEY])
    return {name: last[name] - first[name] for name in sorted(last)}


def solver_method(diagnostics: list, namespace: str = "") -> str | None:
    """The solver method mhe_node in namespace reported on /diagnostics (its last status's
    estimator_config.SOLVER_METHOD_KEY); None when it reported none."""
    return last_value(diagnostics, namespace, "mhe_node", SOLVER_METHOD_KEY)


def aircraft(diagnostics: list, namespace: str = "") -> dict:
    """What flew and what the models were: sim_node's flown aircraft (where it differs from
    the model; {} the model itself), its guidance method and the steps that fell back to
    the vector field, and residual_node's model; None where a node did not say (a recording
    of a real flight, or of an older run)."""
    flown = last_value(diagnostics, namespace, "sim_node", FLOWN_AIRCRAFT_KEY)
    fallbacks = last_value(diagnostics, namespace, "sim_node", GUIDANCE_FALLBACKS_KEY)
    return {"flown": None if flown is None else json.loads(flown),
            "guidance": last_value(diagnostics, namespace, "sim_node", GUIDANCE_KEY),
            "guidance_fallbacks": None if fallbacks is None else int(fallbacks),
            "model": last_value(diagnostics, namespace, "residual_node", MODEL_KEY)}


def last_value(diagnostics: list, namespace: str, node: str, key: str) -> str | None:
    """The value of key on the last /diagnostics status of node (in namespace) that had it."""
    value = None
    for name, values in _node_statuses(diagnostics, namespace):
        if name == node:
            value = values.get(key, value)
    return value


def _node_statuses(diagnostics: list, namespace: str) -> Iterator[tuple[str, dict[str, str]]]:
    """(node name, its key-value pairs) of every /diagnostics status of the nodes in
    namespace, in the order they came."""
    wanted = hardware_id(namespace)
    for array in diagnostics:
        for status in array.status:
            if status.hardware_id == wanted:
                yield (status.name.rsplit("/", 1)[-1],
                       {item.key: item.value for item in status.values})


def run_metrics(run: Run, scenario: str, update_period_s: float | None = None,
                settle_s: float = SETTLE_S,
                threshold_pct: float = DETECTION_THRESHOLD_PCT) -> dict:
    """metrics.json as docs/design.md lays it out. update_period_s [s]: residual_node's, one
    estimate per residual (default: its default, ResidualSettings)."""
    if update_period_s is None:
        update_period_s = residual_update_period_s()
    faults, false_alarms = fault_metrics(run.estimates, run.seeded, settle_s, threshold_pct)
    return {
        "scenario": scenario,
        "duration_s": round(run.duration_s, 3),
        "settle_s": settle_s,
        "detection_threshold_pct": threshold_pct,
        "faults": faults,
        "false_alarms": false_alarms,
        "solver": solver_metrics(run.estimates),
        "pipeline": {
            "wall_s": round(run.wall_s, 3),
            "real_time_factor": round(run.duration_s / run.wall_s, 2) if run.wall_s else None,
            "messages_expected": round(run.duration_s / update_period_s),
            "messages_received": len(run.estimates.stamps_s),
            "cpu_s_per_sim_s": None if not run.cpu_s else {
                name: round(cpu_s / run.duration_s, 4) for name, cpu_s in run.cpu_s.items()},
        },
        "alarms": alarm_metrics(run.alarms, run.seeded) if run.alarms else None,
        "aircraft": dict(run.aircraft) if run.aircraft else None,
    }


def residual_update_period_s() -> float:
    """residual_node's default update_period_s [s] (ResidualSettings, its one home): the
    nodes publish a residual and an estimate every this much sim time."""
    return ResidualSettings().update_period_s


def table(metrics: dict) -> str:
    """The per-fault figures and the run's, as aligned text."""
    lines = [f"scenario {metrics['scenario']}: {metrics['duration_s']:g} s, settle "
             f"{metrics['settle_s']:g} s, threshold {metrics['detection_threshold_pct']:g} %",
             f"{'fault':<26}{'seeded':>8}{'final':>9}{'estimate':>10}{'rmse':>8}"
             f"{'max err':>9}{'delay s':>9}"]
    for name, fault in metrics["faults"].items():
        # None: no figure (a flight no longer than settle_s has no error figures)
        lines.append(
            f"{name:<26}{'yes' if fault['seeded'] else 'no':>8}"
            f"{_figure(fault['seeded_final_pct'], 9)}{_figure(fault['estimate_final_pct'], 10)}"
            f"{_figure(fault['rmse_pct'], 8)}{_figure(fault['max_abs_error_pct'], 9)}"
            f"{_figure(fault['detection_delay_s'], 9, '.1f')}")
    solver, pipeline = metrics["solver"], metrics["pipeline"]
    lines += [
        *ESTIMATOR_LEGEND,
        "estimator false alarms (an estimate at the threshold while its seeded value was below "
        f"it, after settle): {', '.join(metrics['false_alarms']) or 'none'}",
        f"solver: {solver['solves']} solves, {solver['failures']} failures, median "
        f"{solver['median_ms']} ms, p99 {solver['p99_ms']} ms, max {solver['max_ms']} ms "
        f"(wall); CPU median {solver['cpu_median_ms']} ms, p99 {solver['cpu_p99_ms']} ms",
        f"pipeline: {pipeline['messages_received']}/{pipeline['messages_expected']} estimates,"
        f" {pipeline['wall_s']} s wall, real-time factor {pipeline['real_time_factor']}",
    ]
    if pipeline["cpu_s_per_sim_s"]:
        lines.append("CPU per simulated second [s]: " + ", ".join(
            f"{name} {cpu:.3f}" for name, cpu in pipeline["cpu_s_per_sim_s"].items()))
    flown = (metrics.get("aircraft") or {})
    if flown.get("guidance") is not None:
        fallbacks = flown.get("guidance_fallbacks")
        lines.append(f"guidance: {flown['guidance']}" + (
            f", {fallbacks} steps flown on the vector field" if fallbacks else ""))
    if flown.get("flown") is not None:
        lines.append(f"flown aircraft: {_aircraft_text(flown['flown'])}; models: "
                     f"{flown['model'] or 'not said'}")
    alarms = metrics.get("alarms")
    if alarms:
        lines += _detector_lines(alarms)
    return "\n".join(lines)


# What the estimator's rows say, under them: their delay is not the detector's
ESTIMATOR_LEGEND = (
    "  (the estimator, mhe_node, per fault [%]: the seeded value and its estimate at the end,",
    "  the estimate's RMS and largest error after settle; delay s: from the seeded value",
    "  reaching the threshold to the estimate reaching it)",
)


def _detector_lines(alarms: dict) -> list[str]:
    """The detector's alarms (metrics.json's `alarms`), said apart from the estimator's
    figures: its alarms on the tested fault-free samples, and the delay of its first alarm
    after the first fault's start."""
    stretch = ("before the first fault starts" if alarms["fault_start_s"] is not None
               else "(no fault seeded: the whole flight)")
    return [f"detector (detector_node's own alarms, apart from the estimates): designed P_FA "
            f"{alarms['false_alarm_probability']:g} per sample; "
            f"{alarms['fault_free_samples']} tested fault-free samples {stretch}",
            *(f"  {name:<11} fault-free alarms {test['fault_free_alarms']:>4}, first alarm "
              f"after the first fault starts: {_seconds(test['first_alarm_delay_s'])}"
              for name, test in alarms["tests"].items())]


def _aircraft_text(differences: dict) -> str:
    """A flown aircraft's differences from the model on one line ("the model itself")."""
    if not differences:
        return "the model itself"
    parts = []
    for key, value in differences.items():
        if isinstance(value, dict):
            parts += [f"{name} {item:g}" for name, item in value.items()]
        else:
            parts.append(f"{key} {value}")
    return ", ".join(parts)


def _figure(value: float | None, width: int, spec: str = ".2f") -> str:
    return f"{'-' if value is None else format(value, spec):>{width}}"


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} s"
