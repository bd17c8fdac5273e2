"""What every node says on /diagnostics that tools read back (report.py): the hardware id it
names and the key of its CPU time. No ROS here."""

AIRCRAFT = "aircraft"  # the hardware every node diagnoses; its namespace names which one
CPU_KEY = "cpu_s"  # every status's value: the node's process CPU time so far [s]


def hardware_id(namespace: str) -> str:
    """The hardware_id of the nodes in namespace ("/" or "" for none; "/uav1")."""
    return AIRCRAFT + ("" if namespace in ("", "/") else namespace)
