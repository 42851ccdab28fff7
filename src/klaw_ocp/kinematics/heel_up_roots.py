"""The pitches at which the heel-up foot meets the leg, in closed form (§4.2, figure 6): the reach
(the ankle a given distance from the hip) and the ankle limit (θ5 at its heel-off limit). The
virtual leg (:mod:`.virtual_leg`) asks for them at every node of every step.

With its heel up, the foot turns rigidly about its first metatarsal head up to the meta-off pitch
q, then about its toe tip up to MAX_PITCH. Any point fixed to the foot then moves on a circle about
the pivot, so "this point is R from the hip" is a circle intersection. The ankle limit is one too:
holding θ5 at its limit fixes the shank to the foot, so the knee turns with the foot, and

- with the knee bent, θ5 is at its limit where that knee is l3 from the hip (and is the knee the
  inverse kinematics picks, ahead of the hip-ankle line);
- with the hip beyond the leg's reach (the leg straight, the shank pointing at the hip), where
  the hip lies on the shank's line at least l1 from the ankle: seen from the foot, the hip turns
  the other way on its circle about the pivot and crosses that line.

Both pivots are evaluated in one pass (their constants stacked as (2, 1) columns against the n
hips), and the least root wins.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..body import Body
from .leg_geometry import FlatFoot, clamp

#: The steepest foot the rules consider (rad): the foot stands almost on its toe.
MAX_PITCH = math.radians(89)
#: Slack of the pieces' pitch ranges at their joins (rad) and of the straight-knee joins (m, m²):
#: round-off must not drop a root that lies on a join.
_EDGE = 1e-15
_STRAIGHT = 1e-12


@dataclass(frozen=True)
class HeelUp:
    """The foot's two heel-up motions (rows: about the metatarsal head from pitch 0 to q, about the
    toe tip from q to MAX_PITCH) as (2, 1) columns. The ankle and the knee (the knee with θ5 at its
    heel-off limit) are at ``r`` from the pivot, at angle ``phi`` when the piece starts (p0); the
    foot at pitch p has turned clockwise by p - p0 about the pivot."""
    pivot_x: np.ndarray
    pivot_y: np.ndarray
    p0: np.ndarray
    p1: np.ndarray
    ankle_r: np.ndarray
    ankle_phi: np.ndarray
    knee_r: np.ndarray
    knee_phi: np.ndarray
    #: the ankle at p0 less the pivot, and the shank's upward unit vector there
    ankle_dx: np.ndarray
    ankle_dy: np.ndarray
    shank_x: np.ndarray
    shank_y: np.ndarray


@lru_cache(maxsize=64)
def heel_up(body: Body, meta_off_theta6: float, heel_off_theta5: float) -> HeelUp:
    """:class:`HeelUp` of the body's foot, its flat ankle at x = 0 (computed once per body and
    limits)."""
    q, foot = meta_off_theta6, FlatFoot(body, 0.0)
    pivots = np.array([foot.metatarsal, foot.toe])
    ankles = foot.ankle_at(np.array([0.0, q]), q)
    # θ5 is the angle from the shank's upward axis counter-clockwise to the backward sole, at
    # π - p: the shank's axis at π - p - θ5, turning clockwise with the foot
    shank = np.array([[-math.cos(heel_off_theta5 + p), math.sin(heel_off_theta5 + p)] for p in (0.0, q)])
    knees = ankles + body.l4 * shank
    ankle_d, knee_d = ankles - pivots, knees - pivots
    column = lambda v: np.asarray(v, float).reshape(2, 1)
    return HeelUp(pivot_x=column(pivots[:, 0]), pivot_y=column(pivots[:, 1]), p0=column([0.0, q]),
                  p1=column([q, MAX_PITCH]),
                  ankle_r=column([math.hypot(*d) for d in ankle_d]),
                  ankle_phi=column([math.atan2(d[1], d[0]) for d in ankle_d]),
                  knee_r=column([math.hypot(*d) for d in knee_d]),
                  knee_phi=column([math.atan2(d[1], d[0]) for d in knee_d]),
                  ankle_dx=column(ankle_d[:, 0]), ankle_dy=column(ankle_d[:, 1]),
                  shank_x=column(shank[:, 0]), shank_y=column(shank[:, 1]))


def _wrap(angle):
    """``angle`` into [-π, π)."""
    return np.mod(angle + math.pi, 2 * math.pi) - math.pi


#: the two intersections of two circles, or of a circle and a line, stacked on a first axis
_SIGNS = np.array([1.0, -1.0]).reshape(2, 1, 1)


def _on_circle(g: HeelUp, dx, dy, dist, r, phi, radius):
    """The pitches (2 intersections, 2 pieces, n; NaN where the circles do not meet) at which the
    point of the foot at ``r``, ``phi`` about the pivot is ``radius`` from the hip, and the angle
    of that point about the pivot there. ``dx``, ``dy``, ``dist``: the pivot less the hip."""
    # |pivot + r e(psi) - hip| = radius  <=>  d . e(psi) = k, psi = phi - (p - p0)
    k = (radius ** 2 - dist ** 2 - r ** 2) / (2 * r)
    meet = (dist > 0) & (np.abs(k) <= dist)
    spread = np.arccos(clamp(k / np.where(dist > 0, dist, 1.0), -1.0, 1.0))
    psi = np.arctan2(dy, dx) + _SIGNS * spread
    return np.where(meet, g.p0 + _wrap(phi - psi), np.nan), psi


def _least(g: HeelUp, candidates) -> np.ndarray:
    """The least of the candidate pitches (..., 2 pieces, n) in their piece's range, clamped to it
    (MAX_PITCH where there is none)."""
    inside = (candidates >= g.p0 - _EDGE) & (candidates <= g.p1 + _EDGE)      # NaN: never inside
    best = np.where(inside, np.maximum(candidates, g.p0), np.inf).reshape(-1, candidates.shape[-1]).min(axis=0)
    return np.minimum(best, MAX_PITCH)


def _hip_offsets(g: HeelUp, foot: FlatFoot, hips: np.ndarray):
    """The pivots less the hips (2, n) and their distance."""
    dx, dy = (g.pivot_x + foot.ankle_x) - hips[:, 0], g.pivot_y - hips[:, 1]
    return dx, dy, np.hypot(dx, dy)


def reach_pitch(foot: FlatFoot, meta_off_theta6: float, heel_off_theta5: float, hips: np.ndarray,
                radius) -> np.ndarray:
    """The least pitch >= 0 at which the ankle is ``radius`` (a scalar or (n,)) from the hip (n, 2)
    or nearer: 0 if the flat foot's is, else where the heel-up ankle's circle meets the hip's
    (MAX_PITCH if it never does)."""
    g = heel_up(foot.body, meta_off_theta6, heel_off_theta5)
    dx, dy, dist = _hip_offsets(g, foot, hips)
    pitch = _least(g, _on_circle(g, dx, dy, dist, g.ankle_r, g.ankle_phi, radius)[0])
    reaches_flat = np.hypot(foot.ankle[0] - hips[:, 0], foot.ankle[1] - hips[:, 1]) <= radius
    return np.where(reaches_flat, 0.0, pitch)


def ankle_limit_pitch(foot: FlatFoot, meta_off_theta6: float, heel_off_theta5: float, hips: np.ndarray,
                      l3: float, l1: float) -> np.ndarray:
    """The least pitch >= 0 at which θ5 reaches ``heel_off_theta5`` with the hips (n, 2), all of
    whose flat feet have θ5 above it (MAX_PITCH where it never does); see the module docstring."""
    g = heel_up(foot.body, meta_off_theta6, heel_off_theta5)
    dx, dy, dist = _hip_offsets(g, foot, hips)
    # the knee bent: the knee turning with the foot is l3 from the hip, ahead of the hip-ankle
    # line (the cross product of hip->ankle and hip->knee >= 0), the knee inverse kinematics picks
    bent, psi = _on_circle(g, dx, dy, dist, g.knee_r, g.knee_phi, l3)
    knee_x, knee_y = dx + g.knee_r * np.cos(psi), dy + g.knee_r * np.sin(psi)
    at_ankle = psi + (g.ankle_phi - g.knee_phi)
    ankle_x, ankle_y = dx + g.ankle_r * np.cos(at_ankle), dy + g.ankle_r * np.sin(at_ankle)
    bent = np.where(ankle_x * knee_y - ankle_y * knee_x >= -_STRAIGHT, bent, np.nan)
    # the leg straight: in the foot's frame at p0 the hip, on its circle of radius dist about the
    # pivot, meets the shank's line ankle + s·shank at s >= l1: s² + 2bs + c = 0
    b = g.ankle_dx * g.shank_x + g.ankle_dy * g.shank_y
    c = g.ankle_r ** 2 - dist ** 2
    s = -b + _SIGNS * np.sqrt(np.maximum(b * b - c, 0.0))
    on_line = (b * b >= c) & (s >= l1 - _STRAIGHT)
    turn = np.arctan2(g.ankle_dy + s * g.shank_y, g.ankle_dx + s * g.shank_x) - np.arctan2(-dy, -dx)
    straight = np.where(on_line, g.p0 + _wrap(turn), np.nan)
    return _least(g, np.concatenate([bent, straight]))
