"""The actuator's limits and mode: the ``[actuator]`` table of a scenario."""
from __future__ import annotations

from dataclasses import dataclass

from sumo_avoid.core.config import field_doc


@dataclass(frozen=True)
class ActuatorConfig:
    max_accel_mps2: float = field_doc(3.0, doc="largest longitudinal acceleration, m/s^2")
    max_decel_mps2: float = field_doc(8.0, doc="largest braking deceleration, m/s^2")
    max_lat_accel_mps2: float = field_doc(4.0, doc="largest lateral acceleration v*yaw_rate, m/s^2")
    max_yaw_rate_radps: float = field_doc(0.8, doc="largest yaw rate, rad/s")
    min_turn_radius_m: float = field_doc(4.25, doc="smallest turning radius of the vehicle's centre (yaw rate <= v/R), m: "
                                                  "a compact car with an 11 m kerb-to-kerb turning circle (outer front "
                                                  "wheel on 5.5 m, 2.65 m wheelbase, 1.55 m track) turns its centre on 4.25 m")
    max_reverse_speed_mps: float = field_doc(2.0, doc="reverse gear speed limit, m/s (0 = no reversing)")
    mode: str = field_doc("kinematic", doc="'kinematic' (car: accel/yaw limits) or 'relaxation' (flocking "
                                           "reference: dv/dt = (v_des - v)/tau, |dv/dt| <= relax_max_accel)")
    tau_s: float = field_doc(1.0, doc="relaxation mode: velocity time constant tau, s")
    relax_max_accel_mps2: float = field_doc(6.0, doc="relaxation mode: acceleration cap, m/s^2")
    outer_noise_m2ps3: float = field_doc(0.0, doc="relaxation mode: reference simulator's 'outer' noise on the "
                                                  "actual motion, sigma in m^2/s^3 (robotsim: 0.2; 0 = off; "
                                                  "sumo_avoid/core/noise.py)")

    def __post_init__(self):
        if self.mode not in ("kinematic", "relaxation"):
            raise ValueError("actuator.mode must be 'kinematic' or 'relaxation'")
        if self.tau_s <= 0:
            raise ValueError("actuator.tau_s > 0")
        if self.outer_noise_m2ps3 < 0:
            raise ValueError("actuator.outer_noise_m2ps3 >= 0")
