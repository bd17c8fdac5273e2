"""An autopilot's MAVLink link as the project's streams."""
