"""A vehicle's propeller as JSBSim's FGPropeller computes it, from the same XML tables.

The prediction model and the trim need the propeller's force and moment for a given engine
speed, but JSBSim's propeller speed is a read-only state of its own engine model. This
module evaluates the equations of JSBSim's fixed-pitch propeller (jsbsim 1.3.3,
FGPropeller::Calculate) on the tables of the vehicle's propeller file, driven by its engine
file's power source (JSBSim's electric engine: shaft power = effective throttle x power):

    J = V_axial / (n D),  T = C_T(J) rho n^2 D^4,  P_required = C_P(J) rho n^3 D^5,
    torque reaction  Q = -P_engine / omega,  gyroscopic moment  omega_body x (I_p omega e_x).

The propeller's own speed dynamics are not modelled here: the engine speed is measured.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq

if TYPE_CHECKING:
    from uav_aircraft.vehicles import Vehicle


def _table(root: ET.Element, name: str) -> tuple[np.ndarray, np.ndarray]:
    text = root.find(f"table[@name='{name}']/tableData").text
    values = np.array(text.split(), dtype=float).reshape(-1, 2)
    return values[:, 0], values[:, 1]


@dataclass(frozen=True)
class PropellerForces:
    """Thrust [N] along body x and moment [N m] about the propeller hub, body axes."""

    thrust_n: float
    moment_nm: np.ndarray


@dataclass(frozen=True)
class Propeller:
    """Fixed-pitch propeller driven by an engine of `max_power_w` at full effective throttle."""

    diameter_m: float
    inertia_kg_m2: float
    advance_ratio: np.ndarray
    thrust_coefficient: np.ndarray
    power_coefficient: np.ndarray
    max_power_w: float

    @classmethod
    def from_vehicle(cls, vehicle: Vehicle) -> Propeller:
        """Read the vehicle's propeller and engine XML."""
        propeller = ET.parse(vehicle.propeller_file).getroot()
        engine = ET.parse(vehicle.engine_file).getroot()
        j_ct, ct = _table(propeller, "C_THRUST")
        j_cp, cp = _table(propeller, "C_POWER")
        if not np.array_equal(j_ct, j_cp):
            raise ValueError("propeller tables must share their advance ratios")
        return cls(
            diameter_m=float(propeller.find("diameter").text),
            inertia_kg_m2=float(propeller.find("ixx").text),
            advance_ratio=j_ct,
            thrust_coefficient=ct,
            power_coefficient=cp,
            max_power_w=float(engine.find("power").text),
        )

    def _advance_ratio(self, rpm: float, axial_speed_mps: float) -> float:
        rps = rpm / 60.0
        # FGPropeller: below 0.01 rev/s, J is taken as if n were 1 rev/s.
        return axial_speed_mps / (self.diameter_m * (rps if rps > 0.01 else 1.0))

    def thrust_n(self, rpm: float, axial_speed_mps: float, density_kg_m3: float) -> float:
        """T = C_T(J) rho n^2 D^4 [N]."""
        j = self._advance_ratio(rpm, axial_speed_mps)
        ct = np.interp(j, self.advance_ratio, self.thrust_coefficient)
        return float(ct * density_kg_m3 * (rpm / 60.0) ** 2 * self.diameter_m**4)

    def power_required_w(self, rpm: float, axial_speed_mps: float, density_kg_m3: float) -> float:
        """P = C_P(J) rho n^3 D^5 [W]."""
        j = self._advance_ratio(rpm, axial_speed_mps)
        cp = np.interp(j, self.advance_ratio, self.power_coefficient)
        return float(cp * density_kg_m3 * max(rpm / 60.0, 0.01) ** 3 * self.diameter_m**5)

    def forces(
        self,
        rpm: float,
        effective_throttle: float,
        axial_speed_mps: float,
        density_kg_m3: float,
        body_rates_radps: np.ndarray,
    ) -> PropellerForces:
        """Thrust and hub moment (torque reaction plus gyroscopic) at a measured speed."""
        omega_radps = 2.0 * math.pi * rpm / 60.0
        engine_power_w = effective_throttle * self.max_power_w
        angular_momentum = self.inertia_kg_m2 * omega_radps
        _, q, r = body_rates_radps  # spin axis body x: roll rate adds no gyroscopic moment
        moment = np.array(
            [
                -engine_power_w / max(0.01, omega_radps),
                r * angular_momentum,
                -q * angular_momentum,
            ]
        )
        return PropellerForces(self.thrust_n(rpm, axial_speed_mps, density_kg_m3), moment)

    def steady_rpm(
        self, effective_throttle: float, axial_speed_mps: float, density_kg_m3: float
    ) -> float:
        """Engine speed [rpm] at which the propeller absorbs the engine's power."""
        engine_power_w = effective_throttle * self.max_power_w
        if engine_power_w <= 0.0:
            return 0.0

        def excess_power_w(rpm: float) -> float:
            return engine_power_w - self.power_required_w(rpm, axial_speed_mps, density_kg_m3)

        return float(brentq(excess_power_w, 100.0, 30000.0, xtol=1e-6))
