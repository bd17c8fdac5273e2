"""The `vehicle` parameter every node that models an aircraft declares (residual_node,
mhe_node, detector_node, through their cores' settings): one declaration, the shipped
vehicles its choices; and the fuel mass of an aircraft whose link does not say it
(mavlink_node), by default the vehicle's. No rclpy here: the settings (uav_common.settings)
take them."""

from uav_common.settings import ParameterSpec

from uav_aircraft.vehicles import DEFAULT_VEHICLE, vehicle_names

VEHICLE_PARAMETER = ParameterSpec(
    "the aircraft modelled: a folder of uav_aircraft's aircraft/ (docs/aircraft.md), whose model, "
    "noise model and calibrations the node loads", DEFAULT_VEHICLE, choices=vehicle_names())

# A fuel mass setting's "the vehicle's": what its model carries at the start of a flight
# (uav_aircraft.fdm.fuel_on_board_kg resolves it).
VEHICLE_FUEL_KG = -1.0
FUEL_MASS_PARAMETER = ParameterSpec(
    "the fuel on board, which no autopilot streams; -1: what the vehicle's model carries at "
    "the start of a flight (its XML's propulsion/fuel-loaded-lbs; 0 on an electric "
    "aircraft) [kg]", VEHICLE_FUEL_KG, VEHICLE_FUEL_KG, 1000.0)
