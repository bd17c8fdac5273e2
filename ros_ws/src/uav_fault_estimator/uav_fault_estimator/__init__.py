"""Fault diagnosis of the Aerosonde UAV (core modules import no rclpy)."""
