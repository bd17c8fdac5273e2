"""standard_topics_node: the aircraft and its fault estimate in ROS's standard messages, for
tools that know only those (RViz, Foxglove's 3D and Map panels, PlotJuggler, tf2).

Subscribes `state` (from sim_node or log_replay_node), `faults/estimate` and `faults/seeded`;
publishes, each stamped with its state's stamp (standard_frames.py has the frames' maths):

    /tf                          tf2_msgs/TFMessage     map -> base_link
    odom                         nav_msgs/Odometry      pose in map, twist in base_link
    imu                          sensor_msgs/Imu        base_link: attitude, rates, specific force
    fix                          sensor_msgs/NavSatFix  frame base_link
    track                        nav_msgs/Path          the flown track in map, every track_period_s
    faults/estimate_pct/<fault>  std_msgs/Float64       each fault's estimate [%]
    faults/seeded_pct/<fault>    std_msgs/Float64       each seeded fault [%]

Under a namespace the body frame is `<namespace>/base_link` (`uav2/base_link`) and `map` is
shared: give every vehicle's node the same map_origin to see them in one map.
"""

from __future__ import annotations

import math
import sys

import numpy as np
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, TransformStamped, Vector3
from nav_msgs.msg import Odometry, Path
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu, NavSatFix, NavSatStatus
from std_msgs.msg import Float64, Header
from tf2_msgs.msg import TFMessage
from uav_common.envelope import STATE_LIMITS, gate, state_rate_gate
from uav_common.message_fields import stamp_nanoseconds, stamp_seconds, state_array
from uav_common.ros.diagnostics import OK, WARN, Diagnostics
from uav_common.ros.matched_streams import guarded
from uav_common.ros.node_life import run_node, when_subscribed
from uav_common.ros.parameters import (
    QOS_PARAMETER,
    WAIT_FOR_SUBSCRIBERS_PARAMETER,
    ParameterSpec,
    declare_parameters,
)
from uav_common.ros.qos import STREAM_QOS_PROFILES
from uav_common.stamp_matching import GuardedStream, StampVerdict
from uav_fault_msgs.msg import AircraftState, FaultEstimate, FaultVector

from uav_fault_estimator.viewing.standard_frames import GeodeticPoint, StandardFrames, StandardState

PARAMETERS = {
    "map_origin_from_first_state": ParameterSpec(
        "true: map's origin is the first state's position; false: map_origin", True),
    "map_origin": ParameterSpec(
        "map's origin when not the first state's: latitude [deg], longitude [deg], altitude "
        "[m]", [55.6, 12.5, 0.0]),
    "track_period_s": ParameterSpec("sim time between the track's poses [s]", 1.0, 0.05, 60.0),
    "track_poses": ParameterSpec("poses the track keeps, the newest (an hour at 1 s)", 3600,
                                 2, 100000),
    "qos": QOS_PARAMETER,
    "wait_for_subscribers": WAIT_FOR_SUBSCRIBERS_PARAMETER,
}
MAP_FRAME, BODY_FRAME = "map", "base_link"  # REP 105's names
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)  # tf2's own for /tf
LATEST_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
UNKNOWN_COVARIANCE = -1.0  # sensor_msgs/Imu: element 0 of a covariance, the value is absent


def _vector3(values: np.ndarray) -> Vector3:
    return Vector3(x=float(values[0]), y=float(values[1]), z=float(values[2]))


def _pose(state: StandardState) -> Pose:
    x, y, z = map(float, state.position_enu_m)
    qx, qy, qz, qw = map(float, state.orientation_xyzw)
    return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def _with_covariance(values: np.ndarray) -> tuple[Vector3, np.ndarray]:
    """A Vector3 and its covariance: all zeros (unknown) when finite, else the value's
    absence (zeros, element 0 of the covariance -1, as sensor_msgs/Imu defines)."""
    covariance = np.zeros(9)
    if not np.isfinite(values).all():
        covariance[0] = UNKNOWN_COVARIANCE
        values = np.zeros(3)
    return _vector3(values), covariance


def imu_message(header: Header, state: StandardState) -> Imu:
    """sensor_msgs/Imu in base_link; what the state lacks is marked absent."""
    message = Imu(header=header)
    if np.isfinite(state.orientation_xyzw).all():
        message.orientation = _pose(state).orientation
    else:
        message.orientation_covariance[0] = UNKNOWN_COVARIANCE
    message.angular_velocity, message.angular_velocity_covariance = _with_covariance(
        state.angular_velocity_flu_radps)
    message.linear_acceleration, message.linear_acceleration_covariance = _with_covariance(
        state.specific_force_flu_mps2)
    return message


def fix_message(header: Header, state: StandardState) -> NavSatFix:
    """sensor_msgs/NavSatFix; NO_FIX while the position is missing."""
    point = state.position
    has_fix = all(map(math.isfinite, (point.latitude_deg, point.longitude_deg, point.altitude_m)))
    status = NavSatStatus.STATUS_FIX if has_fix else NavSatStatus.STATUS_NO_FIX
    return NavSatFix(
        header=header, status=NavSatStatus(status=status, service=NavSatStatus.SERVICE_GPS),
        latitude=point.latitude_deg, longitude=point.longitude_deg, altitude=point.altitude_m,
        position_covariance_type=NavSatFix.COVARIANCE_TYPE_UNKNOWN)


def odometry_message(header: Header, body_frame: str, pose: Pose,
                     state: StandardState) -> Odometry:
    """nav_msgs/Odometry: pose of body_frame in map, twist in body_frame."""
    message = Odometry(header=header, child_frame_id=body_frame)
    message.pose.pose = pose
    message.twist.twist.linear = _vector3(state.velocity_flu_mps)
    message.twist.twist.angular = _vector3(state.angular_velocity_flu_radps)
    return message


def transform_message(header: Header, body_frame: str, pose: Pose) -> TFMessage:
    """/tf's map -> body_frame at pose."""
    transform = TransformStamped(header=header, child_frame_id=body_frame)
    transform.transform.translation = Vector3(x=pose.position.x, y=pose.position.y,
                                              z=pose.position.z)
    transform.transform.rotation = pose.orientation
    return TFMessage(transforms=[transform])


class StandardTopicsNode(Node):
    """Thin adapter: each state through StandardFrames into the standard messages."""

    def __init__(self) -> None:
        super().__init__("standard_topics_node")
        p = declare_parameters(self, PARAMETERS)
        self.frames = StandardFrames(None if p["map_origin_from_first_state"]
                                     else _origin(p["map_origin"]))
        namespace = self.get_namespace().strip("/")
        self.body_frame = f"{namespace}/{BODY_FRAME}" if namespace else BODY_FRAME
        self.track_period_s, self.track_poses = p["track_period_s"], p["track_poses"]
        self.track = Path(header=Header(frame_id=MAP_FRAME))
        qos = STREAM_QOS_PROFILES[p["qos"]]
        self.publishers_ = {
            "tf": self.create_publisher(TFMessage, "/tf", TF_QOS),
            "odom": self.create_publisher(Odometry, "odom", qos),
            "imu": self.create_publisher(Imu, "imu", qos),
            "fix": self.create_publisher(NavSatFix, "fix", qos),
            "track": self.create_publisher(Path, "track", LATEST_QOS),
        }
        self.fault_publishers: dict[str, object] = {}
        self.stream, self.rate_gate = GuardedStream(), state_rate_gate()
        self.counts = {"states": 0, "without_pose": 0, "implausible_values": 0, "restarts": 0}
        when_subscribed(self, self.publishers_["odom"], p["wait_for_subscribers"],
                        lambda: self.subscribe(qos))
        self.diagnostics = Diagnostics(self)

    def subscribe(self, qos: QoSProfile) -> None:
        """The inputs: state, and the estimated and seeded faults."""
        self.create_subscription(AircraftState, "state", self.on_state, qos)
        self.create_subscription(FaultEstimate, "faults/estimate",
                                 lambda m: self.on_faults("estimate", m), qos)
        self.create_subscription(FaultVector, "faults/seeded",
                                 lambda m: self.on_faults("seeded", m), qos)

    def on_state(self, message: AircraftState) -> None:
        verdict, taken = guarded(self, self.stream, "state",
                                 stamp_nanoseconds(message.header.stamp), message,
                                 "the track and the acceleration's difference start again")
        if verdict is StampVerdict.RESTART:
            self.frames.reset()
            self.rate_gate.reset()
            self.track.poses.clear()
            self.counts["restarts"] += 1
        for stamp_ns, taken_message in taken:
            self.publish_state(stamp_ns / 1e9, taken_message)

    def publish_state(self, time_s: float, message: AircraftState) -> None:
        """Every standard message of one state."""
        values, implausible = gate(state_array(message), STATE_LIMITS)
        values, glitches = self.rate_gate(time_s, values)
        state = self.frames.update(time_s, values)
        header = Header(stamp=message.header.stamp, frame_id=self.body_frame)
        self.publishers_["imu"].publish(imu_message(header, state))
        self.publishers_["fix"].publish(fix_message(header, state))
        self.counts["states"] += 1
        self.counts["implausible_values"] += implausible + glitches
        if np.isfinite(state.position_enu_m).all() and np.isfinite(state.orientation_xyzw).all():
            map_header = Header(stamp=message.header.stamp, frame_id=MAP_FRAME)
            pose = _pose(state)
            self.publishers_["odom"].publish(
                odometry_message(map_header, self.body_frame, pose, state))
            self.publishers_["tf"].publish(transform_message(map_header, self.body_frame, pose))
            self.extend_track(map_header, state.time_s, pose)
        else:
            self.counts["without_pose"] += 1
        self.report(time_s)

    def extend_track(self, header: Header, time_s: float, pose: Pose) -> None:
        """A pose on the track every track_period_s of the state's time; published then."""
        poses = self.track.poses
        if poses and time_s - stamp_seconds(poses[-1].header.stamp) < self.track_period_s:
            return
        poses.append(PoseStamped(header=header, pose=pose))
        del poses[:-self.track_poses]
        self.track.header.stamp = header.stamp
        self.publishers_["track"].publish(self.track)

    def on_faults(self, kind: str, message: FaultEstimate | FaultVector) -> None:
        """Each fault's value on faults/<kind>_pct/<name>, its publisher made on first use."""
        if len(message.names) != len(message.values_pct):
            self.get_logger().warning(f"faults/{kind}: {len(message.names)} names for "
                                      f"{len(message.values_pct)} values: message dropped",
                                      throttle_duration_sec=5.0)
            return
        for name, value in zip(message.names, message.values_pct, strict=True):
            topic = f"faults/{kind}_pct/{name}"
            if topic not in self.fault_publishers:
                try:
                    self.fault_publishers[topic] = self.create_publisher(Float64, topic,
                                                                         LATEST_QOS)
                except Exception as error:  # rclpy's InvalidTopicNameException and kin
                    self.get_logger().warning(f"no topic for fault {name!r}: {error}",
                                              once=True)
                    continue
            self.fault_publishers[topic].publish(Float64(data=float(value)))

    def report(self, time_s: float) -> None:
        missing = self.counts["without_pose"]
        level = WARN if missing and self.counts["states"] == missing else OK
        self.diagnostics.update(level, f"state at {time_s:.2f} s in map and {self.body_frame}"
                                if level == OK else "no state with a position and attitude yet",
                                {**self.counts, "strays": self.stream.strays,
                                 "fault_topics": len(self.fault_publishers)})


def _origin(values: list[float]) -> GeodeticPoint:
    """map_origin's three values; ValueError (bad input, one line) otherwise."""
    if len(values) != 3 or not -90.0 <= values[0] <= 90.0 or not -180.0 <= values[1] <= 180.0:
        raise ValueError(f"map_origin {values}: it must be [latitude in [-90, 90] deg, "
                         "longitude in [-180, 180] deg, altitude m]")
    return GeodeticPoint(*map(float, values))


def main(args: list[str] | None = None) -> int:
    return run_node("standard_topics_node", StandardTopicsNode, args=args)


if __name__ == "__main__":
    sys.exit(main())
