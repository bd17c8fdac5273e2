"""Fault diagnosis of fixed-wing UAVs (core modules import no rclpy)."""
