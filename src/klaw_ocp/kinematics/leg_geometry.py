"""The geometry of the leg and its foot on the ground (§4.2, figure 6; Table B-1 rows 3-13):
two-link inverse kinematics and the rigid foot turning about its heel, first metatarsal head or
toe tip. :mod:`.virtual_leg` puts them together with the foot periods' rules.

Frames: world x forward, y up, ground y = 0; arrays are over n samples; angles in radians. Pitch
``p`` is the foot's heel-up rotation (clockwise), negative while it rotates toe-up about the heel.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..body import Body


def _rotate(points: np.ndarray, pivot: np.ndarray, angle) -> np.ndarray:
    """``points`` (n, 2) rotated counter-clockwise by ``angle`` (n,) about ``pivot`` (2,) or (n, 2)."""
    c, s = np.cos(angle), np.sin(angle)
    v = points - pivot
    return pivot + np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


def leg_ik(body: Body, hip: np.ndarray, ankle: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thigh angle θ3, knee flexion θ4 (swing-model convention: knee = hip - l3 (sin θ3, cos θ3))
    and the knee, of the two-segment leg from ``hip`` to ``ankle`` (n, 2), knee forward. The
    distance is clipped to l1 (the leg straight): :attr:`VirtualLegFrames.overreach` says by how much."""
    d_vec = ankle - hip
    l3, l4 = body.l3, body.l4
    d = np.minimum(np.hypot(d_vec[:, 0], d_vec[:, 1]), l3 + l4)
    beta = np.arctan2(-d_vec[:, 0], -d_vec[:, 1])
    # the triangle's half-angle formulas: well conditioned at the straight knee, where arccos of
    # the cosine law loses half the digits (1e-8 rad, 1e-8 m of hip)
    s = (l3 + l4 + d) / 2
    short = (l3 + l4 - d) / 2                          # s - d, exactly 0 for a straight leg
    root = lambda v: np.sqrt(np.maximum(v, 0.0))
    delta = 2 * np.arctan2(root((s - l3) * short), root(s * (s - l4)))     # at the hip
    theta4 = 2 * np.arctan2(root(s * short), root((s - l3) * (s - l4)))     # knee flexion
    theta3 = beta - delta
    knee = hip - body.l3 * np.column_stack([np.sin(theta3), np.cos(theta3)])
    return theta3, theta4, knee


@dataclass(frozen=True)
class FlatFoot:
    """The stance foot's points lying flat, its flat-foot ankle at (ankle_x, l9)."""
    body: Body
    ankle_x: float

    @property
    def ankle(self):
        return np.array([self.ankle_x, self.body.l9])

    @property
    def heel(self):
        return np.array([self.ankle_x - self.body.l8, 0.0])

    @property
    def metatarsal(self):
        return np.array([self.ankle_x + math.sqrt(self.body.l12 ** 2 - self.body.l9 ** 2), 0.0])

    @property
    def toe(self):
        return self.metatarsal + np.array([self.body.l13, 0.0])

    def ankle_at(self, pitch, meta_off_theta6: float) -> np.ndarray:
        """The ankle alone at foot pitch ``pitch`` (n,), the pivots of :meth:`pose`: written out,
        for the root searches, which ask for it thousands of times a walk."""
        p = np.atleast_1d(np.asarray(pitch, float))
        q = meta_off_theta6
        heel, ankle0, meta, toe = self.heel, self.ankle, self.metatarsal, self.toe
        c, s = math.cos(q), math.sin(q)
        v = ankle0 - meta
        ankle_q = meta + np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1]])   # turned by -q about M
        pivot = np.where((p < 0)[:, None], heel, np.where((p <= q)[:, None], meta, toe))
        start = np.where((p <= q)[:, None], ankle0, ankle_q)
        turn = np.where(p <= q, -p, -(p - q))
        d = start - pivot
        ct, st = np.cos(turn), np.sin(turn)
        return pivot + np.column_stack([ct * d[:, 0] - st * d[:, 1], st * d[:, 0] + ct * d[:, 1]])

    def pose(self, pitch, meta_off_theta6: float, rocker_theta6=0.0) -> dict:
        """Heel, ankle, metatarsal head, toe tip (n, 2), θ6 and the sole's counter-clockwise angle
        (n,) at foot pitch ``pitch`` (n,): about the heel for p < 0 (with the toe angle
        ``rocker_theta6``), about the metatarsal head for 0 <= p <= meta_off_theta6 (toe flat:
        θ6 = p), about the toe tip beyond (θ6 held at meta_off_theta6)."""
        p = np.atleast_1d(np.asarray(pitch, float))
        n = p.size
        rest = {k: np.tile(getattr(self, k), (n, 1)) for k in ("heel", "ankle", "metatarsal", "toe")}
        q = meta_off_theta6
        rocker, about_m = p < 0, p >= 0
        out = {k: v.copy() for k, v in rest.items()}
        # toe-up about the heel: the whole foot turns; the toe keeps its angle to the foot
        sigma = np.where(rocker, -p, 0.0)
        out["metatarsal"] = np.where(rocker[:, None], _rotate(rest["metatarsal"], self.heel, sigma),
                                     out["metatarsal"])
        theta6 = np.where(rocker, np.broadcast_to(rocker_theta6, (n,)), np.minimum(p, q))
        forward = np.column_stack([np.cos(sigma + theta6), np.sin(sigma + theta6)])
        out["toe"] = np.where(rocker[:, None], out["metatarsal"] + self.body.l13 * forward, out["toe"])
        # heel up about the metatarsal head, then about the toe tip
        first = np.where(about_m, -np.minimum(p, q), 0.0)
        second = np.where(p > q, -(p - q), 0.0)
        turned = _rotate(_rotate(rest["heel"], self.metatarsal, first), self.toe, second)
        out["heel"] = np.where(about_m[:, None], turned, out["heel"])
        out["ankle"] = self.ankle_at(p, q)
        out["metatarsal"] = np.where(about_m[:, None], _rotate(rest["metatarsal"], self.toe, second),
                                     out["metatarsal"])
        out["theta6"] = theta6
        out["sole"] = np.where(rocker, sigma, -p)
        return out


def ankle_angle(theta3, theta4, sole) -> np.ndarray:
    """θ5: from the shank's upward axis (absolute angle φ = θ3 + θ4) counter-clockwise to the
    backward sole direction (the sole turned counter-clockwise by ``sole`` from flat)."""
    phi = theta3 + theta4
    up = np.column_stack([np.sin(phi), np.cos(phi)])
    back = np.column_stack([-np.cos(sole), -np.sin(sole)])
    cross = up[:, 0] * back[:, 1] - up[:, 1] * back[:, 0]
    return np.mod(np.arctan2(cross, np.sum(up * back, axis=1)), 2 * math.pi)


def smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)
