"""Replays a simulated flight into running nodes, message by message, with corruption: what a
hostile tester does with a recording. The flight comes from the core simulator;
each message can be altered, duplicated, restamped or left out on its way to one namespace
while another gets it untouched, so that two copies of a node can be compared."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from rclpy.duration import Duration
from uav_common.ros.graph_probe import RosGraph
from uav_common.ros.messages import air_data_message, controls_message, state_message, wind_message
from uav_common.ros.qos import STREAM_QOS
from uav_fault_msgs.msg import AircraftState, AirData, ControlInputs, WindEstimate

from uav_sim.scenario import Scenario
from uav_sim.simulation import Simulation

TOPICS = {"state": AircraftState, "controls": ControlInputs, "wind/filtered": WindEstimate,
          "air_data": AirData}
ACK_EVERY = 20  # samples between waits for the subscribers' acknowledgements


@dataclass(frozen=True)
class FlightSample:
    time_s: float
    arrays: dict[str, np.ndarray]  # by topic


def simulated_flight(scenario: Scenario, duration_s: float) -> list[FlightSample]:
    """Every sensor sample of the scenario flown for duration_s [s] (sim_node's arrays)."""
    simulation = Simulation(dataclasses.replace(scenario, duration_s=duration_s))
    samples, sample = [], simulation.sample()
    while True:
        samples.append(FlightSample(sample.time_s, {
            "state": sample.state, "controls": sample.controls,
            "wind/filtered": sample.wind_filtered_ned_mps, "air_data": sample.air_data}))
        if simulation.finished:
            return samples
        sample = simulation.step()


def message(topic: str, time_s: float, values: np.ndarray) -> Any:
    """The message sim_node would publish on topic at time_s with these values."""
    if topic == "state":
        return state_message(time_s, values)
    if topic == "controls":
        return controls_message(time_s, values)
    if topic == "air_data":
        return air_data_message(time_s, values)
    return wind_message(time_s, values, 10.0)


# corrupt(sample, topic, values) -> [(stamp_s, values), ...]: what the disturbed copy gets
# for this topic and sample (an empty list: nothing; two entries: a duplicate; ...).
Corruption = Callable[[FlightSample, str, np.ndarray], Sequence[tuple[float, np.ndarray]]]


class Replayer:
    """Publishers in the test's graph node for the clean and the disturbed namespace."""

    def __init__(self, graph: RosGraph, namespaces: Sequence[str]) -> None:
        self.graph = graph
        self.publishers = {
            (namespace, topic): graph.node.create_publisher(kind, f"{namespace}/{topic}",
                                                            STREAM_QOS)
            for namespace in namespaces for topic, kind in TOPICS.items()}

    def wait_for_subscribers(self, counts: dict[str, int], timeout_s: float) -> bool:
        """Whether each topic's publishers (every namespace) have counts[topic] subscriptions
        (1 for a topic not named) within timeout_s."""
        def ready() -> bool:
            return all(p.get_subscription_count() >= counts.get(topic, 1)
                       for (_, topic), p in self.publishers.items())
        self.graph.spin(timeout_s, until=ready)
        return ready()

    def play(self, flight: list[FlightSample], clean: str, disturbed: str,
             corrupt: Corruption) -> None:
        """Publish the flight to both namespaces, corrupted on the way to `disturbed`."""
        for index, sample in enumerate(flight):
            for topic in TOPICS:
                values = sample.arrays[topic]
                if values is None:
                    continue
                self.publishers[(clean, topic)].publish(message(topic, sample.time_s, values))
                for stamp_s, altered in corrupt(sample, topic, values):
                    self.publishers[(disturbed, topic)].publish(
                        message(topic, stamp_s, altered))
            if index % ACK_EVERY == 0:
                self.wait_for_acknowledgements()
            self.graph.spin(0.0)
        self.wait_for_acknowledgements()

    def wait_for_acknowledgements(self) -> None:
        for publisher in self.publishers.values():
            publisher.wait_for_all_acked(Duration(seconds=10.0))
