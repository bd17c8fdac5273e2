"""What every node of the project shares: QoS per kind of topic, parameters declared with
descriptors (type, range) from the package's config YAML and checked, a /diagnostics
publisher, and the main that runs a node and ends it cleanly (run_node)."""

from __future__ import annotations

import faulthandler
import re
import signal
import sys
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

import rclpy
import rclpy.duration
import rclpy.logging
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)
from rclpy.signals import SignalHandlerOptions

from uav_common.health import CPU_KEY, hardware_id
from uav_common.package_data import default_parameters
from uav_common.ros.messages import stamp
from uav_common.ros.parameter_files import wildcard_only_names
from uav_common.ros_processes import STOP_TIMEOUT_S

# Sensor-rate streams and estimates, by each node's `qos` parameter. "reliable" (the
# default): keep-all, so that a fast simulation loses nothing while subscribers catch up;
# a slow subscriber holds its publisher back. "sensor_data": ROS's profile (best effort, the
# newest 5), so that no subscriber holds a publisher back; messages may be lost. A reliable
# subscription does not match a best-effort publisher (DDS): choose it on every node.
STREAM_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
STREAM_QOS_PROFILES = {"reliable": STREAM_QOS, "sensor_data": qos_profile_sensor_data}
# /clock: only the newest time matters.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
DIAGNOSTICS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)

# A node's own levels. STALE is not among them: by diagnostic_msgs' convention it is the
# aggregator's verdict on a node that has gone silent; a node without input says WARN.
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
# Wall time without a status update after which an input-driven node warns that its inputs
# stopped (they arrive at 2-20 Hz of sim time, and the graph runs at or above real time).
SILENT_INPUTS_S = 5.0


@dataclass(frozen=True)
class ParameterSpec:
    """What a node says about one of its parameters: its description; for numbers, the
    closed range [low, high] its values (each element of an array) must lie in; for a
    string, the choices it must be one of; and whether the node applies a change at run
    time (live) or reads it once, at start (read-only). The default lives in the package's
    config YAML alone, and its type is the default's type."""

    description: str
    low: float | None = None
    high: float | None = None
    live: bool = False
    choices: tuple[str, ...] = ()

    def range_text(self) -> str:
        return "" if self.low is None or self.high is None else f"[{self.low:g}, {self.high:g}]"


# Every stream node's `wait_for_subscribers` parameter (when_subscribed).
WAIT_FOR_SUBSCRIBERS_PARAMETER = ParameterSpec(
    "subscribe to the inputs only once the node's output has this many subscriptions, so "
    "that nothing it publishes is lost to discovery; 0: at once", 0, 100)
SUBSCRIPTION_POLL_S = 0.05  # wall time between looks at an output's subscription count


def when_subscribed(node: Node, publisher: Publisher, wanted: int,
                    subscribe: Callable[[], None]) -> None:
    """Call subscribe() (the node's input subscriptions) once publisher has `wanted`
    subscriptions as the publisher itself sees them (a listener's own view of the graph can
    be ahead of the publisher's); at once when wanted is 0. The node spins meanwhile
    (parameters, diagnostics), and its source (sim_node's wait_for_subscribers) waits in
    turn for the subscriptions subscribe() makes: the whole chain is matched before the
    first message."""
    if publisher.get_subscription_count() >= wanted:
        subscribe()
        return
    node.get_logger().info(
        f"waiting for {wanted} subscription(s) of {publisher.topic_name} before subscribing")

    def look() -> None:
        if publisher.get_subscription_count() >= wanted:
            node.destroy_timer(timer)
            subscribe()

    timer = node.create_timer(SUBSCRIPTION_POLL_S, look,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))


# Every stream node's `qos` parameter (STREAM_QOS_PROFILES).
QOS_PARAMETER = ParameterSpec(
    "QoS of the node's sensor-rate streams: reliable (keep-all, nothing lost, a slow "
    "subscriber holds the publisher back) or sensor_data (best effort, newest 5: messages may "
    "be lost); a reliable subscription does not hear a sensor_data publisher",
    choices=tuple(STREAM_QOS_PROFILES))


class ParameterError(ValueError):
    """A parameter override the node refuses (bad type, out of range, unknown)."""


_TYPE_NAMES = {
    Parameter.Type.BOOL: "a boolean", Parameter.Type.INTEGER: "an integer",
    Parameter.Type.DOUBLE: "a real number", Parameter.Type.STRING: "a string",
    Parameter.Type.BYTE_ARRAY: "a byte array", Parameter.Type.BOOL_ARRAY: "a boolean list",
    Parameter.Type.INTEGER_ARRAY: "an integer list", Parameter.Type.DOUBLE_ARRAY: "a real list",
    Parameter.Type.STRING_ARRAY: "a string list", Parameter.Type.NOT_SET: "no value",
}
_NUMBERS = (Parameter.Type.INTEGER, Parameter.Type.DOUBLE)
_NUMBER_ARRAYS = (Parameter.Type.INTEGER_ARRAY, Parameter.Type.DOUBLE_ARRAY)
# An integer given where a real is declared (`-p solver_eps_abs:=1`, `tau_a_s: 4` in a
# params file) is the real it names: taken as that real. Not the other way round: 50.0
# for a count is refused, as a real there is more likely a slip than a whole number.
_WIDENED = {Parameter.Type.INTEGER: Parameter.Type.DOUBLE,
            Parameter.Type.INTEGER_ARRAY: Parameter.Type.DOUBLE_ARRAY}


def _expected(kind: Parameter.Type, spec: ParameterSpec) -> str:
    text = _TYPE_NAMES[kind]
    if spec.range_text():
        text += (" in " if kind in _NUMBERS else " of values in ") + spec.range_text()
    return text


def checked_value(name: str, value: Any, kind: Parameter.Type, spec: ParameterSpec) -> Any:
    """value as the declared type `kind` (an integer widened to a real), in the spec's range;
    ParameterError, one line naming the parameter, otherwise."""
    given = Parameter.Type.from_parameter_value(value)
    if isinstance(value, list | tuple) and not value and kind.name.endswith("_ARRAY"):
        given = kind  # `[]` has no element to tell its type by
    if given != kind and _WIDENED.get(given) == kind:
        value = float(value) if kind == Parameter.Type.DOUBLE else [float(v) for v in value]
        given = kind
    if given != kind:
        raise ParameterError(f"parameter {name}: {value!r} is {_TYPE_NAMES[given]}; it must be "
                             f"{_expected(kind, spec)}")
    if spec.range_text() and kind in _NUMBERS + _NUMBER_ARRAYS:
        values = [value] if kind in _NUMBERS else list(value)
        bad = [v for v in values if not spec.low <= v <= spec.high]  # NaN is never in range
        if bad:
            raise ParameterError(f"parameter {name}: {bad[0]!r} is out of range; it must be "
                                 f"{_expected(kind, spec)}")
    if spec.choices and value not in spec.choices:
        raise ParameterError(f"parameter {name}: {value!r} is not a choice; it must be one of "
                             f"{', '.join(spec.choices)}")
    return value


def _descriptor(kind: Parameter.Type, spec: ParameterSpec) -> ParameterDescriptor:
    # Read-only unless live: a value read once, at start, cannot follow a change at run
    # time, so `ros2 param set` is refused with that reason, never ignored.
    descriptor = ParameterDescriptor(description=spec.description, type=kind.value,
                                     read_only=not spec.live)
    if spec.range_text():
        if kind == Parameter.Type.DOUBLE:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(spec.low), to_value=float(spec.high))]
        elif kind == Parameter.Type.INTEGER:
            descriptor.integer_range = [
                IntegerRange(from_value=int(spec.low), to_value=int(spec.high), step=1)]
        elif kind in _NUMBER_ARRAYS:
            descriptor.additional_constraints = f"each value in {spec.range_text()}"
    if spec.choices:
        descriptor.additional_constraints = f"one of {', '.join(spec.choices)}"
    return descriptor


# What a node does with changes of its live parameters (new values by name): apply them
# all, or none and raise ParameterError with the reason `ros2 param set` prints.
ApplyChanges = Callable[[dict[str, Any]], None]


def declare_parameters(
    node: Node, package: str, config_file: str, specs: Mapping[str, ParameterSpec | str],
    apply_changes: ApplyChanges | None = None,
) -> dict[str, Any]:
    """Declare each parameter with its default from the package's config YAML, its type and
    range in its descriptor; the values by name.

    Values given on the command line or in a --params-file override the defaults, after a
    check: of the type (an integer is taken for a real), of the range, and that the node has
    such a parameter. A bad one raises ParameterError (one line) before anything is declared;
    a name the node lacks that only a file's `/**` section gave it is ignored, with one
    warning naming them all (parameter_files.py).
    Live parameters (ParameterSpec.live) changed at run time go, checked the same way, to
    apply_changes; once it has applied them the returned dict holds the new values.
    """
    specs = {name: spec if isinstance(spec, ParameterSpec) else ParameterSpec(spec)
             for name, spec in specs.items()}
    defaults = default_parameters(package, config_file)
    missing = set(specs) ^ set(defaults)
    if missing:
        raise KeyError(f"parameters without both a description and a default: {sorted(missing)}")
    # rclpy keeps the overrides meant for this node (-p, --params-file) here; there is no
    # public accessor, and declaring would take a wrong one with rclpy's own traceback.
    overrides = {name: parameter.value for name, parameter in node._parameter_overrides.items()}
    unknown = sorted(name for name in overrides
                     if name not in specs and not node.has_parameter(name))
    shared = sorted(set(unknown) & wildcard_only_names(_process_arguments(), node.get_name()))
    if shared:  # a file written for every node: its keys for others are not this one's
        node.get_logger().warning(
            f"ignoring {', '.join(shared)} of the parameter file's /** section: this node "
            f"has no such parameter{'s' if len(shared) > 1 else ''}")
        unknown = [name for name in unknown if name not in shared]
    if unknown:
        raise ParameterError(
            f"unknown parameter{'s' if len(unknown) > 1 else ''} {', '.join(unknown)} (this "
            f"node has: {', '.join(sorted(specs))})")
    values = {}
    for name, spec in specs.items():
        kind = Parameter.Type.from_parameter_value(defaults[name])
        checked_value(name, defaults[name], kind, spec)  # the shipped default fits, too
        values[name] = checked_value(name, overrides.get(name, defaults[name]), kind, spec)
    for name, spec in specs.items():
        kind = Parameter.Type.from_parameter_value(defaults[name])
        node.declare_parameter(name, values[name], _descriptor(kind, spec), ignore_override=True)
    values = {name: node.get_parameter(name).value for name in specs}
    kinds = {name: Parameter.Type.from_parameter_value(defaults[name]) for name in specs}
    node.add_pre_set_parameters_callback(
        lambda parameters: [_widened(parameter, kinds) for parameter in parameters])
    live = {name: spec for name, spec in specs.items() if spec.live}
    if live:
        if apply_changes is None:
            raise TypeError(f"live parameters {sorted(live)} need apply_changes")
        node.add_on_set_parameters_callback(
            lambda parameters: _set_live(parameters, live, values, apply_changes))
    return values


def _widened(parameter: Parameter, kinds: Mapping[str, Parameter.Type]) -> Parameter:
    """The pre-set callback's step: an integer (or integer array) set on a real (or real
    array) parameter becomes the real it names, as at start (`ros2 param set ... 8`)."""
    kind = kinds.get(parameter.name)
    if kind is None or _WIDENED.get(parameter.type_) != kind:
        return parameter
    value = parameter.value
    return Parameter(parameter.name, kind,
                     float(value) if kind == Parameter.Type.DOUBLE else [float(v) for v in value])


def _set_live(parameters: list[Parameter], live: Mapping[str, ParameterSpec],
              values: dict[str, Any], apply_changes: ApplyChanges) -> SetParametersResult:
    """The on-set callback: rclpy has refused read-only ones and values outside a
    descriptor's range already; the same checks as at start, then the node applies them."""
    try:
        changes = {parameter.name: checked_value(
            parameter.name, parameter.value, Parameter.Type.from_parameter_value(
                values[parameter.name]), live[parameter.name])
            for parameter in parameters if parameter.name in live}
        if changes:
            apply_changes(changes)
    except ParameterError as error:
        return SetParametersResult(successful=False, reason=str(error))
    values.update(changes)
    return SetParametersResult(successful=True)


class Diagnostics:
    """Publishes the node's latest health on /diagnostics once a second of wall time, with
    the vehicle as hardware_id (`aerosonde`, or `aerosonde/uav1` in namespace /uav1) and,
    beside the node's own values, its process's CPU time so far (CPU_KEY): what the node
    costs, whatever else shares the cores.

    Published every period_s of wall time (health is for the people and tools watching the
    run), stamped in the node's time: simulation time under use_sim_time, and a clock
    source's own time (clock_s: what it publishes on /clock [s]). A node driven by inputs
    (silent_after_s given) says at least WARN, with its last status's values, once it has had
    no update for that long. A node may add statuses of its own parts (update_part:
    `<node>/<part>`, e.g. mhe_node's model_fit), published with its own. A node whose status
    is cheaper to take once per publication than per input gives before_publish, which
    calls update().
    """

    def __init__(self, node: Node, period_s: float = 1.0,
                 silent_after_s: float | None = SILENT_INPUTS_S,
                 clock_s: Callable[[], float] | None = None,
                 before_publish: Callable[[], None] | None = None) -> None:
        self._node = node
        self._before_publish = before_publish
        self._publisher = node.create_publisher(DiagnosticArray, "/diagnostics", DIAGNOSTICS_QOS)
        self._status = DiagnosticStatus(
            level=OK, name=node.get_fully_qualified_name(), message="starting",
            hardware_id=hardware_id(node.get_namespace()),
        )
        self._parts: dict[str, DiagnosticStatus] = {}
        self._silent_after_s = silent_after_s
        self._clock_s = clock_s
        self._updated_s = time.monotonic()
        node.create_timer(period_s, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def update(self, level: bytes, message: str, values: dict[str, Any]) -> None:
        """Set the status published next (level: OK, WARN or ERROR)."""
        self._status.level = level
        self._status.message = message
        self._status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
        self._updated_s = time.monotonic()

    def update_part(self, part: str, level: bytes, message: str, values: dict[str, Any]) -> None:
        """Set the status of one of the node's parts (named `<node>/<part>`)."""
        self._parts[part] = DiagnosticStatus(
            level=level, name=f"{self._status.name}/{part}", message=message,
            hardware_id=self._status.hardware_id,
            values=[KeyValue(key=key, value=str(value)) for key, value in values.items()])

    def publish(self) -> None:
        if self._before_publish is not None:
            self._before_publish()
        status, silent_s = self._status, time.monotonic() - self._updated_s
        level, message = status.level, status.message
        if self._silent_after_s is not None and silent_s > self._silent_after_s:
            level = max(level, WARN)  # an ERROR stays one
            message = f"no input for {silent_s:.0f} s (last: {status.message})"
        published = DiagnosticStatus(
            level=level, name=status.name, hardware_id=status.hardware_id, message=message,
            values=[*status.values, KeyValue(key=CPU_KEY, value=f"{time.process_time():.3f}")])
        array = DiagnosticArray(status=[published, *self._parts.values()])
        array.header.stamp = (self._node.get_clock().now().to_msg() if self._clock_s is None
                              else stamp(self._clock_s()))
        self._publisher.publish(array)

    def publish_last(self, timeout_s: float = 1.0) -> None:
        """Publish now and wait up to timeout_s [s] until the subscribers have it: a node
        about to end says its last status (its whole CPU time)."""
        self.publish()
        self._publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout_s))


NodeType = TypeVar("NodeType", bound=Node)

# Exit statuses of a node's process.
EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
STOP_POLL_S = 0.1  # longest wait of spin() between looks at a stop signal [s, wall time]
# A node still running this long after a stop signal prints every thread's stack on stderr
# (faulthandler's own thread: it also reports a main thread stuck inside C) [s, wall time];
# before ros_processes.stop_all kills what remains.
STUCK_STOP_S = STOP_TIMEOUT_S - 2.0


class Stopped(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived: the node ends, with status 0."""


class _StopRequest:
    """The stop signal received, if any, and whether the handler raises Stopped at once
    (in a node's own run loop) or only records it (in spin(), which looks between callbacks:
    raised inside a callback or a message conversion, pybind11 and the executor turn it into
    other errors)."""

    signal: int | None = None
    raises = True


def _stop(signum: int, _frame: object) -> None:
    for sig in STOP_SIGNALS:  # once is enough: the node's clean-up is not interrupted
        signal.signal(sig, signal.SIG_IGN)
    _StopRequest.signal = signum
    faulthandler.dump_traceback_later(STUCK_STOP_S, exit=False)
    if _StopRequest.raises:
        raise Stopped(signal.Signals(signum).name)


def spin(node: Node) -> None:
    """rclpy.spin until a stop signal: the wait for work ends every STOP_POLL_S to look for
    one (a Python signal handler runs only between Python statements), and a signal ends it
    between callbacks, never inside one.

    rclpy's EventsExecutor (C++, callbacks in the order their events came) rather than the
    SingleThreadedExecutor (a Python wait set rebuilt for every callback): the default demo's
    nodes took 6 / 5 / 10 ms of CPU per simulated second (detector, mhe, residual) instead
    of 11 / 7 / 15, and the graph flew at 36.6-37.2 times real time instead of 28-31
    (docs/performance.md). The nodes' timers all run on the steady clock: sim-time timers
    under an events executor are not relied on (rclcpp's lacked them, ros2/rclcpp#2457)."""
    executor = EventsExecutor()
    executor.add_node(node)
    _StopRequest.raises = False
    try:
        while executor.context.ok() and _StopRequest.signal is None:
            executor.spin_once(timeout_sec=STOP_POLL_S)
    finally:
        _StopRequest.raises = True
        executor.remove_node(node)
        executor.shutdown(timeout_sec=0.0)


def _rcl_message(error: Exception) -> str:
    """rcl's error text without its source locations (`, at /project/src/x.c:12`)."""
    text = re.sub(r", at \S+:\d+", "", str(error))
    return text.removeprefix("failed to initialize rcl: ")


class _Arguments:
    """The arguments rclpy was initialised with by run_node (None: the process's own)."""

    given: list[str] | None = None


def _process_arguments() -> list[str]:
    """The arguments the node's ROS arguments come from."""
    return _Arguments.given if _Arguments.given is not None else sys.argv


def _init(name: str, args: list[str] | None) -> bool:
    """rclpy.init without rclpy's signal handlers; False, after one line, when rcl cannot
    parse the arguments (a params file that does not parse or does not exist, a bad -p)."""
    _Arguments.given = args
    # rcl's own `Failed to parse global arguments` line would come before ours: muted.
    rclpy.logging.set_logger_level("rcl", rclpy.logging.LoggingSeverity.FATAL)
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except _rclpy.RCLError as error:
        print(f"{name}: bad ROS arguments: {_rcl_message(error)}", file=sys.stderr)
        return False
    finally:
        if rclpy.logging.get_logger_level("rcl") == rclpy.logging.LoggingSeverity.FATAL:
            rclpy.logging.set_logger_level("rcl", rclpy.logging.LoggingSeverity.UNSET)
    return True


def run_node(
    name: str,
    make_node: Callable[[], NodeType],
    run: Callable[[NodeType], None] = spin,
    args: list[str] | None = None,
) -> int:
    """A node's main: init, make the node, run it, shut down; the exit status.

    Bad input (arguments rcl cannot parse, a bad parameter or scenario: a ValueError while
    making or running the node) ends the process with one line on stderr and status 2.
    SIGINT and SIGTERM end it with status 0, however it was started: the node handles both
    itself (also a SIGINT its starter ignored, as `cmd &` in a script does), rclpy's context
    staying valid for the clean-up (rclpy's own handlers shut the context down under the
    running node: RCLError tracebacks). spin() ends between callbacks; a node's own `run`
    gets Stopped (a KeyboardInterrupt) raised in its main thread.
    """
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, _stop)
    node = None
    try:
        if not _init(name, args):
            return EXIT_BAD_INPUT
        node = make_node()
        run(node)
        return EXIT_OK
    except (KeyboardInterrupt, ExternalShutdownException):
        return EXIT_OK
    except Exception as error:
        if _StopRequest.signal is not None:
            # an error the stop caused: Stopped raised inside a call into C++ (a message
            # conversion) comes out as another exception
            return EXIT_OK
        if isinstance(error, ValueError):
            print(f"{name}: {error}", file=sys.stderr)
            return EXIT_BAD_INPUT
        raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
