"""How the virtual leg lands (§4.2's "normal" period at its start): the foot's pitch and the knee at
heel strike, and how fast the foot then comes down about the heel.

The paper's telescopic stance leg is longer than the human leg at heel strike (the foot lands
toe-up, which brings the ankle nearer the hip) and it shortens at once: the hip approaches the
planted foot at 0.9 m/s in the natural walk, 1.5 m/s in steps of 1.05 m, 1.8 m/s at 8 km/h. A
straight human leg follows that only by the foot turning about the heel, as fast as
c / lever, with a lever (the heel-ankle arm across the leg) of about 5 cm: 1000-2000°/s, 2-4° a
frame at 500 fps; any slower and the straight knee bends as the square root of time. People land
with the knee a little flexed and keep flexing it through loading response; so does the body. It
lands with the least knee flexion (0, then LANDING_KNEE_STEP apart, up to LANDING_KNEE_MAX) at
which the hip's approach is shared between the foot, turning at most LANDING_FOOT_RATE, and the
knee, so that thigh, knee and ankle start at most LANDING_JOINT_RATE. Where the straight leg
already manages (the natural walk, slower walks) it lands straight, as before.

A bent knee brings the ankle nearer the hip, so the foot lands a little more toe-up about the same
heel point (the planned one): the body's swing leg bends into that posture over the end of its
swing (:mod:`klaw_ocp.body_motion.swing_legs`). The dynamics are unchanged: their swing leg lands
straight, and the stance leg's hip is the simulated one throughout.

Frames: world x forward, y up, ground y = 0; pitch clockwise (heel-up), negative toe-up.
"""
from __future__ import annotations

import math

import numpy as np

from .leg_geometry import ankle_angle, foot_pieces, leg_ik, leg_ik_float
from .pitch_rules import rocker_pitch

#: the fastest thigh, knee and ankle may start after heel strike (rad/s): 1.8° a frame at 500 fps
LANDING_JOINT_RATE = math.radians(900)
#: the fastest the foot's pitch may start where the knee lands bent (rad/s). The pitch is not a
#: joint angle: with the knee flexing, the shank turns the same way and the ankle angle changes
#: by their difference.
LANDING_FOOT_RATE = math.radians(1600)
#: the knee flexions at heel strike tried, least first (rad)
LANDING_KNEE_STEP = math.radians(0.5)
LANDING_KNEE_MAX = math.radians(15.0)
#: the time step over which the starting rates are measured (s)
_RATE_STEP = 1e-4


def landing_pitch(body, ankle_x: float, hip, reach: float, hip_velocity) -> tuple[float, float]:
    """The pitch (rad, < 0: toe-up) at which the foot, its heel on the ground at ankle_x - l8, has
    its ankle ``reach`` from the hip, and the pitch rate (rad/s) at which the hip-ankle distance
    starts still with the hip moving at ``hip_velocity``: the heel-rocker rate the straight leg
    needs (the ankle turning clockwise about the heel as the pitch rises)."""
    # in plain floats: numpy's overhead on two-vectors is most of the cost
    heel_x, ankle0_x, ankle0_y = ankle_x - body.l8, ankle_x, body.l9
    hip_x, hip_y = (float(v) for v in hip)
    r_heel = math.hypot(ankle0_x - heel_x, ankle0_y)
    to_x, to_y = hip_x - heel_x, hip_y
    dist = math.hypot(to_x, to_y)
    # the circles |A - hip| = reach and |A - heel| = r_heel: the intersection ahead of the heel
    along = (dist ** 2 + r_heel ** 2 - reach ** 2) / (2 * dist)
    across = math.sqrt(max(r_heel ** 2 - along ** 2, 0.0))
    e_x, e_y = to_x / dist, to_y / dist
    land_x, land_y = heel_x + along * e_x + across * e_y, along * e_y - across * e_x
    sole_up = math.atan2(land_y, land_x - heel_x) - math.atan2(ankle0_y, ankle0_x - heel_x)
    # d|hip - ankle|/dt = e.(v_hip - dA/dp p') = 0, dA/dp = ((A - heel)_y, -(A - heel)_x)
    e_x, e_y = (hip_x - land_x) / reach, (hip_y - land_y) / reach
    along = e_x * land_y + e_y * (heel_x - land_x)
    v_x, v_y = (float(v) for v in hip_velocity)
    rate = (e_x * v_x + e_y * v_y) / along if abs(along) > 1e-12 else 0.0
    return -sole_up, max(rate, 0.0)


def starting_rates(foot, hip, hip_velocity) -> np.ndarray:
    """The thigh's, the knee's and the ankle's rates (rad/s: θ3, θ4, θ5) as the stance foot
    ``foot`` (a :class:`.virtual_leg.StanceFoot`) starts, the hip moving at ``hip_velocity``:
    over a step of _RATE_STEP, the rocker's pitch, the ankle turned about the heel and the leg's
    inverse kinematics as :meth:`.virtual_leg.StanceFoot.frames` has them, without the rest of
    the foot (the walk asks this at every heel strike). :func:`starting_rates_of` of the one
    foot, on Python floats (the same operations in the same order: numpy's cost per call on two
    samples was all of its time), the rocker's power on an array as there."""
    t = np.array([0.0, _RATE_STEP])
    pitch = rocker_pitch(t, foot.t_flat, np.full(2, foot.rocker_pitch), np.full(2, foot.rocker_rate)).tolist()
    (hx, hy), (vx, vy) = np.asarray(hip, float).tolist(), np.asarray(hip_velocity, float).tolist()
    pieces, body, ankle_x = foot_pieces(foot.foot.body, foot.meta_off_theta6), foot.foot.body, foot.foot.ankle_x
    q = []
    for dt, p in zip(t.tolist(), pitch):
        theta3, theta4 = leg_ik_float(body, hx + dt * vx, hy + dt * vy, *pieces.ankle_float(ankle_x, p))
        q.append((theta3, theta4, (-p + theta3 + theta4 + math.pi / 2) % (2 * math.pi)))
    return np.array([(b - a) / _RATE_STEP for a, b in zip(*q)])


def starting_rates_of(foot, pitches: np.ndarray, rates: np.ndarray, hip, hip_velocity) -> np.ndarray:
    """:func:`starting_rates` (n, 3) of the feet that are ``foot`` but for their heel-strike pitch
    ``pitches`` (n,) and rocker rate ``rates`` (n,): every knee the landing search tries, in one
    pass of the same element-wise operations."""
    n = len(pitches)
    t = np.tile([0.0, _RATE_STEP], n)
    hips = np.asarray(hip, float) + t[:, None] * np.asarray(hip_velocity, float)
    pitch = rocker_pitch(t, foot.t_flat, np.repeat(pitches, 2), np.repeat(rates, 2))
    theta3, theta4, _ = leg_ik(foot.foot.body, hips, foot.foot.ankle_at(pitch, foot.meta_off_theta6))
    theta5 = ankle_angle(theta3, theta4, -pitch)
    q = np.stack([theta3, theta4, theta5], axis=1).reshape(n, 2, 3)
    return (q[:, 1] - q[:, 0]) / _RATE_STEP


#: the candidates of :func:`least_largest_rates` for three joints: the lines' pairs (i, j) and the
#: sign of a_i + b_i r = ±(a_j + b_j r), in the order the rate is looked for (the first least wins)
_PAIRS = [(i, j, sign) for i in range(3) for j in range(3) for sign in (1.0, -1.0)]


def least_largest_rates(at_zero: np.ndarray, slope: np.ndarray, most: np.ndarray) -> np.ndarray:
    """For each foot k, the rate r in [0, most_k] that makes the largest of |at_zero[k] +
    slope[k] r| least (at_zero, slope (n, 3): the thigh's, the knee's and the ankle's starting
    rates at r = 0 and per unit of r). The joints' starting rates are linear in the foot's (their
    velocities are linear in the hip's and the foot's), so the optimum is an end of the range or
    where two of the lines |a_i + b_i r| cross (each line's own zero among them: i = j, sign -1).
    Every foot's 20 candidates at once (one foot at a time in Python loops took 0.86 ms for a fast
    step's 30 knees, this 0.12 ms); the first least candidate, in the order ends, then _PAIRS."""
    i, j, sign = (np.array(column) for column in zip(*_PAIRS))
    denominator = slope[:, i] - sign * slope[:, j]                         # (n, 18)
    valid = np.abs(denominator) > 1e-12
    crossing = (sign * at_zero[:, j] - at_zero[:, i]) / np.where(valid, denominator, 1.0)
    candidates = np.concatenate([np.zeros((len(most), 1)), most[:, None], crossing], axis=1)
    r = np.clip(candidates, 0.0, most[:, None])                            # (n, 20)
    largest = np.max(np.abs(at_zero[:, :, None] + slope[:, :, None] * r[:, None, :]), axis=1)
    largest[:, 2:][~valid] = np.inf                                        # (no crossing there)
    return r[np.arange(len(most)), np.argmin(largest, axis=1)]


def least_landing_knee(make_foot, poses, hip, hip_velocity, usable: bool = True):
    """The stance foot of the least knee flexion at heel strike tried whose thigh, knee and ankle
    start at most LANDING_JOINT_RATE; if none does, the one whose largest joint rate is least.
    ``make_foot(knee, rate)`` builds the foot landing with that knee flexion (rad), its pitch
    starting at ``rate`` (rad/s; None: the rate that keeps the hip-ankle distance still, capped at
    LANDING_FOOT_RATE for a bent knee), and has that rate as ``rocker_rate``; ``poses(knees)``
    gives those feet's heel-strike pitches and capped still-length rates (n,) each. A straight leg
    must start at the rate that holds its length; a bent one starts at the rate, at most that one,
    that keeps the largest joint rate least. ``usable`` False (no rocker to measure) takes the
    straight leg. Every bent knee is tried in one pass (:func:`starting_rates_of`): the fast walks
    that need one (7-9 km/h) tried them one by one at 10 ms a step."""
    straight = make_foot(0.0, None)
    if not usable:
        return straight
    best = (float(np.max(np.abs(starting_rates(straight, hip, hip_velocity)))), 0.0, None)
    if best[0] <= LANDING_JOINT_RATE:
        return straight
    knees = np.arange(1, int(round(LANDING_KNEE_MAX / LANDING_KNEE_STEP)) + 1) * LANDING_KNEE_STEP
    pitches, most = poses(knees)
    at_zero = starting_rates_of(straight, pitches, np.zeros(len(knees)), hip, hip_velocity)
    capped = starting_rates_of(straight, pitches, most, hip, hip_velocity)
    # the joints' rates per unit of the foot's (none where the foot may not turn at all)
    turns = most > 0
    slope = np.where(turns[:, None], (capped - at_zero) / np.where(turns, most, 1.0)[:, None], 0.0)
    rates = least_largest_rates(at_zero, slope, most)
    # (the lines are a model: each foot's rates measured again)
    largest = np.max(np.abs(starting_rates_of(straight, pitches, rates, hip, hip_velocity)), axis=1)
    within = np.flatnonzero(largest <= LANDING_JOINT_RATE)
    if within.size:
        k = int(within[0])
        return make_foot(float(knees[k]), float(rates[k]))
    k = int(np.argmin(largest))
    best = min(best, (float(largest[k]), float(knees[k]), float(rates[k])))
    return make_foot(best[1], best[2])
