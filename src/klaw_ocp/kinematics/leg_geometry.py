"""The geometry of the leg and its foot on the ground (§4.2, figure 6; Table B-1 rows 3-13):
two-link inverse kinematics and the rigid foot turning about its heel, first metatarsal head or
toe tip. :mod:`.virtual_leg` puts them together with the foot periods' rules.

Frames: world x forward, y up, ground y = 0; arrays are over n samples; angles in radians. Pitch
``p`` is the foot's heel-up rotation (clockwise), negative while it rotates toe-up about the heel.

The walk asks for these at a few to a few dozen samples at a time, thousands of times a walk, so
numpy's fixed cost per call, not the arithmetic, is what they cost: the foot's constant points
are computed once per body (:func:`foot_pieces`) and each function uses as few array operations
as it can.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from ..body import Body


def _rotate(points: np.ndarray, pivot: np.ndarray, angle) -> np.ndarray:
    """``points`` (n, 2) rotated counter-clockwise by ``angle`` (n,) about ``pivot`` (2,) or (n, 2)."""
    c, s = np.cos(angle), np.sin(angle)
    v = points - pivot
    return pivot + np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


def _points(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n, 2) from x and y (n,): cheaper than np.column_stack for the few samples asked at a time."""
    out = np.empty((len(x), 2))
    out[:, 0], out[:, 1] = x, y
    return out


def leg_fk(body: Body, hip: np.ndarray, theta3, theta4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The swing model's leg from its hip (n, 2) and angles θ3, θ4 (n,): the shank angle
    θ3 + θ4, the knee = hip - l3 (sin θ3, cos θ3) and the ankle = knee - l4 (sin, cos)(θ3 + θ4)
    (n, 2); :func:`leg_ik` inverts it."""
    shank = theta3 + theta4
    # np.column_stack's numbers written column by column (its wrapper cost more than the sums)
    knee = _points(hip[:, 0] - body.l3 * np.sin(theta3), hip[:, 1] - body.l3 * np.cos(theta3))
    return shank, knee, _points(knee[:, 0] - body.l4 * np.sin(shank), knee[:, 1] - body.l4 * np.cos(shank))


def leg_ik(body: Body, hip: np.ndarray, ankle: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thigh angle θ3, knee flexion θ4 (swing-model convention: knee = hip - l3 (sin θ3, cos θ3))
    and the knee, of the two-segment leg from ``hip`` (n, 2) to ``ankle`` (n, 2) or (2,), knee
    forward. The distance is clipped to l1 (the leg straight): :attr:`VirtualLegFrames.overreach`
    says by how much."""
    hx, hy = hip[:, 0], hip[:, 1]
    dx, dy = ankle[..., 0] - hx, ankle[..., 1] - hy
    l3, l4 = body.l3, body.l4
    d = np.minimum(np.hypot(dx, dy), l3 + l4)
    beta = np.arctan2(-dx, -dy)
    # the triangle's half-angle formulas: well conditioned at the straight knee, where arccos of
    # the cosine law loses half the digits (1e-8 rad, 1e-8 m of hip)
    s = (l3 + l4 + d) / 2
    short = (l3 + l4 - d) / 2                          # s - d, exactly 0 for a straight leg
    # the four square roots' arguments in one array, so that their clip at 0, roots and the two
    # arctangents are a call each (numpy's fixed cost per call was this function's time); rows:
    # the hip's half-angle (y, x), then the knee's
    s3, s4 = s - l3, s - l4
    roots = np.empty((4,) + s.shape)
    np.multiply(s3, short, out=roots[0])
    np.multiply(s, s4, out=roots[1])
    np.multiply(s, short, out=roots[2])
    np.multiply(s3, s4, out=roots[3])
    np.sqrt(np.maximum(roots, 0.0, out=roots), out=roots)
    delta, theta4 = 2 * np.arctan2(roots[0::2], roots[1::2])     # at the hip; knee flexion
    theta3 = beta - delta
    knee = _points(hx - l3 * np.sin(theta3), hy - l3 * np.cos(theta3))
    return theta3, theta4, knee


def leg_ik_float(body: Body, hip_x: float, hip_y: float, ankle_x: float, ankle_y: float) -> tuple[float, float]:
    """θ3 and θ4 of :func:`leg_ik` for one hip and ankle, on Python floats (the walk's one-sample
    calls): the same operations in the same order, the three arctangents in one array as there."""
    l3, l4 = body.l3, body.l4
    dx, dy = ankle_x - hip_x, ankle_y - hip_y
    d = float(np.hypot(dx, dy))
    d = d if d <= l3 + l4 or d != d else l3 + l4
    s, short = (l3 + l4 + d) / 2, (l3 + l4 - d) / 2
    root = lambda v: math.sqrt(v if v >= 0.0 or v != v else 0.0)
    beta, delta, theta4 = np.arctan2([-dx, root((s - l3) * short), root(s * short)],
                                     [-dy, root(s * (s - l4)), root((s - l3) * (s - l4))]).tolist()
    return beta - 2 * delta, 2 * theta4


def knee_flexion_for_reach(body: Body, d) -> np.ndarray:
    """Knee flexion (rad, 0 straight) of the two-segment leg whose hip and ankle are ``d`` (m,
    clipped to l1) apart: :func:`leg_ik`'s half-angle form, well conditioned at the straight knee."""
    l3, l4 = body.l3, body.l4
    d = np.minimum(np.asarray(d, float), l3 + l4)
    s = (l3 + l4 + d) / 2
    return 2 * np.arctan2(np.sqrt(np.maximum(s * (l3 + l4 - d) / 2, 0.0)),
                          np.sqrt(np.maximum((s - l3) * (s - l4), 0.0)))


def reach_for_knee_flexion(body: Body, flexion) -> np.ndarray:
    """The hip-to-ankle distance (m) of the leg with knee flexion ``flexion`` (rad): the law of
    cosines, the inverse of :func:`knee_flexion_for_reach`."""
    l3, l4 = body.l3, body.l4
    return np.sqrt(l3 * l3 + l4 * l4 + 2 * l3 * l4 * np.cos(flexion))


def _readonly(values) -> np.ndarray:
    array = np.array(values, float)
    array.flags.writeable = False       # cached and shared: nobody may change it
    return array


@dataclass(frozen=True)
class FlatFoot:
    """The stance foot's points lying flat, its flat-foot ankle at (ankle_x, l9); computed once
    (read-only arrays)."""
    body: Body
    ankle_x: float

    @cached_property
    def ankle(self) -> np.ndarray:
        return _readonly([self.ankle_x, self.body.l9])

    @cached_property
    def heel(self) -> np.ndarray:
        return _readonly([self.ankle_x - self.body.l8, 0.0])

    @cached_property
    def metatarsal(self) -> np.ndarray:
        return _readonly([self.ankle_x + self.body.metatarsal_reach, 0.0])

    @cached_property
    def toe(self) -> np.ndarray:
        return _readonly(self.metatarsal + np.array([self.body.l13, 0.0]))

    def ankle_at(self, pitch, meta_off_theta6: float) -> np.ndarray:
        """The ankle alone at foot pitch ``pitch`` (n,), as in :meth:`pose`."""
        p = np.atleast_1d(np.asarray(pitch, float))
        return foot_pieces(self.body, meta_off_theta6).turned(self.ankle_x, p, ANKLE)[:, 0]

    def pose(self, pitch, meta_off_theta6: float, rocker_theta6=0.0) -> dict:
        """Heel, ankle, metatarsal head, toe tip (n, 2), θ6 and the sole's counter-clockwise angle
        (n,) at foot pitch ``pitch`` (n,): about the heel for p < 0 (with the toe angle
        ``rocker_theta6``); heel up with the toe tip on the ground for p >= 0, the toe joint
        following the pitch (θ6 = p: about the metatarsal head, the toe flat) until near
        ``meta_off_theta6`` and then held there (about the toe tip), blended C1 over
        META_OFF_BLEND either side of it (:func:`toe_flexion`)."""
        p = np.atleast_1d(np.asarray(pitch, float))
        q = meta_off_theta6
        heel, ankle, metatarsal = foot_pieces(self.body, q).turned(self.ankle_x, p).transpose(1, 0, 2)
        rocker = p < 0
        theta6 = np.where(rocker, rocker_theta6, toe_flexion(p, q))
        toe = np.empty((len(p), 2))
        toe[:] = self.toe        # on the ground unless rocking
        if rocker.any():   # toe-up about the heel: the whole foot turns; the toe keeps its angle to the foot
            forward = theta6[rocker] - p[rocker]
            toe[rocker] = metatarsal[rocker] + self.body.l13 * _points(np.cos(forward), np.sin(forward))
        return {"heel": heel, "ankle": ankle, "metatarsal": metatarsal, "toe": toe, "theta6": theta6, "sole": -p}


#: the points of :class:`FootPieces`, in its order
ANKLE = slice(1, 2)          # the ankle row of the foot pieces (heel, ankle, metatarsal head)
#: The half width (rad) of the pitch band about meta-off (θ6 at its limit q) over which the toe
#: joint stops following the pitch: the heel-up foot's pivot moves from the metatarsal head to the
#: toe tip with a continuous rate. A hard switch at q jumped the pitch rate (hence the ankle's,
#: 120 deg/s at 100 fps) and the toe's rate (from the pitch rate to 0, 360 deg/s) at meta-off.
META_OFF_BLEND = math.radians(12.0)


def meta_off_band(q: float) -> float:
    """The half width of the meta-off blend for the limit ``q`` (narrower where q is small, so that
    the toe joint follows the flat foot's first pitch)."""
    return min(META_OFF_BLEND, 0.5 * q)


def toe_flexion(p, q: float):
    """θ6 of the heel-up foot at pitch ``p`` >= 0 with the meta-off limit ``q``: p up to q - w, q
    from q + w, the C1 parabola p - (p - q + w)²/(4 w) between (w = :func:`meta_off_band`)."""
    w = meta_off_band(q)
    p = np.asarray(p, float)
    if w <= 0:
        return np.minimum(p, q)
    v = p - q
    return np.where(v <= -w, p, np.where(v >= w, q, p - (v + w) ** 2 / (4 * w)))


@dataclass(frozen=True)
class FootPieces:
    """A flat foot's motions, its ankle at x = 0: toe-up about the heel (p < 0); heel up (p >= 0)
    with the toe tip on the ground, the toe segment turned up by p - θ6(p) (:func:`toe_flexion`), so
    the rest of the foot, rigid, turns clockwise by p about the metatarsal head wherever the toe
    segment puts it. ``heel_offsets``, ``meta_offsets``: the heel, ankle and metatarsal head of the
    flat foot less the heel and less the metatarsal head (3, 2); ``toe``: the toe tip (2,)."""
    q: float
    heel: np.ndarray
    toe: np.ndarray
    l13: float
    heel_offsets: np.ndarray
    meta_offsets: np.ndarray

    def turned(self, ankle_x: float, p: np.ndarray, points=slice(None)) -> np.ndarray:
        """The foot's ``points`` (n, len(points), 2) at pitches ``p`` (n,), its flat ankle at
        ``ankle_x``."""
        below = p < 0
        rocking = np.count_nonzero(below)
        if rocking == 0 or rocking == len(p):
            return self._turned_one_way(ankle_x, p, points, rocking > 0)
        # some pitches on each side: each side as a foot of its own (the same numbers per pitch)
        out = np.empty((len(p),) + self.heel_offsets[points].shape)
        out[below] = self._turned_one_way(ankle_x, p[below], points, True)
        out[~below] = self._turned_one_way(ankle_x, p[~below], points, False)
        return out

    def _turned_one_way(self, ankle_x: float, p: np.ndarray, points, rocker: bool) -> np.ndarray:
        """:meth:`turned` of pitches all on one side of 0: about the heel (``rocker``, p < 0) or
        about the metatarsal head, the toe segment risen."""
        if rocker:
            pivot_x, pivot_y, v = self.heel[0] + ankle_x, self.heel[1], self.heel_offsets[points]
        else:
            beta = p - toe_flexion(np.maximum(p, 0.0), self.q)      # the toe segment's rise
            pivot_x = (self.toe[0] - self.l13 * np.cos(beta) + ankle_x)[:, None]
            pivot_y = (self.l13 * np.sin(beta))[:, None]
            v = self.meta_offsets[points]
        c, s = np.cos(p)[:, None], np.sin(p)[:, None]
        out = np.empty((len(p),) + v.shape)
        out[..., 0] = pivot_x + (c * v[:, 0] + s * v[:, 1])
        out[..., 1] = pivot_y + (-s * v[:, 0] + c * v[:, 1])
        return out

    def ankle_float(self, ankle_x: float, p: float) -> tuple[float, float]:
        """The ankle of :meth:`turned` at one pitch ``p``, on Python floats (math's sin and cos
        are numpy's)."""
        if p < 0:
            pivot_x, pivot_y, (vx, vy) = self.heel[0] + ankle_x, self.heel[1], self.heel_offsets[1].tolist()
        else:
            w = meta_off_band(self.q)
            flat = p if p >= 0.0 or p != p else 0.0
            if w <= 0:
                theta6 = flat if flat <= self.q or flat != flat else self.q
            else:
                v = flat - self.q
                theta6 = flat if v <= -w else (self.q if v >= w else flat - (v + w) * (v + w) / (4 * w))
            beta = p - theta6
            pivot_x, pivot_y = self.toe[0] - self.l13 * math.cos(beta) + ankle_x, self.l13 * math.sin(beta)
            vx, vy = self.meta_offsets[1].tolist()
        c, s = math.cos(p), math.sin(p)
        return float(pivot_x + (c * vx + s * vy)), float(pivot_y + (-s * vx + c * vy))


@lru_cache(maxsize=64)
def foot_pieces(body: Body, meta_off_theta6: float) -> FootPieces:
    """:class:`FootPieces` of the body's foot whose toe stops turning at ``meta_off_theta6``
    (computed once: every pitch asks for them)."""
    foot = FlatFoot(body, 0.0)
    points = np.array([foot.heel, foot.ankle, foot.metatarsal])
    return FootPieces(meta_off_theta6, _readonly(foot.heel), _readonly(foot.toe), body.l13,
                      _readonly(points - foot.heel), _readonly(points - foot.metatarsal))


def ankle_angle(theta3, theta4, sole) -> np.ndarray:
    """θ5: from the shank's upward axis (absolute angle φ = θ3 + θ4 clockwise from the vertical,
    so π/2 - φ counter-clockwise from x) counter-clockwise to the backward sole direction (the sole
    turned counter-clockwise by ``sole`` from flat: sole + π), in [0, 2π)."""
    return np.mod(np.asarray(sole) + theta3 + theta4 + math.pi / 2, 2 * math.pi)


def clamp(x, lo, hi):
    """``np.clip(x, lo, hi)``'s numbers (NaN stays NaN) as two ufuncs, for half its time: np.clip
    passes through Python wrappers, ~3 us on a few samples, and the virtual leg and the swing
    foot clamp hundreds of times a walk."""
    return np.minimum(np.maximum(x, lo), hi)


def clamp_float(x: float, lo: float, hi: float) -> float:
    """:func:`clamp` of one number, for the rules' one-sample paths: numpy's maximum and minimum to
    the bit (a NaN stays NaN, ties keep ``x``)."""
    x = x if x >= lo or x != x else lo
    return x if x <= hi or x != x else hi


def smoothstep(u):
    """3u² - 2u³ of ``u`` clamped to [0, 1]."""
    u = clamp(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)
