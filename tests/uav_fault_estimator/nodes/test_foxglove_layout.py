"""The shipped Foxglove layout (config/foxglove_layout.json, installed with the package): its
panels are the ones its tree places, each configured with keys foxglove-sdk's layout model
knows for that panel, and every topic it names is advertised by foxglove_node while the
graph runs (sim, residual, mhe, detector and standard_topics nodes), in the types its panels
draw, each message path starting with a field of the advertised type."""

from __future__ import annotations

import dataclasses
import json
import re
import time

import foxglove.layouts as fl
import pytest
from helpers.process_table import listening_port
from uav_common.package_data import config_path
from uav_common.ros_processes import SIM_TIME_ROS_ARGS, ros2_run_argv
from uav_fault_estimator.recording.project_bag import project_typestore
from uav_fault_estimator.viewing.live_view import SUBPROTOCOL
from websockets.sync.client import connect

# Each panel type's configuration in foxglove-sdk's layout model (None: no settings), and
# its nested settings: key in the configuration: (model, how it holds them: a list of
# entries, a mapping to entries, or one entry).
PANEL_MODELS: dict[str, tuple[type | None, dict[str, tuple[type, str]]]] = {
    "Plot": (fl.PlotConfig, {"paths": (fl.PlotSeries, "list")}),
    "StateTransitions": (fl.StateTransitionsConfig,
                         {"paths": (fl.StateTransitionsSeries, "list")}),
    "3D": (fl.ThreeDeeConfig, {"scene": (fl.BaseRendererSceneSettings, "one")}),
    "map": (fl.MapConfig, {"topicConfig": (fl.MapTopicSettings, "mapping")}),
    "Parameters": (None, {}),
}


def layout() -> dict:
    return json.loads(config_path("uav_fault_estimator", "foxglove_layout.json").read_text())


def placed(tree: dict | str) -> list[str]:
    """The panel ids a layout tree places, left to right."""
    if isinstance(tree, str):
        return [tree]
    return placed(tree["first"]) + placed(tree["second"])


def model_keys(model: type | None) -> set[str]:
    """The camelCase keys of a foxglove-sdk layout model (its dataclass fields)."""
    fields = dataclasses.fields(model) if model is not None else ()
    return {re.sub(r"_(\w)", lambda match: match[1].upper(), field.name) for field in fields}


def message_paths(config: dict) -> list[str]:
    """Every `/topic.field...` a panel's configuration reads."""
    return [path["value"] for path in config.get("paths", [])]


def named_topics(config: dict) -> set[str]:
    """Every topic a panel's configuration names (message paths, 3D topics, Map topics)."""
    return ({path.split(".")[0] for path in message_paths(config)}
            | set(config.get("topics", {})) | set(config.get("topicConfig", {}))
            | ({config["followTopic"]} if "followTopic" in config else set()))


@pytest.mark.timeout(30)
def test_every_panel_is_placed_and_configured_with_keys_the_sdk_knows():
    shipped = layout()
    assert sorted(placed(shipped["layout"])) == sorted(shipped["configById"])
    for panel_id, config in shipped["configById"].items():
        model, nested = PANEL_MODELS[panel_id.split("!")[0]]
        assert set(config) <= model_keys(model), (panel_id, set(config) - model_keys(model))
        for key, (entry_model, held) in nested.items():
            value = config.get(key, [] if held == "list" else {})
            entries = (value if held == "list" else
                       list(value.values()) if held == "mapping" else [value])
            for entry in entries:
                assert set(entry) <= model_keys(entry_model), (panel_id, key, entry)
    three_d = shipped["configById"]["3D!track"]
    assert (three_d["followTf"], three_d["fixedFrame"]) == ("base_link", "map")
    assert named_topics(three_d) == {"/tf", "/track"}
    assert named_topics(shipped["configById"]["map!fix"]) == {"/fix"}


@pytest.mark.integration
@pytest.mark.timeout(120)
def test_every_topic_the_layout_names_is_advertised_while_the_graph_runs(
        short_scenario, start_process):
    configs = layout()["configById"].values()
    wanted = set().union(*(named_topics(config) for config in configs))
    start_process(ros2_run_argv("uav_sim", "sim_node", ros_args=[
        "-p", f"scenario:={short_scenario(600.0)}", "-p", "real_time_factor:=1.0",
        "-p", "wait_for_subscribers:=0"]), "sim_node")
    for node_name in ("residual_node", "mhe_node", "detector_node", "standard_topics_node"):
        start_process(ros2_run_argv("uav_fault_estimator", node_name,
                                    ros_args=SIM_TIME_ROS_ARGS), node_name)
    node = start_process(ros2_run_argv("uav_fault_estimator", "foxglove_node", ros_args=[
        "-p", "port:=0", *SIM_TIME_ROS_ARGS]), "foxglove_node")
    port = listening_port(node.pid, timeout_s=30)
    advertised: dict[str, str] = {}  # topic: type
    with connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL],
                 open_timeout=10) as client:
        deadline = time.monotonic() + 60
        while not wanted <= set(advertised) and time.monotonic() < deadline:
            frame = client.recv(timeout=max(0.0, deadline - time.monotonic()))
            if isinstance(frame, str) and (message := json.loads(frame))["op"] == "advertise":
                advertised |= {channel["topic"]: channel["schemaName"]
                               for channel in message["channels"]}
    assert wanted <= set(advertised), (wanted - set(advertised), node.output())
    # the types the 3D and Map panels draw
    assert {topic: advertised[topic] for topic in ("/tf", "/track", "/fix")} == {
        "/tf": "tf2_msgs/msg/TFMessage", "/track": "nav_msgs/msg/Path",
        "/fix": "sensor_msgs/msg/NavSatFix"}
    fields = project_typestore().fielddefs
    for path in (path for config in configs for path in message_paths(config)):
        topic, field = re.match(r"([^.]+)\.(\w+)", path).groups()
        assert field in [name for name, _ in fields[advertised[topic]][1]], path
    print(f"advertised: {sorted(wanted)}")
