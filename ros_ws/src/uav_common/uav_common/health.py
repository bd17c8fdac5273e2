"""What every node says on /diagnostics that tools read back (report.py): the hardware id it
names, the key of its CPU time, and the simulator's keys the report reads. No ROS here."""

AIRCRAFT = "aircraft"  # the hardware every node diagnoses; its namespace names which one
CPU_KEY = "cpu_s"  # every status's value: the node's process CPU time so far [s]
# sim_node's values: the scenario's guidance method, and its steps flown on the vector field
# because the MPC guidance's QP was not solved
GUIDANCE_KEY, GUIDANCE_FALLBACKS_KEY = "guidance", "guidance_fallbacks"


def hardware_id(namespace: str) -> str:
    """The hardware_id of the nodes in namespace ("/" or "" for none; "/uav1")."""
    return AIRCRAFT + ("" if namespace in ("", "/") else namespace)
