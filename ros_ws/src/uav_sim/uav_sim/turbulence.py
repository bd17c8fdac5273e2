"""Von Karman turbulence from the background wind (MIL-F-8785C), as the paper's simulator had.

The embedded-estimation paper (section IV) applied von Karman shaping filters to three white
noise sources, with parameters from the background wind magnitude and the altitude, and
shear effects on pitch and yaw. JSBSim 1.3.3 has only Dryden forms, so this module writes
the von Karman filters itself and the simulation drives JSBSim's gust properties with them:

- Intensities and scale lengths (`milspec_scales`): MIL-F-8785C, 3.7.2-3.7.3, with the
  background wind speed as the wind at 20 ft; the low-altitude model below 1000 ft, the
  medium/high-altitude one above 2000 ft, linear in altitude between.
- Linear gusts u, v, w (`shaping_filters`): rational approximations of the von Karman
  spectra. The textbook second/third-order forms (MIL-HDBK-1797, MATLAB's Von Karman block)
  fall 3 dB below the spectrum above T omega of about 100, inside 0.05-2 Hz at our scale
  lengths, so the poles and zeros below are a least-squares fit of the log spectrum over
  T omega 1e-3..5e3 (T = L/V): within 0.4 dB there, -5/3 slope included.
- Rotational gusts p, q, r: MIL-F-8785C's forms (p from the spanwise gradient of w, q and r
  from the along-path gradients of w and v), in body axes; they enter the aircraft's rate
  derivatives through `atmosphere/gust-{p,q,r}-rad_sec` (every vehicle's XML).
- Discretisation is exact for white noise through a linear system (Van Loan), and the state
  starts in its stationary distribution: no start-up transient, any step size.

The filters use the scenario's airspeed and altitude, which the autopilot holds. The linear
gusts are in turbulence axes (u along the horizontal mean wind, v to its right, w down), the
low-altitude convention of MIL-F-8785C and MATLAB's blocks. No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm, solve_continuous_lyapunov
from uav_aircraft.fdm import M_PER_FT, MPS_PER_KT

VON_KARMAN_A = 1.339  # the von Karman spectra's constant (MIL-F-8785C, 3.7.2)

LOW_ALTITUDE_FT = 1000.0  # at and below: the low-altitude model
HIGH_ALTITUDE_FT = 2000.0  # at and above: the medium/high-altitude model
MIN_ALTITUDE_FT = 10.0  # the low-altitude formulas are clipped here
HIGH_ALTITUDE_SCALE_FT = 2500.0  # von Karman scale length above 2000 ft (3.7.2.1)

# MIL-F-8785C, Figure 7: sigma [ft/s] above 2000 ft against altitude [ft], for the
# probabilities of exceedance that 3.7.2.1 names light (1e-2), moderate (1e-3) and severe
# (1e-5); 3.7.2.2 puts the wind at 20 ft of those levels at 15, 30 and 45 knots. A wind at
# 20 ft between those interpolates linearly (zero wind, zero sigma), beyond 45 kt severe.
POE_ALTITUDES_FT = (500.0, 1750.0, 3750.0, 7500.0, 15000.0, 25000.0, 35000.0, 45000.0,
                    55000.0, 65000.0, 75000.0, 80000.0)
POE_SIGMA_FTPS = {
    15.0: (6.6, 6.9, 7.4, 6.7, 4.6, 2.7, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0),
    30.0: (8.6, 9.6, 10.6, 10.1, 8.0, 6.6, 5.0, 4.2, 2.7, 0.0, 0.0, 0.0),
    45.0: (15.6, 17.6, 23.0, 23.6, 22.1, 20.0, 16.0, 15.1, 12.1, 7.9, 6.2, 5.1),
}

# Normalised shaping filters |H(j x)|^2 ~ S(x), x = T omega, T = L / V: zeros and poles
# [1/T] of prod(1 + s T / z) / prod(1 + s T / p), fitted as the module docstring says.
LONGITUDINAL_ZEROS = (5.3148, 68.770, 909.89)
LONGITUDINAL_POLES = (0.86948, 8.1159, 105.53, 1420.0)
LATERAL_ZEROS = (0.33674, 9.6165, 102.64, 1118.5)
LATERAL_POLES = (0.40068, 1.3319, 14.261, 152.38, 1695.8)


@dataclass(frozen=True)
class TurbulenceScales:
    """Standard deviations [m/s] and scale lengths [m] of the u, v, w gusts."""

    sigma_mps: tuple[float, float, float]
    length_m: tuple[float, float, float]


def _low_altitude(wind_at_20ft_mps: float, altitude_ft: float) -> TurbulenceScales:
    """MIL-F-8785C 3.7.3: L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2 [ft],
    sigma_w = 0.1 W20, sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4."""
    h_ft = max(altitude_ft, MIN_ALTITUDE_FT)
    factor = 0.177 + 0.000823 * h_ft
    sigma_w = 0.1 * wind_at_20ft_mps
    sigma_uv = sigma_w / factor**0.4
    length_uv_m = h_ft / factor**1.2 * M_PER_FT
    return TurbulenceScales((sigma_uv, sigma_uv, sigma_w),
                            (length_uv_m, length_uv_m, h_ft * M_PER_FT))


def _high_altitude(wind_at_20ft_mps: float, altitude_ft: float) -> TurbulenceScales:
    """MIL-F-8785C 3.7.2.1: isotropic, sigma from Figure 7, L = 2500 ft."""
    knots = wind_at_20ft_mps / MPS_PER_KT
    anchors_kt = (0.0, *POE_SIGMA_FTPS)
    sigmas = (0.0, *(np.interp(altitude_ft, POE_ALTITUDES_FT, row)
                     for row in POE_SIGMA_FTPS.values()))
    sigma_mps = float(np.interp(knots, anchors_kt, sigmas)) * M_PER_FT
    length_m = HIGH_ALTITUDE_SCALE_FT * M_PER_FT
    return TurbulenceScales((sigma_mps,) * 3, (length_m,) * 3)


def milspec_scales(wind_at_20ft_mps: float, altitude_m: float) -> TurbulenceScales:
    """Gust intensities and scale lengths at altitude_m for a wind at 20 ft of
    wind_at_20ft_mps (MIL-F-8785C; between 1000 and 2000 ft linear in altitude)."""
    altitude_ft = altitude_m / M_PER_FT
    if altitude_ft <= LOW_ALTITUDE_FT:
        return _low_altitude(wind_at_20ft_mps, altitude_ft)
    if altitude_ft >= HIGH_ALTITUDE_FT:
        return _high_altitude(wind_at_20ft_mps, altitude_ft)
    low = _low_altitude(wind_at_20ft_mps, LOW_ALTITUDE_FT)
    high = _high_altitude(wind_at_20ft_mps, HIGH_ALTITUDE_FT)
    weight = (altitude_ft - LOW_ALTITUDE_FT) / (HIGH_ALTITUDE_FT - LOW_ALTITUDE_FT)
    return TurbulenceScales(
        tuple(a + weight * (b - a) for a, b in zip(low.sigma_mps, high.sigma_mps, strict=True)),
        tuple(a + weight * (b - a) for a, b in zip(low.length_m, high.length_m, strict=True)),
    )


def von_karman_psd(axis: str, frequency_radps: np.ndarray, sigma_mps: float,
                   length_m: float, airspeed_mps: float) -> np.ndarray:
    """One-sided von Karman power spectral density [(m/s)^2 / (rad/s)] of the u (longitudinal)
    or v / w (lateral, vertical) gust met at airspeed_mps (MIL-F-8785C, 3.7.2): its integral
    over omega >= 0 is sigma^2."""
    x = VON_KARMAN_A * length_m * np.asarray(frequency_radps) / airspeed_mps
    scale = sigma_mps**2 * length_m / (math.pi * airspeed_mps)
    if axis == "u":
        return 2.0 * scale / (1.0 + x**2) ** (5.0 / 6.0)
    return scale * (1.0 + 8.0 / 3.0 * x**2) / (1.0 + x**2) ** (11.0 / 6.0)


@dataclass(frozen=True)
class StateSpace:
    """x' = A x + B n, y = C x, n unit white noise (two-sided PSD 1)."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray


def _cascade(gain: float, zeros: tuple[float, ...], poles: tuple[float, ...],
             time_s: float) -> StateSpace:
    """gain prod(1 + s T / z_i) / prod(1 + s T / p_j) with one more pole than zeros, as
    first-order sections in series (well conditioned where a companion form is not)."""
    a, b, c, d = np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), gain
    for zero, pole in zip((*zeros, None), poles, strict=True):
        rate = pole / time_s
        # (1 + s/z)/(1 + s/p) = p/z + (p/z)(z - p)/(s + p); 1/(1 + s/p) = p/(s + p).
        if zero is None:
            section_c, section_d = rate, 0.0
        else:
            section_d = pole / zero
            section_c = section_d * (zero - pole) / time_s
        # In series: the section's input is the previous output c x + d n.
        size = a.shape[0]
        a = np.block([[a, np.zeros((size, 1))], [c, np.array([[-rate]])]])
        b = np.vstack([b, [[d]]])
        c = np.hstack([section_d * c, [[section_c]]])
        d = section_d * d
    return StateSpace(a, b, c)


def _block_diagonal(systems: list[StateSpace]) -> StateSpace:
    states = sum(system.a.shape[0] for system in systems)
    a = np.zeros((states, states))
    b = np.zeros((states, len(systems)))
    c = np.zeros((len(systems), states))
    start = 0
    for index, system in enumerate(systems):
        stop = start + system.a.shape[0]
        a[start:stop, start:stop] = system.a
        b[start:stop, index] = system.b[:, 0]
        c[index, start:stop] = system.c[0]
        start = stop
    return StateSpace(a, b, c)


def shaping_filters(scales: TurbulenceScales, airspeed_mps: float,
                    wingspan_m: float) -> StateSpace:
    """One linear system from four unit white noises to the gusts [u, v, w] [m/s] and
    [p, q, r] [rad/s] (MIL-F-8785C, 3.7.2, von Karman forms):

    H_u = sigma_u sqrt(2 T_u) H^_u(T_u s),  H_v,w = sigma sqrt(T) H^_v(T s)   (T = L / V)
    H_p = sigma_w sqrt(0.8 pi / (V L_w)) (pi L_w / (4 b))^(1/6) / (1 + 4 b s / (pi V))
    q = (s / V) / (1 + 4 b s / (pi V)) w,   r = -(s / V) / (1 + 3 b s / (pi V)) v

    so that |H(j omega)|^2 = pi times the one-sided spectrum of von_karman_psd.
    """
    (sigma_u, sigma_v, sigma_w), (length_u, length_v, length_w) = scales.sigma_mps, scales.length_m
    speed = airspeed_mps
    time_u, time_v, time_w = length_u / speed, length_v / speed, length_w / speed
    tau_p = 4.0 * wingspan_m / (math.pi * speed)
    gain_p = (sigma_w * math.sqrt(0.8 * math.pi / (speed * length_w))
              * (math.pi * length_w / (4.0 * wingspan_m)) ** (1.0 / 6.0))
    linear = _block_diagonal([
        _cascade(sigma_u * math.sqrt(2.0 * time_u), LONGITUDINAL_ZEROS, LONGITUDINAL_POLES,
                 time_u),
        _cascade(sigma_v * math.sqrt(time_v), LATERAL_ZEROS, LATERAL_POLES, time_v),
        _cascade(sigma_w * math.sqrt(time_w), LATERAL_ZEROS, LATERAL_POLES, time_w),
        _cascade(gain_p, (), (1.0,), tau_p),
    ])
    # q and r: first-order lags z of w and v; (s/V)/(1 + tau s) x = (x - z) / (V tau).
    tau_q, tau_r = tau_p, 3.0 * wingspan_m / (math.pi * speed)
    states = linear.a.shape[0]
    a = np.zeros((states + 2, states + 2))
    a[:states, :states] = linear.a
    c_v, c_w = linear.c[1], linear.c[2]
    a[states, :states], a[states, states] = c_w / tau_q, -1.0 / tau_q
    a[states + 1, :states], a[states + 1, states + 1] = c_v / tau_r, -1.0 / tau_r
    b = np.vstack([linear.b, np.zeros((2, 4))])
    c = np.zeros((6, states + 2))
    c[:4, :states] = linear.c
    c[4, :states], c[4, states] = c_w / (speed * tau_q), -1.0 / (speed * tau_q)
    c[5, :states], c[5, states + 1] = -c_v / (speed * tau_r), 1.0 / (speed * tau_r)
    return StateSpace(a, b, c)


class VonKarmanTurbulence:
    """Samples of the shaping filters every period_s, exactly discretised (Van Loan), from a
    stationary start; `step()` returns the gust velocities in NED [m/s] and the body-axis gust
    rates [rad/s]."""

    def __init__(self, scales: TurbulenceScales, airspeed_mps: float, wingspan_m: float,
                 wind_azimuth_rad: float, period_s: float, rng: np.random.Generator) -> None:
        system = shaping_filters(scales, airspeed_mps, wingspan_m)
        self.output = system.c
        self.transition, noise_covariance = _discretise(system, period_s)
        self.noise_factor = _square_root(noise_covariance)
        stationary = solve_continuous_lyapunov(system.a, -system.b @ system.b.T)
        self.rng = rng
        self.state = _square_root(stationary) @ rng.standard_normal(system.a.shape[0])
        cos_psi, sin_psi = math.cos(wind_azimuth_rad), math.sin(wind_azimuth_rad)
        # Turbulence axes (u along the wind, v to its right, w down) to NED.
        self.to_ned = np.array([[cos_psi, -sin_psi, 0.0], [sin_psi, cos_psi, 0.0],
                                [0.0, 0.0, 1.0]])

    def gusts(self) -> tuple[np.ndarray, np.ndarray]:
        """The current gust velocity, NED [m/s], and body-axis gust rates [rad/s]."""
        values = self.output @ self.state
        return self.to_ned @ values[:3], values[3:]

    def step(self) -> tuple[np.ndarray, np.ndarray]:
        """Advance one period and return gusts()."""
        noise = self.rng.standard_normal(self.state.size)
        self.state = self.transition @ self.state + self.noise_factor @ noise
        return self.gusts()


def _discretise(system: StateSpace, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact discrete transition and noise covariance over period_s (Van Loan, 1978)."""
    size = system.a.shape[0]
    block = np.zeros((2 * size, 2 * size))
    block[:size, :size] = -system.a
    block[:size, size:] = system.b @ system.b.T
    block[size:, size:] = system.a.T
    exponential = expm(block * period_s)
    transition = exponential[size:, size:].T
    covariance = transition @ exponential[:size, size:]
    return transition, 0.5 * (covariance + covariance.T)


def _square_root(covariance: np.ndarray) -> np.ndarray:
    """F with F F^T = covariance, for a covariance that may be numerically singular."""
    values, vectors = np.linalg.eigh(covariance)
    return vectors * np.sqrt(np.clip(values, 0.0, None))
