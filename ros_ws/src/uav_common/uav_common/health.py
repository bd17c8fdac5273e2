"""What every node says on /diagnostics that tools read back (report.py, the calibration
commands): the hardware id it names, the key of its CPU time, the simulator's keys the
report reads, and the vehicle an aircraft's source says flew. No ROS here."""

AIRCRAFT = "aircraft"  # the hardware every node diagnoses; its namespace names which one
CPU_KEY = "cpu_s"  # every status's value: the node's process CPU time so far [s]
# sim_node's values: the scenario's guidance method, and its steps flown on the vector field
# because the MPC guidance's QP was not solved
GUIDANCE_KEY, GUIDANCE_FALLBACKS_KEY = "guidance", "guidance_fallbacks"
# The vehicle that flies, as the aircraft's source (sim_node, mavlink_node) says it: what a
# recording says flew (recording.project_bag.recorded_vehicle)
VEHICLE_KEY = "vehicle"


def hardware_id(namespace: str) -> str:
    """The hardware_id of the nodes in namespace ("/" or "" for none; "/uav1")."""
    return AIRCRAFT + ("" if namespace in ("", "/") else namespace)
