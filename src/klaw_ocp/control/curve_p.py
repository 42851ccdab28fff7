"""Kinematics that frame the swing law (:mod:`.swing_law`): curve P and the swing1 end posture (§4.3).

Swing1 starts where the hind leg's double support ends: the virtual leg's toe-off posture
(kinematics/virtual_leg.py, ``StanceFoot``, ``toe_off_pitch``; "the continuing stance phase of the
hind leg is completed kinematically", §3), whose ankle is curve P's a0.

Curve P (§4.3): the ankle path of swing1, ``y(s) = sum A_i s^(4-i)`` with s the ankle's forward
travel since toe-off and the five conditions y(0) = a0, y(C) = a_max, y'(C) = 0, y(D) = a_min,
y'(D) = 0. D and a_min place the ankle where "the toe is directly under the knee" at t1 with the
thigh at its heel-strike angle; C = 0.3 D; a_max falls with speed.
"""
from __future__ import annotations

import math

import numpy as np

from ..body import Body
from ..dynamics.points import foot_points_float


def root(f, a: float, b: float, xtol: float) -> float:
    """A root of f in [a, b], where f changes sign: regula falsi with the Illinois modification
    (superlinear, never leaves the bracket). The searches below run at every step on plain float
    functions; this keeps them free of scipy's import and call overhead."""
    fa, fb = f(a), f(b)
    if fa == 0 or fb == 0:
        return a if fa == 0 else b
    if fa * fb > 0:
        raise ValueError(f"no sign change of f on [{a}, {b}]")
    for _ in range(200):
        c = b - fb * (b - a) / (fb - fa)
        if not min(a, b) <= c <= max(a, b):
            c = 0.5 * (a + b)
        fc = f(c)
        if fc == 0:
            return c
        if fc * fb < 0:
            a, fa = b, fb
        else:
            fa *= 0.5
        b, fb = c, fc
        if abs(b - a) <= xtol:
            break
    return b


def toe_under_knee(body: Body, knee: np.ndarray, theta5: float, theta6: float) -> tuple[np.ndarray, float]:
    """Ankle position and shank angle with the toe tip directly under the knee (end of swing1).

    The toe's x less the knee's (:func:`~klaw_ocp.dynamics.points.foot_points_float` with the
    ankle l4 below the knee along the shank at φ) is A sin φ + B cos φ, with A = -l4 - r cos θ5 -
    l9 sin θ5 - l13 cos(θ5 + θ6) and B = r sin θ5 - l9 cos θ5 + l13 sin(θ5 + θ6), r the metatarsal
    head's reach ahead of the ankle: its root is φ = atan2(B, -A) (A < 0: the shank is the longest
    term). In closed form; it was a regula falsi to 1e-13 rad, thousands of evaluations a walk."""
    ankle_x, ankle_y, phi = _toe_under_knee(body, float(knee[0]), float(knee[1]), theta5, theta6)
    return np.array([ankle_x, ankle_y]), phi


def _toe_under_knee(body: Body, kx: float, ky: float, theta5: float, theta6: float) -> tuple[float, float, float]:
    """:func:`toe_under_knee` on floats: the ankle's x and y and the shank angle (the swing1 end
    posture's search asks for it a dozen times a step, where making arrays was half its time)."""
    l4, l9, l13 = body.l4, body.l9, body.l13
    reach = body.metatarsal_reach
    c5, s5 = math.cos(theta5), math.sin(theta5)
    a = -l4 - reach * c5 - l9 * s5 - l13 * math.cos(theta5 + theta6)
    b = reach * s5 - l9 * c5 + l13 * math.sin(theta5 + theta6)
    phi = math.atan2(b, -a)
    return kx - body.l4 * math.sin(phi), ky - body.l4 * math.cos(phi), phi


def curve_p_coefficients(a0: float, a_max: float, a_min: float, c: float, d: float,
                         end_slope: float = 0.0) -> np.ndarray:
    """[A0..A4] of y(s) = A0 s^4 + A1 s^3 + A2 s^2 + A3 s + A4 from the five conditions of §4.3,
    with y'(D) = ``end_slope`` (the paper's 0 by default: see :func:`end_slope_for_knee_rate`)."""
    rows = [[0, 0, 0, 0, 1],
            [c ** 4, c ** 3, c ** 2, c, 1],
            [4 * c ** 3, 3 * c ** 2, 2 * c, 1, 0],
            [d ** 4, d ** 3, d ** 2, d, 1],
            [4 * d ** 3, 3 * d ** 2, 2 * d, 1, 0]]
    return np.linalg.solve(np.array(rows, float), np.array([a0, a_max, 0.0, a_min, end_slope]))


def swing1_end_posture(body: Body, knee: np.ndarray, theta5_natural: float, theta6: float,
                       clearance: float) -> tuple[np.ndarray, float, float]:
    """Ankle, shank angle and ankle angle theta5 at t1, with the toe tip under the knee.

    The foot keeps the ankle angle interpolated towards heel strike (``theta5_natural``) when its
    toe then clears the ground by ``clearance``; otherwise the ankle dorsiflexes just enough (as a
    walker's does at mid-swing). With the thigh at its heel-strike angle and the toe under the knee
    (§4.3), the interpolated foot alone would often point its toe into the ground.
    """
    kx, ky = float(knee[0]), float(knee[1])

    def toe_height(theta5):
        ankle_x, ankle_y, phi = _toe_under_knee(body, kx, ky, theta5, theta6)
        toe = foot_points_float(ankle_x, ankle_y, phi, theta5, theta6, body.l8, body.l9, body.l12, body.l13)[2]
        return toe[1] - clearance

    theta5 = theta5_natural
    if toe_height(theta5) < 0:
        upper = theta5_natural + math.radians(60)
        if toe_height(upper) < 0:
            theta5 = upper
        else:
            theta5 = root(toe_height, theta5_natural, upper, xtol=1e-12)
    ankle, phi = toe_under_knee(body, knee, theta5, theta6)
    return ankle, phi, theta5


#: the largest share of the knee's own direction (-tan phi) curve P's slope at D takes (about 0.45
#: at 5 km/h, near it in slow walks); see :func:`end_slope_for_knee_rate`
END_SLOPE_SHARE = 0.6


def end_slope_for_knee_rate(body: Body, shank_angle: float, hip_vel: np.ndarray, knee_rate: float) -> float:
    """Curve P's slope at D that has the knee extending at ``knee_rate`` (rad/s, theta4d) at t1.

    At t1 the thigh is at rest (swing1's final condition), so the ankle moves with the hip plus
    the shank turning about the knee: d(ankle)/dt = hip_vel + l4 theta4d (-cos phi, sin phi), phi
    the shank's angle behind the vertical. The knee law keeps the ankle on the curve, so the
    curve's slope there sets the knee's rate. With the paper's y'(D) = 0 the knee arrives at t1
    almost at rest, and swing2 must extend it from rest to rest in 15 % of the swing: a knee
    torque near 1 N m/kg whose reaction pushes the held thigh back by 7° and the straight leg's
    heel into the ground. A person's knee is already extending at 250-350°/s there."""
    vx = float(hip_vel[0]) - body.l4 * math.cos(shank_angle) * knee_rate
    vy = float(hip_vel[1]) + body.l4 * math.sin(shank_angle) * knee_rate
    # The knee alone moves the ankle along -tan(phi); as the curve's slope nears it (slow walks,
    # where the hip's share of the ankle's speed is small) the knee law's d(constraint)/d(theta4)
    # vanishes and swing1 has no solution nearby: the slope keeps at most END_SLOPE_SHARE of it.
    return max(vy / vx, -END_SLOPE_SHARE * math.tan(shank_angle))
