"""Spring and damping constants of the torque shapes, from the locomotion attributes.

The attributes give each spring-damper as a natural frequency f (Hz) and a damping ratio zeta,
so one set of defaults serves every body size; the constants follow from the inertia the spring
acts on: ``k = m_eff (2 pi f)^2`` and ``d = 2 zeta m_eff (2 pi f)``.

- leg (F_w, §4.2): m_eff = m2, the upper body riding on the telescope.
- trunk (F_theta2, §4.2): I2 + m2 r2^2, the upper body about the hip.
- hip hold (F_theta3 in swing2/3, §4.3): the straight swing leg about the hip.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..body import Body


@dataclass(frozen=True)
class ControlGains:
    k_w: float      # N/m
    v_w: float      # N s/m
    k_t: float      # N m/rad
    d_t: float      # N m s/rad
    theta2_ref: float  # rad
    k_y: float      # m/m, pa per metre of hip-height error
    c_y: float      # s, pa per m/s of hip-height-rate error
    k_h: float      # N m/rad
    d_h: float      # N m s/rad

    def as_dict(self) -> dict:
        return asdict(self)


def _spring(inertia: float, frequency_hz: float, damping_ratio: float) -> tuple[float, float]:
    omega = 2 * math.pi * frequency_hz
    return inertia * omega ** 2, 2 * damping_ratio * inertia * omega


def control_gains(body: Body, attrs) -> ControlGains:
    k_w, v_w = _spring(body.m2, attrs.leg_frequency, attrs.leg_damping_ratio)
    k_t, d_t = _spring(body.I2 + body.m2 * body.r2 ** 2, attrs.trunk_frequency, attrs.trunk_damping_ratio)
    leg_about_hip = body.I3 + body.m3 * body.r3 ** 2 + body.I4 + body.m4 * (body.l3 + body.r4) ** 2
    k_h, d_h = _spring(leg_about_hip, attrs.hip_hold_frequency, attrs.hip_hold_damping_ratio)
    return ControlGains(k_w, v_w, k_t, d_t, math.radians(attrs.trunk_lean), attrs.hip_height_gain,
                        attrs.hip_height_rate_gain, k_h, d_h)
