"""scripts/demo.sh end to end: bad scenarios refused before any node starts, a node dying
mid-run, and short flights whose metrics.json and figures come out of the recording."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.process_table import kill_all, nodes_logging_under
from helpers.repo import SCRIPTS
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.ros_processes import RosProcess, wait_until
from uav_fault_estimator.chain.demo_run import (
    OUTPUT_MARK,
    Demo,
    DemoAircraft,
    OutputFolderError,
    prepare_output,
)
from uav_fault_estimator.chain.offline import fly_and_estimate
from uav_fault_estimator.estimation.model_file import shipped_model
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.recording.project_bag import project_typestore, read_topics
from uav_fault_estimator.reporting import report
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import default_scenario_path, load_scenario, vehicle_scenario_path

pytestmark = pytest.mark.integration

DEMO = SCRIPTS / "demo.sh"
DURATION_S = 120.0
EXPECTED_ESTIMATES = 240  # one per 0.5 s
TWO_FAULTS = [
    {"name": "right_wing_lift_loss", "start_s": 20, "ramp_s": 20, "magnitude_pct": 10},
    {"name": "left_wing_drag_increase", "start_s": 60, "ramp_s": 0, "magnitude_pct": 25},
]
FIGURES = ["states.png", "track.png", "wind.png", "residuals.png", "sensitivity.png",
           "estimates.png", "alarms.png"]
METRICS_KEYS = {"scenario", "duration_s", "settle_s", "detection_threshold_pct", "faults",
                "false_alarms", "solver", "pipeline", "alarms", "aircraft"}
FAULT_KEYS = {"seeded", "seeded_final_pct", "estimate_final_pct", "rmse_pct",
              "max_abs_error_pct", "detection_delay_s"}
SOLVER_KEYS = {"name", "solves", "median_ms", "p99_ms", "max_ms", "cpu_median_ms", "cpu_p99_ms",
               "failures"}
PIPELINE_KEYS = {"wall_s", "real_time_factor", "messages_expected", "messages_received",
                 "cpu_s_per_sim_s"}
PROGRESS = re.compile(r"^  t = (\d+) / ", re.MULTILINE)


@pytest.fixture
def run_dir(tmp_path: Path) -> Iterator[Path]:
    """The demo's --out folder; no node logging there may outlive the test."""
    folder = tmp_path / "run"
    try:
        yield folder
    finally:
        kill_all(nodes_logging_under(tmp_path))


def start_demo(start_process, scenario: Path, out: Path, *arguments: str) -> RosProcess:
    return start_process([str(DEMO), str(scenario), "--out", str(out), *arguments], "demo")


def fly(start_process, scenario: Path, out: Path, timeout_s: float = 100, status: int = 0,
        *arguments: str) -> str:
    """Run the demo to its end, with the further arguments; its output (the exit status
    asserted: 0, done and the targets met, unless said)."""
    demo = start_demo(start_process, scenario, out, *arguments)
    ended = demo.wait(timeout_s)
    output = demo.output()
    print(output)
    assert ended == status, output
    assert not nodes_logging_under(out)
    return output


def check_metrics(out: Path) -> dict:
    """metrics.json as docs/design.md lays it out, every estimate received, figures written."""
    metrics = json.loads((out / "metrics.json").read_text())
    assert set(metrics) == METRICS_KEYS
    assert list(metrics["faults"]) == list(PAPER_FAULT_NAMES)
    assert all(set(fault) == FAULT_KEYS for fault in metrics["faults"].values())
    assert set(metrics["solver"]) == SOLVER_KEYS
    assert set(metrics["pipeline"]) == PIPELINE_KEYS
    assert metrics["duration_s"] == pytest.approx(DURATION_S)
    pipeline = metrics["pipeline"]
    assert pipeline["messages_received"] == pipeline["messages_expected"] == EXPECTED_ESTIMATES
    assert metrics["solver"]["failures"] == 0
    # what flew and what the models were, from sim_node's and residual_node's /diagnostics
    assert isinstance(metrics["aircraft"]["flown"], dict)
    assert metrics["aircraft"]["guidance"] == "vector_field"  # the default guidance
    assert metrics["aircraft"]["guidance_fallbacks"] == 0
    assert metrics["aircraft"]["model"] == shipped_model("aerosonde")
    for name in FIGURES:
        assert (out / name).stat().st_size > 10_000, name
    # each node's output once: no rcl log file beside it, nor one of the demo's own
    assert {path.name for path in (out / "logs").glob("*.log")} == {
        f"{node}.log" for node in ("sim_node", "residual_node", "mhe_node", "detector_node",
                                   "recorder_node")}
    return metrics


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_a_shorter_flight_says_what_it_cut_and_what_it_did_not_judge(start_process,
                                                                     run_dir) -> None:
    """The default scenario flown for its first 60 s (--duration): the copy sim_node flew,
    the faults starting later not reached (said at the start and in the report, and not
    seeded in metrics.json), the lift ramp at 2 % since 58 s not judged, the run's verdict
    its last line."""
    output = fly(start_process, default_scenario_path(), run_dir, 100, 0, "--duration", "60")
    note = ("scenario 'default' cut at 60 s of its 300 s (--duration): not reached, starting "
            "later: left_wing_drag_increase at 110 s, left_wing_lift_loss at 170 s, "
            "right_wing_drag_increase at 210 s")
    lines = output.splitlines()
    assert lines[1] == f"demo: {note}" and note in lines, output
    assert lines[-1].endswith("s of wall time; targets (docs/estimator.md#targets): met (not "
                              "judged, at the threshold within 10 s of the end: "
                              "right_wing_lift_loss)"), output
    flown = load_scenario(run_dir / "logs" / "scenario.yaml")
    assert flown.duration_s == 60.0 and flown.faults == load_scenario(
        default_scenario_path()).faults
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["duration_s"] == 60.0
    assert metrics["pipeline"]["messages_received"] == 120
    assert [name for name, entry in metrics["faults"].items() if entry["seeded"]] == [
        "right_wing_lift_loss"]


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("duration", "words"), [
    ("400", "--duration 400 s is longer than the scenario 'default' (300 s): it cuts a "
            "scenario short"),
    ("-5", "--duration -5: a flight's duration is a positive number of seconds"),
    ("nan", "--duration nan: a flight's duration is a positive number of seconds"),
], ids=["longer", "negative", "nan"])
def test_a_duration_that_cuts_nothing_short_is_one_line(duration, words, run_dir) -> None:
    result = subprocess.run([str(DEMO), "--duration", duration, "--out", str(run_dir)],
                            capture_output=True, text=True, timeout=50)
    assert result.returncode == 2, result
    assert result.stderr == f"demo: {words}\n"
    assert not run_dir.exists()


def bad_scenario_run(scenario: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(DEMO), str(scenario), "--out", str(out)], capture_output=True,
                          text=True, timeout=60)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_bad_scenario_ends_before_any_node_starts(tmp_path, run_dir) -> None:
    invalid = tmp_path / "invalid.yaml"
    scenario = yaml.safe_load((scenarios_dir() / "default.yaml").read_text())
    invalid.write_text(yaml.safe_dump({**scenario, "wingspan_m": 3.0}))
    for path, key in ((tmp_path / "missing.yaml", "cannot read"), (invalid, "wingspan_m")):
        result = bad_scenario_run(path, run_dir)
        lines = result.stderr.splitlines()
        assert result.returncode == 2, result
        assert len(lines) == 1 and str(path) in lines[0] and key in lines[0], result.stderr
        assert not run_dir.exists()  # no output folder: no node was started
        assert not nodes_logging_under(tmp_path)


def kill_at(time_s: float, demo: RosProcess, run_dir: Path, *words: str) -> None:
    """Once the demo has flown time_s [s], SIGKILL the one node of it whose command line
    holds every word."""
    assert wait_until(lambda: any(int(t) >= time_s for t in PROGRESS.findall(demo.output()))
                      or not demo.running(), timeout_s=80), demo.output()
    found = [info for info in nodes_logging_under(run_dir)
             if all(word in info.cmdline for word in words)]
    assert len(found) == 1, demo.output()
    kill_all(found)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_node_dying_mid_run_ends_the_demo_with_its_name(
        start_process, short_scenario, run_dir) -> None:
    demo = start_demo(start_process, short_scenario(DURATION_S), run_dir)
    kill_at(20.0, demo, run_dir, "residual_node")

    assert demo.wait(30) == 1, demo.output()
    output = demo.output()
    print(output)
    assert "residual_node exited with status -9" in output
    assert not nodes_logging_under(run_dir)
    typestore = project_typestore()
    states = read_topics(run_dir / "bag", typestore, ("/state",))["/state"]
    assert len(states) >= 20 * 20  # at least the 20 s flown before the kill, at 20 Hz


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_two_aircraft_in_one_domain_each_estimate_as_their_own_offline_chain(
        start_process, short_scenario, run_dir) -> None:
    """Two aircraft of different kinds: /uav1 the Aerosonde on the MPC guidance (every QP
    solved), /uav2 the Carbon-Z; both fly on the first simulator's /clock, one recorder
    takes both, and each vehicle's estimates, read under its namespace, are its own core
    chain's to the last digit."""
    duration_s = 60.0
    methods = ("mpc", "vector_field")
    vehicles = ("aerosonde", "carbon_z")
    scenarios = [short_scenario(duration_s, vehicle_scenario_path(vehicle, "default"),
                                faults=[fault], guidance={"method": method})
                 for fault, method, vehicle in zip(TWO_FAULTS, methods, vehicles, strict=True)]
    demo = start_process([str(DEMO), *map(str, scenarios), "--out", str(run_dir)], "demo")
    assert demo.wait(120) == 0, demo.output()
    output = demo.output()
    print(output)
    assert re.search(r"^  t = 60 / 60 s, 240 estimates \(/uav1: 120, /uav2: 120\)$", output,
                     re.MULTILINE), output
    assert "following /clock" in (run_dir / "logs/uav2/sim_node.log").read_text()
    assert "following /clock" not in (run_dir / "logs/uav1/sim_node.log").read_text()
    typestore = project_typestore()
    for namespace, scenario, fault, method, vehicle in zip(
            ("/uav1", "/uav2"), scenarios, TWO_FAULTS, methods, vehicles, strict=True):
        metrics = json.loads((run_dir / namespace[1:] / "metrics.json").read_text())
        assert metrics["pipeline"]["messages_received"] == 120
        assert metrics["aircraft"]["model"] == shipped_model(vehicle)
        assert metrics["aircraft"]["guidance"] == method
        assert metrics["aircraft"]["guidance_fallbacks"] == 0
        assert metrics["solver"]["name"] == "proxsuite"  # its own mhe_node's /diagnostics
        assert [name for name, entry in metrics["faults"].items() if entry["seeded"]] == [
            fault["name"]]
        flown = report.run_from(read_topics(run_dir / "bag", typestore, report.TOPICS,
                                            namespace), run_dir / "bag").estimates
        offline, _ = fly_and_estimate(load_scenario(scenario))
        np.testing.assert_array_equal(flown.stamps_s, offline.stamps_s)
        np.testing.assert_allclose(flown.values_pct, offline.values_pct, rtol=0, atol=1e-9)
    other = short_scenario(30.0)
    refused = subprocess.run([str(DEMO), str(scenarios[0]), str(other), "--out",
                              str(run_dir.parent / "other")], capture_output=True, text=True,
                             timeout=60)
    assert refused.returncode == 2 and refused.stderr == (
        "demo: the scenarios last 30 s and 60 s: the vehicles fly on one clock, so their "
        "scenarios must last as long\n")


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_a_two_fault_flight_gives_its_metrics(start_process, short_scenario, run_dir) -> None:
    """The default flight (turbulence from the wind, noisy sensors) cut to 120 s with two
    faults, estimated by the active-set method (the scenario's estimator override): the
    graph's estimates are the core chain's (offline.py) to the last digit, so no message
    was lost or reordered; against the seeded faults they are what that chain measures
    (docs/estimator.md). (ProxSuite's graph runs are checked the same way by the
    two-aircraft test.)"""
    scenario = short_scenario(DURATION_S, faults=TWO_FAULTS,
                              estimator={"solver_method": "active_set"})
    # 60 s after its step the drag's RMS error is still above 15 % of it: the targets were
    # set for five-minute flights (docs/estimator.md#targets)
    output = fly(start_process, scenario, run_dir, 100, 3)
    assert re.search(r"^demo: done in [\d.]+ s of wall time; targets \(docs/estimator.md"
                     r"#targets\): missed: left_wing_drag_increase RMS [\d.]+ % of 25$",
                     output, re.MULTILINE), output
    assert re.search(r"^  t = 30 / 120 s, \d+ estimates$", output, re.MULTILINE), output
    assert "right_wing_lift_loss" in output and "pipeline: 240/240 estimates" in output
    metrics = check_metrics(run_dir)
    assert metrics["solver"]["name"] == "active_set"  # from mhe_node's /diagnostics

    typestore = project_typestore()
    flown = report.run_from(read_topics(run_dir / "bag", typestore, report.TOPICS),
                            run_dir / "bag").estimates
    offline, _ = fly_and_estimate(load_scenario(scenario))
    np.testing.assert_array_equal(flown.stamps_s, offline.stamps_s)
    np.testing.assert_allclose(flown.values_pct, offline.values_pct, rtol=0, atol=1e-9)

    lift, drag = (metrics["faults"][name]
                  for name in ("right_wing_lift_loss", "left_wing_drag_increase"))
    assert lift["seeded"] and lift["seeded_final_pct"] == 10.0
    assert drag["seeded"] and drag["seeded_final_pct"] == 25.0
    # measured (air data in the models, calibrated Q): lift 10.7 % at the end, detection
    # delay 5.0 s (metrics.json); drag 26.4 % at the end, 60 s after its step, delay 1.0 s
    assert lift["estimate_final_pct"] == pytest.approx(10.0, abs=2.5), lift
    assert lift["detection_delay_s"] is not None and lift["detection_delay_s"] <= 20.0, lift
    assert drag["estimate_final_pct"] == pytest.approx(25.0, abs=5.0), drag
    assert drag["detection_delay_s"] is not None and drag["detection_delay_s"] <= 30.0, drag


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_a_fault_free_flight_in_steady_wind_raises_no_false_alarm(
        start_process, tmp_path, run_dir) -> None:
    """Without turbulence and with ideal sensors every estimate stays within 0.2 % of zero
    (the sensor model's noise alone leaves up to 0.41 %, measured; in turbulence the
    fault-free flight does raise false alarms at the 2 % threshold: docs/results.md)."""
    scenario = yaml.safe_load((scenarios_dir() / "fault_free.yaml").read_text())
    scenario["wind"]["turbulence"] = "none"
    scenario["sensors"] = {"noise": False, "air_data": True}
    path = tmp_path / "fault_free.yaml"
    path.write_text(yaml.safe_dump({**scenario, "duration_s": DURATION_S}))
    fly(start_process, path, run_dir)
    metrics = check_metrics(run_dir)
    assert metrics["scenario"] == "fault_free"
    assert not any(fault["seeded"] for fault in metrics["faults"].values())
    largest = {name: fault["max_abs_error_pct"] for name, fault in metrics["faults"].items()}
    assert metrics["false_alarms"] == [], largest
    assert max(largest.values()) < 0.2, largest


@pytest.mark.timeout(60)
def test_a_scenario_that_is_not_utf8_is_one_line(tmp_path, run_dir) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes((scenarios_dir() / "default.yaml").read_bytes().replace(
        b"name: default", "name: défaut".encode("latin-1")))
    result = bad_scenario_run(path, run_dir)
    lines = result.stderr.splitlines()
    assert result.returncode == 2, result
    assert lines == [f"demo: scenario {path}: not UTF-8 text (byte 0xe9 at offset "
                     f"{path.read_bytes().index(0xE9)})"], result.stderr
    assert not run_dir.exists()
    assert not nodes_logging_under(tmp_path)


def demo_into(out: Path, scenario: Path | None = None) -> subprocess.CompletedProcess:
    """demo.sh with an output folder it is expected to refuse (before any node starts)."""
    scenario_args = [str(scenario)] if scenario else []
    return subprocess.run([str(DEMO), *scenario_args, "--out", str(out)], capture_output=True,
                          text=True, timeout=60)


def contents(folder: Path) -> dict[str, bytes | None]:
    """Every path under folder (relative) with a file's bytes (None for a folder)."""
    return {str(path.relative_to(folder)): None if path.is_dir() else path.read_bytes()
            for path in sorted(folder.rglob("*"))}


@pytest.mark.timeout(60)
def test_a_folder_the_demo_did_not_make_is_refused_untouched(tmp_path, run_dir) -> None:
    """The issue's case: logs/ and bag/ of the user's own, no mark: nothing is removed,
    nothing written, nothing started; one line naming the folder and what to do."""
    (run_dir / "logs").mkdir(parents=True)
    (run_dir / "logs" / "important.txt").write_text("the user's notes\n")
    (run_dir / "bag").mkdir()
    (run_dir / "bag" / "metadata.yaml").write_text("not the demo's\n")
    (run_dir / "metrics.json").write_text("{}\n")
    before = contents(run_dir)
    result = demo_into(run_dir)
    assert result.returncode == 2, result
    assert result.stderr.splitlines() == [
        f"demo: output folder {run_dir} is not empty and not one demo.sh made (no "
        f"{OUTPUT_MARK} in it): nothing there is removed or overwritten; choose another "
        "--out (a new or empty folder)"], result.stderr
    assert result.stdout == ""
    assert contents(run_dir) == before  # no mark either
    assert not nodes_logging_under(tmp_path)


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_an_out_that_is_a_file_or_cannot_be_written_is_one_line(tmp_path) -> None:
    a_file = tmp_path / "results.txt"
    a_file.write_text("keep me\n")
    read_only = Path("/sys") / f"uav_demo_test_{os.getpid()}"  # mkdir fails there, even as root
    cases = [
        (a_file, f"demo: output folder {a_file} is a file, not a folder; choose another "
                 "--out (a new or empty folder)"),
        (a_file / "run", f"demo: cannot write into the output folder {a_file / 'run'} (Not a "
                         "directory); choose another --out (a new or empty folder)"),
        (read_only, f"demo: cannot write into the output folder {read_only} ("),
    ]
    for out, line in cases:
        result = demo_into(out)
        lines = result.stderr.splitlines()
        assert result.returncode == 2, result
        assert len(lines) == 1 and lines[0].startswith(line), result.stderr
        assert "Traceback" not in result.stderr
    assert a_file.read_text() == "keep me\n"
    assert not read_only.exists()
    assert not nodes_logging_under(tmp_path)


@pytest.mark.timeout(30)
def test_prepare_output_makes_marks_and_replaces_only_its_own(tmp_path) -> None:
    scenario = tmp_path / "flight.yaml"
    out = tmp_path / "new" / "run"
    prepare_output(out, scenario)  # a new folder (and its parent): made and marked
    assert contents(out) == {OUTPUT_MARK: (out / OUTPUT_MARK).read_bytes(), "logs": None}

    # an earlier run's bag/ and logs/ go; what else is in the marked folder stays
    (out / "bag").mkdir()
    (out / "bag" / "bag.mcap").write_bytes(b"earlier")
    (out / "logs" / "sim_node.log").write_text("earlier\n")
    (out / "metrics.json").write_text("{}\n")
    (out / "notes.txt").write_text("mine\n")
    prepare_output(out, scenario)
    assert sorted(contents(out)) == sorted([OUTPUT_MARK, "logs", "metrics.json", "notes.txt"])
    assert (out / "notes.txt").read_text() == "mine\n"

    empty = tmp_path / "empty"  # an existing empty folder is taken and marked
    empty.mkdir()
    prepare_output(empty, scenario)
    assert (empty / OUTPUT_MARK).is_file() and (empty / "logs").is_dir()


@pytest.mark.timeout(30)
def test_prepare_output_refuses_links_files_and_the_scenario_inside(tmp_path) -> None:
    target = tmp_path / "elsewhere"
    target.mkdir()
    (target / "keep.txt").write_text("keep\n")
    out = tmp_path / "run"
    prepare_output(out, tmp_path / "flight.yaml")
    (out / "bag").symlink_to(target)
    refused = "^" + re.escape(f"{out / 'bag'} is not a folder demo.sh made")
    with pytest.raises(OutputFolderError, match=refused):
        prepare_output(out, tmp_path / "flight.yaml")
    assert (target / "keep.txt").read_text() == "keep\n" and (out / "bag").is_symlink()

    (out / "bag").unlink()
    (out / "bag").write_text("a file\n")
    with pytest.raises(OutputFolderError, match=re.escape("is not a folder demo.sh made")):
        prepare_output(out, tmp_path / "flight.yaml")
    (out / "bag").unlink()

    inside = out / "logs" / "flight.yaml"
    inside.write_text("name: x\n")
    with pytest.raises(OutputFolderError, match=r"inside .*/logs, which the run replaces"):
        prepare_output(out, inside)
    assert inside.read_text() == "name: x\n"


@pytest.mark.slow
@pytest.mark.timeout(150)
def test_a_second_run_into_its_folder_replaces_the_first(
        start_process, short_scenario, run_dir) -> None:
    """demo.sh twice into the same --out: the second run's bag/ and logs/ replace the
    first's, a file the user left beside them stays."""
    fly(start_process, short_scenario(10.0), run_dir)
    assert (run_dir / OUTPUT_MARK).is_file()
    (run_dir / "logs" / "stale.log").write_text("from the first run\n")
    (run_dir / "notes.txt").write_text("mine\n")
    first_mcap = {path.name for path in (run_dir / "bag").glob("*.mcap")}

    output = fly(start_process, short_scenario(12.0), run_dir)
    assert "pipeline: 24/24 estimates" in output, output
    assert not (run_dir / "logs" / "stale.log").exists()
    assert (run_dir / "notes.txt").read_text() == "mine\n"
    assert json.loads((run_dir / "metrics.json").read_text())["duration_s"] == 12.0
    states = read_topics(run_dir / "bag", project_typestore(), ("/state",))["/state"]
    assert len(states) == 12 * 20 + 1, len(states)  # the second flight's, at 20 Hz from 0 s
    assert {path.name for path in (run_dir / "bag").glob("*.mcap")} == first_mcap


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_one_aircraft_failing_leaves_the_other_to_finish(
        start_process, short_scenario, run_dir) -> None:
    """/uav1's mhe_node killed (SIGKILL) 10 s into a two-aircraft flight: /uav2 flies on, gets
    every estimate and its report, /uav1 is reported as far as it came, and the demo ends
    with status 1 naming /uav1.

    The flight lasts 120 s: flown as fast as the nodes keep up (15-20 times real time here),
    the 110 s after the kill's moment take seconds of wall time, where 30 s of a 40 s flight
    were once flown between the progress line and the kill."""
    duration_s = 120.0
    estimates = round(duration_s / ResidualSettings().update_period_s)  # one per residual
    scenarios = [short_scenario(duration_s, faults=[fault]) for fault in TWO_FAULTS]
    demo = start_process([str(DEMO), *map(str, scenarios), "--out", str(run_dir)], "demo")
    kill_at(10.0, demo, run_dir, "mhe_node", "uav1")
    assert demo.wait(120) == 1, demo.output()
    output = demo.output()
    print(output)
    assert "demo: uav1/mhe_node exited with status -9 (killed by SIGKILL) during the run" in output
    assert "demo: /uav1 failed: uav1/mhe_node exited with status -9 (killed" in output
    second = json.loads((run_dir / "uav2" / "metrics.json").read_text())
    assert second["pipeline"]["messages_received"] == estimates
    first = json.loads((run_dir / "uav1" / "metrics.json").read_text())
    assert 0 < first["pipeline"]["messages_received"] < estimates
    assert not nodes_logging_under(run_dir)


SIGINT_DEFAULT, SIGINT_IGNORED = (
    f"import signal, time; signal.signal(signal.SIGINT, signal.{disposition}); "
    "print('ready', flush=True); time.sleep(60)" for disposition in ("SIG_DFL", "SIG_IGN"))


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_a_process_ended_by_the_stops_sigint_is_no_failure(tmp_path) -> None:
    """A node process without a SIGINT handler yet ends by the signal itself (status -2):
    stopped as asked, not reported; one that ignores it and is killed is."""
    demo = Demo([DemoAircraft("", load_scenario(scenarios_dir() / "default.yaml"), None)], tmp_path)
    # SIGINT's disposition set by each process itself: the test's own may be inherited as
    # ignored (a suite started with `&` from a script).
    demo.nodes["stopped_by_sigint"] = RosProcess([sys.executable, "-c", SIGINT_DEFAULT],
                                                 tmp_path / "default.log")
    demo.nodes["killed"] = RosProcess([sys.executable, "-c", SIGINT_IGNORED],
                                      tmp_path / "ignored.log")
    assert wait_until(lambda: all("ready" in node.output() for node in demo.nodes.values()),
                      timeout_s=30)
    assert demo.stop() == ["killed exited with status -9 (killed by SIGKILL) when stopped"]


@pytest.mark.timeout(120)
def test_a_model_calibration_that_cannot_be_used_ends_the_demo_before_any_node(tmp_path,
                                                                                run_dir):
    calibration = tmp_path / "model.yaml"
    calibration.write_text("vehicle: aerosonde\nmodel_file: aerosonde.xml\nmodel_sha256: '0'\n"
                           "aircraft: {}\n")
    result = subprocess.run([str(DEMO), "--out", str(run_dir), "--model-calibration",
                             str(calibration)], capture_output=True, text=True, timeout=100)
    lines = result.stderr.splitlines()
    assert result.returncode == 2, result
    assert len(lines) == 1 and "made for another model file" in lines[0], result.stderr
    assert not run_dir.exists()  # no output folder: no node was started
