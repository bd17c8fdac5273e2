"""The `vehicle` parameter every node that models an aircraft declares (residual_node,
mhe_node, detector_node, through their cores' settings): one declaration, the shipped
vehicles its choices. No rclpy here: the settings (uav_common.settings) take it."""

from uav_common.settings import ParameterSpec

from uav_aircraft.vehicles import DEFAULT_VEHICLE, vehicle_names

VEHICLE_PARAMETER = ParameterSpec(
    "the aircraft modelled: a folder of uav_aircraft's aircraft/ (docs/aircraft.md), whose model, "
    "noise model and calibrations the node loads", DEFAULT_VEHICLE, choices=vehicle_names())
