"""Kinematics that frame the swing: the hind leg's double support and curve P (§3, §4.2, §4.3).

"the continuing stance phase of the hind leg is completed kinematically": from heel strike of the
leading leg to toe-off (t_ds later), the hind foot's toe tip stays on the ground while the foot
pitches about the first metatarsal head (heel-off) towards the toe-off pitch attribute. The knee
follows by inverse kinematics of the two-segment leg between hip and ankle; the foot is pitched
further whenever the straight leg could not reach it. The state at toe-off starts swing1.

Curve P (§4.3): the ankle path of swing1, ``y(s) = sum A_i s^(4-i)`` with s the ankle's forward
travel since toe-off and the five conditions y(0) = a0, y(C) = a_max, y'(C) = 0, y(D) = a_min,
y'(D) = 0. D and a_min place the ankle where "the toe is directly under the knee" at t1 with the
thigh at its heel-strike angle; C = 0.3 D; a_max falls with speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..body import Body
from ..dynamics.kinematics import foot_points_float


def root(f, a: float, b: float, xtol: float) -> float:
    """A root of f in [a, b], where f changes sign: regula falsi with the Illinois modification
    (superlinear, never leaves the bracket). The searches below run thousands of times a walk on
    plain float functions; this keeps them free of scipy's import and call overhead."""
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


def metatarsal_offset(body: Body) -> float:
    """Forward distance from the flat-foot ankle to the first metatarsal head."""
    return math.sqrt(body.l12 ** 2 - body.l9 ** 2)


def hind_ankle(body: Body, metatarsal_x: float, pitch: float) -> np.ndarray:
    """Ankle of a foot pitched by ``pitch`` (rad, heel up) about the metatarsal head on the ground."""
    return np.array(_hind_ankle(body, metatarsal_x, pitch))


def _hind_ankle(body: Body, metatarsal_x: float, pitch: float) -> tuple[float, float]:
    # the flat-foot ankle relative to the metatarsal head, (-offset, l9), rotated by -pitch
    c, s, ox = math.cos(pitch), math.sin(pitch), -metatarsal_offset(body)
    return metatarsal_x + c * ox + s * body.l9, -s * ox + c * body.l9


def leg_angles(body: Body, hip: np.ndarray, ankle: np.ndarray) -> tuple[float, float]:
    """(theta3, theta4) of the swing-model leg reaching from ``hip`` to ``ankle`` (knee forward)."""
    dx, dy = float(ankle[0] - hip[0]), float(ankle[1] - hip[1])
    d = min(math.hypot(dx, dy), body.l1)
    beta = math.atan2(-dx, -dy)
    cos_delta = (body.l3 ** 2 + d ** 2 - body.l4 ** 2) / (2 * body.l3 * d)
    cos_knee = (d ** 2 - body.l3 ** 2 - body.l4 ** 2) / (2 * body.l3 * body.l4)
    return beta - math.acos(max(-1.0, min(1.0, cos_delta))), math.acos(max(-1.0, min(1.0, cos_knee)))


#: The hind leg reaches its ankle with the knee this little bent (hip-ankle distance 0.1 % short
#: of l1, about 5 degrees of flexion): a fully straight knee is a singular point of the inverse
#: kinematics, where the knee angle's rate at toe-off would be ill-defined.
REACH_FRACTION = 1 - 1e-3


def reach_pitch(body: Body, hip: np.ndarray, metatarsal_x: float) -> float:
    """Smallest foot pitch at which the leg reaches the ankle (0 if it reaches it flat).

    The pitched ankle moves on a circle of radius l12 about the metatarsal head, so the pitch
    where it is l1·REACH_FRACTION from the hip is a circle intersection, in closed form (the
    double support asks this at every node of every step)."""
    hx, hy = float(hip[0]), float(hip[1])
    radius = body.l1 * REACH_FRACTION

    def reach(p):
        ax, ay = _hind_ankle(body, metatarsal_x, p)
        return math.hypot(ax - hx, ay - hy) - radius
    limit = math.radians(89)
    if reach(0.0) <= 0:
        return 0.0
    if reach(limit) > 0:
        return limit
    # ankle(p) = M + l12 (cos(phi0 - p), sin(phi0 - p)); |ankle - H| = R  <=>  D . e(phi) = K
    dx, dy = metatarsal_x - hx, -hy
    dist, phi0 = math.hypot(dx, dy), math.atan2(body.l9, -metatarsal_offset(body))
    k = (radius ** 2 - dist ** 2 - body.l12 ** 2) / (2 * body.l12)
    if dist > 0 and abs(k) <= dist:
        psi, spread = math.atan2(dy, dx), math.acos(k / dist)
        pitches = [math.remainder(phi0 - psi - sign * spread, 2 * math.pi) for sign in (1.0, -1.0)]
        inside = [p for p in pitches if 0.0 <= p <= limit]
        if inside:   # reach > 0 at 0 and <= 0 at the limit: one crossing in between
            return min(inside)
    return root(reach, 0.0, limit, xtol=1e-15)


#: The least forward rotation of the thigh over swing1 (rad): the toe-off posture keeps the thigh at
#: least this far behind its heel-strike angle theta3 (eq. 3). See :func:`toe_off_pitch`.
MIN_SWING1_THIGH_TRAVEL = 0.15


def toe_off_pitch(body: Body, hip: np.ndarray, metatarsal_x: float, pitch_start: float, pitch_wanted: float,
                  theta3_target: float) -> float:
    """Foot pitch at toe-off: the ``toe_off_foot_pitch`` attribute, lowered if needed so that the
    thigh is not ahead of ``theta3_target + MIN_SWING1_THIGH_TRAVEL``.

    Swing1 carries the thigh forward to its heel-strike angle while the ankle travels forward along
    curve P (section 4.3). Raising the heel with the hip still above the foot, as in the first step
    from standing, bends the knee forwards and puts the thigh ahead of that angle; swing1 would then
    have to swing the thigh back while the ankle moves forward, which drives the kinematic knee
    through full extension, where the ankle-on-curve-P constraint is singular (its derivative in
    theta4 vanishes) and the subphase has no well-defined solution. A person starting to walk
    raises the heel only as far as the hip has moved over the foot; so does this rule. In steady
    walking the hip is well ahead of the hind foot at toe-off and the attribute applies unchanged.
    """
    wanted = max(pitch_wanted, pitch_start)
    reach = reach_pitch(body, hip, metatarsal_x)
    bound = theta3_target + MIN_SWING1_THIGH_TRAVEL
    thigh = lambda pitch: leg_angles(body, hip, _hind_ankle(body, metatarsal_x, pitch))[0] - bound
    if thigh(max(wanted, reach)) >= 0:      # :func:`hind_leg` raises the pitch to the reach pitch
        return wanted
    lowest = max(pitch_start, reach)
    if thigh(lowest) <= 0:
        return lowest
    # the thigh angle falls monotonically as the heel rises (the ankle comes up towards the hip)
    return root(thigh, lowest, wanted, xtol=1e-13)


@dataclass(frozen=True)
class HindLeg:
    """The hind leg at one instant of double support (world frame)."""
    theta3: float
    theta4: float
    pitch: float
    ankle: np.ndarray


def hind_leg(body: Body, hip: np.ndarray, metatarsal_x: float, t: float, t_ds: float,
             pitch_start: float, pitch_toe_off: float) -> HindLeg:
    """The hind leg at time t of the double support (pitch interpolated, raised to reach)."""
    pitch = pitch_start + (pitch_toe_off - pitch_start) * min(1.0, t / t_ds)
    pitch = max(pitch, reach_pitch(body, hip, metatarsal_x))
    ankle = hind_ankle(body, metatarsal_x, pitch)
    th3, th4 = leg_angles(body, hip, ankle)
    return HindLeg(th3, th4, pitch, ankle)


def ankle_angle(shank_angle: float, pitch: float) -> float:
    """theta5 of a foot pitched by ``pitch``: the angle from the shank's upward axis, counter-
    clockwise, to the backward sole direction (pi/2 for a vertical shank and a flat foot)."""
    up = np.array([math.sin(shank_angle), math.cos(shank_angle)])
    back = np.array([-math.cos(pitch), math.sin(pitch)])
    return math.atan2(up[0] * back[1] - up[1] * back[0], up @ back) % (2 * math.pi)


def toe_under_knee(body: Body, knee: np.ndarray, theta5: float, theta6: float) -> tuple[np.ndarray, float]:
    """Ankle position and shank angle with the toe tip directly under the knee (end of swing1)."""
    kx, ky = float(knee[0]), float(knee[1])
    dims = (body.l8, body.l9, body.l12, body.l13)

    def toe_ahead(phi):
        ankle = kx - body.l4 * math.sin(phi), ky - body.l4 * math.cos(phi)
        return foot_points_float(*ankle, phi, theta5, theta6, *dims)[2][0] - kx
    phi = root(toe_ahead, -0.5, math.pi / 2, xtol=1e-13)
    return np.array([kx - body.l4 * math.sin(phi), ky - body.l4 * math.cos(phi)]), phi


def curve_p_coefficients(a0: float, a_max: float, a_min: float, c: float, d: float) -> np.ndarray:
    """[A0..A4] of y(s) = A0 s^4 + A1 s^3 + A2 s^2 + A3 s + A4 from the five conditions of §4.3."""
    rows = [[0, 0, 0, 0, 1],
            [c ** 4, c ** 3, c ** 2, c, 1],
            [4 * c ** 3, 3 * c ** 2, 2 * c, 1, 0],
            [d ** 4, d ** 3, d ** 2, d, 1],
            [4 * d ** 3, 3 * d ** 2, 2 * d, 1, 0]]
    return np.linalg.solve(np.array(rows, float), np.array([a0, a_max, 0.0, a_min, 0.0]))


def swing1_end_posture(body: Body, knee: np.ndarray, theta5_natural: float, theta6: float,
                       clearance: float) -> tuple[np.ndarray, float, float]:
    """Ankle, shank angle and ankle angle theta5 at t1, with the toe tip under the knee.

    The foot keeps the ankle angle interpolated towards heel strike (``theta5_natural``) when its
    toe then clears the ground by ``clearance``; otherwise the ankle dorsiflexes just enough (as a
    walker's does at mid-swing). With the thigh at its heel-strike angle and the toe under the knee
    (§4.3), the interpolated foot alone would often point its toe into the ground.
    """
    def toe_height(theta5):
        ankle, phi = toe_under_knee(body, knee, theta5, theta6)
        toe = foot_points_float(ankle[0], ankle[1], phi, theta5, theta6, body.l8, body.l9, body.l12, body.l13)[2]
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
