"""The pitch at which the heel-up foot meets the leg (§4.2, figure 6): the least pitch that puts the
ankle a given distance from the hip (the leg's reach under the knee's schedule). The virtual leg
(:mod:`.virtual_leg`) asks for it at every node of every step and at every frame of the body.

With its heel up, the foot turns about its first metatarsal head up to the meta-off pitch q, then
about its toe tip up to MAX_PITCH, the pivot passing from one to the other over a narrow band about
q (:func:`.leg_geometry.toe_flexion`). Outside that band the ankle moves on a circle about the
pivot, so "the ankle is R from the hip" is a circle intersection, in closed form; inside it the
root is found by a few safeguarded Newton steps. Both pivots are evaluated in one pass (their
constants stacked as (2, 1) columns against the n hips), and the least root wins.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..body import Body
from .leg_geometry import FlatFoot, clamp, clamp_float, foot_pieces, meta_off_band

#: The steepest foot the rules consider (rad): the foot stands almost on its toe.
MAX_PITCH = math.radians(89)
#: Slack of the pieces' pitch ranges at their joins (rad): round-off must not drop a root that lies
#: on a join.
_EDGE = 1e-15
#: at most this many safeguarded Newton steps for a root in the meta-off band (from the secant of
#: its ends, 3-4 reach 1e-14 rad: the distance is nearly linear in the pitch there)
_BAND_STEPS = 30
#: the band root's distance error (m) at which it stops: round-off of the ankle's distance
_BAND_TOL = 1e-15
#: Up to this many hips, :func:`reach_pitch` works on Python floats, hip by hip: the walk asks for
#: one to a few dozen at a time, where numpy's fixed cost per call (1-3 us, some 60 calls) was all
#: the time. The same operations in the same order on the same functions (math's sin and cos are
#: numpy's; hypot, arctan2 and arccos stay numpy's), so the same numbers to the bit.
_FEW = 32


@dataclass(frozen=True)
class HeelUp:
    """The foot's two rigid heel-up motions (rows: about the metatarsal head from pitch 0 to
    q - band, about the toe tip from q + band to MAX_PITCH) as (2, 1) columns. The ankle is at
    ``r`` from the pivot, at angle ``phi`` when the piece's reference pose (pitch p0: 0, q) is
    turned clockwise by p - p0 about the pivot."""
    pivot_x: np.ndarray
    pivot_y: np.ndarray
    p0: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    ankle_r: np.ndarray
    ankle_phi: np.ndarray
    q: float
    band: float


@lru_cache(maxsize=64)
def heel_up(body: Body, meta_off_theta6: float) -> HeelUp:
    """:class:`HeelUp` of the body's foot, its flat ankle at x = 0 (computed once per body and
    limit). The toe-tip piece's reference pose is the foot turned by q about the metatarsal head:
    beyond the band the blended foot is that pose turned about the toe tip."""
    q, foot = meta_off_theta6, FlatFoot(body, 0.0)
    band = meta_off_band(q)
    pivots = np.array([foot.metatarsal, foot.toe])
    c, s = math.cos(q), math.sin(q)
    v = foot.ankle - foot.metatarsal
    ankles = np.array([foot.ankle, foot.metatarsal + np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1]])])
    d = ankles - pivots
    column = lambda values: np.asarray(values, float).reshape(2, 1)
    return HeelUp(pivot_x=column(pivots[:, 0]), pivot_y=column(pivots[:, 1]), p0=column([0.0, q]),
                  lo=column([0.0, q + band]), hi=column([q - band, MAX_PITCH]),
                  ankle_r=column([math.hypot(*x) for x in d]), ankle_phi=column([math.atan2(x[1], x[0]) for x in d]),
                  q=q, band=band)


def _wrap(angle):
    """``angle`` into [-π, π)."""
    return np.mod(angle + math.pi, 2 * math.pi) - math.pi


#: the two intersections of two circles, stacked on a first axis
_SIGNS = np.array([1.0, -1.0]).reshape(2, 1, 1)


def _on_circle(g: HeelUp, dx, dy, dist, radius):
    """The pitches (2 intersections, 2 pieces, n; NaN where the circles do not meet) at which the
    ankle's circle about each pivot is ``radius`` from the hip. ``dx``, ``dy``, ``dist``: the pivot
    less the hip."""
    # |pivot + r e(psi) - hip| = radius  <=>  d . e(psi) = k, psi = phi - (p - p0)
    r = g.ankle_r
    k = (radius ** 2 - dist ** 2 - r ** 2) / (2 * r)
    meet = (dist > 0) & (np.abs(k) <= dist)
    spread = np.arccos(clamp(k / np.where(dist > 0, dist, 1.0), -1.0, 1.0))
    psi = np.arctan2(dy, dx) + _SIGNS * spread
    return np.where(meet, g.p0 + _wrap(g.ankle_phi - psi), np.nan)


def _least(g: HeelUp, candidates) -> np.ndarray:
    """The least of the candidate pitches (..., 2 pieces, n) in their piece's range, clamped to it
    (inf where there is none)."""
    inside = (candidates >= g.lo - _EDGE) & (candidates <= g.hi + _EDGE)      # NaN: never inside
    return np.where(inside, np.maximum(candidates, g.lo), np.inf).reshape(-1, candidates.shape[-1]).min(axis=0)


def _band_root(foot: FlatFoot, q: float, band: float, hips: np.ndarray, radius: np.ndarray,
               far: np.ndarray, near: np.ndarray) -> np.ndarray:
    """The pitch in [q - band, q + band] at which the ankle is ``radius`` from each hip, where the
    distance falls through it over the band (``far``, ``near``: the excess of the distance over the
    radius at the band's ends). In the band the toe segment rises by β = (p - q + band)²/(4 band)
    about the toe tip and the rest of the foot turns by p about the metatarsal head it carries, so
    the ankle and its derivative are a few terms: Newton's steps from the secant of the ends, kept
    in the bracket."""
    body = foot.body
    off_x, off_y = -body.metatarsal_reach, body.l9               # the flat ankle less the flat head
    toe_x = foot.ankle_x + body.metatarsal_reach + body.l13
    a, b = np.full(len(hips), q - band), np.full(len(hips), q + band)
    fa, fb = far, near
    p = a + (b - a) * fa / (fa - fb)
    for _ in range(_BAND_STEPS):
        rise = (p - q + band) ** 2 / (4 * band)
        c, s, cb, sb = np.cos(p), np.sin(p), np.cos(rise), np.sin(rise)
        ax = toe_x - body.l13 * cb + (c * off_x + s * off_y) - hips[:, 0]
        ay = body.l13 * sb + (-s * off_x + c * off_y) - hips[:, 1]
        dist = np.hypot(ax, ay)
        g = dist - radius
        if np.all(np.abs(g) <= _BAND_TOL):
            return p   # met to round-off: a further Newton step would move p by < 1e-14
        rate = (p - q + band) / (2 * band)
        dax = body.l13 * sb * rate + (-s * off_x + c * off_y)
        day = body.l13 * cb * rate + (-c * off_x - s * off_y)
        slope = (ax * dax + ay * day) / dist
        # the bracket (g falls with p), then a Newton step, or the bisection where it leaves it
        a, b = np.where(g > 0, p, a), np.where(g > 0, b, p)
        step = p - g / np.where(slope != 0, slope, -1.0)
        inside = (step >= a) & (step <= b)
        new = np.where(inside, step, 0.5 * (a + b))
        if np.all(np.abs(new - p) <= 1e-14):
            return new
        p = new
    return p


def _band_root_few(foot: FlatFoot, q: float, band: float, hx: list, hy: list, radius: list,
                   far: list, near: list) -> list:
    """:func:`_band_root` on Python floats (lists of the few hips' x, y and the rest): every hip
    steps until all have met, as the arrays do, so that each root is the one they give. The
    distances of all hips in one numpy hypot a step (its numbers are the arrays' to the bit)."""
    body = foot.body
    off_x, off_y, l13 = -body.metatarsal_reach, body.l9, body.l13
    toe_x = foot.ankle_x + body.metatarsal_reach + body.l13
    n, a0, b0, quarter, half = len(hx), q - band, q + band, 4 * band, 2 * band
    a, b = [a0] * n, [b0] * n
    p = [a0 + (b0 - a0) * fa / (fa - fb) for fa, fb in zip(far, near)]
    cos, sin, rows = math.cos, math.sin, range(n)
    for _ in range(_BAND_STEPS):
        terms, axs, ays = [], [], []
        for i in rows:
            pi = p[i]
            lever = pi - q + band
            rise = lever * lever / quarter
            c, s, cb, sb = cos(pi), sin(pi), cos(rise), sin(rise)
            axs.append(toe_x - l13 * cb + (c * off_x + s * off_y) - hx[i])
            ays.append(l13 * sb + (-s * off_x + c * off_y) - hy[i])
            terms.append((lever, c, s, cb, sb))
        dists = _hypot(axs, ays).tolist()
        gs = [dist - r for dist, r in zip(dists, radius)]
        if all(abs(g) <= _BAND_TOL for g in gs):
            return p
        new = []
        for i in rows:
            lever, c, s, cb, sb = terms[i]
            ax, ay, g = axs[i], ays[i], gs[i]
            rate = lever / half
            dax = l13 * sb * rate + (-s * off_x + c * off_y)
            day = l13 * cb * rate + (-c * off_x - s * off_y)
            slope = (ax * dax + ay * day) / dists[i]
            if g > 0:
                a[i] = p[i]
            else:
                b[i] = p[i]
            step = p[i] - g / (slope if slope != 0 else -1.0)
            new.append(step if a[i] <= step <= b[i] else 0.5 * (a[i] + b[i]))
        if all(abs(x - y) <= 1e-14 for x, y in zip(new, p)):
            return new
        p = new
    return p


@lru_cache(maxsize=64)
def _band_ends(body: Body, meta_off_theta6: float) -> np.ndarray:
    """The ankle (2, 2) at the meta-off band's two ends, its flat ankle at x = 0."""
    g = heel_up(body, meta_off_theta6)
    ends = foot_pieces(body, meta_off_theta6).turned(0.0, np.array([g.q - g.band, g.q + g.band]), slice(1, 2))[:, 0]
    ends.flags.writeable = False
    return ends


def reach_pitch(foot: FlatFoot, meta_off_theta6: float, hips: np.ndarray, radius) -> np.ndarray:
    """The least pitch >= 0 at which the ankle is ``radius`` (a scalar or (n,)) from the hip (n, 2)
    or nearer: 0 if the flat foot's is, else where the heel-up ankle meets the hip's circle
    (MAX_PITCH if it never does)."""
    g = heel_up(foot.body, meta_off_theta6)
    if len(hips) <= _FEW:    # the radii as a list (np.broadcast_to alone cost 3-5 us a call)
        radius = np.asarray(radius, float)
        return _reach_pitch_few(foot, g, hips, radius.tolist() if radius.ndim else [float(radius)] * len(hips))
    radius = np.broadcast_to(np.asarray(radius, float), (len(hips),))
    dx, dy = (g.pivot_x + foot.ankle_x) - hips[:, 0], g.pivot_y - hips[:, 1]
    pitch = _least(g, _on_circle(g, dx, dy, np.hypot(dx, dy), radius))
    reaches_flat = np.hypot(foot.ankle[0] - hips[:, 0], foot.ankle[1] - hips[:, 1]) <= radius
    if g.band > 0:
        # no root about the metatarsal head: where the band's ends bracket the reach, the root is in it
        missing = (pitch > g.q - g.band + _EDGE) & ~reaches_flat
        if missing.any():
            ends = _band_ends(foot.body, meta_off_theta6)
            h, rad = hips[missing], radius[missing]
            far = np.hypot(ends[0, 0] + foot.ankle_x - h[:, 0], ends[0, 1] - h[:, 1]) - rad
            near = np.hypot(ends[1, 0] + foot.ankle_x - h[:, 0], ends[1, 1] - h[:, 1]) - rad
            bracket = (far > 0) & (near <= 0)
            inside = np.flatnonzero(missing)[bracket]
            if inside.size:
                pitch[inside] = _band_root(foot, g.q, g.band, hips[inside], radius[inside], far[bracket], near[bracket])
    return np.where(reaches_flat, 0.0, np.minimum(pitch, MAX_PITCH))


#: numpy's hypot (libm's) on two numbers: math.hypot rounds differently in the last bit
_hypot = np.hypot


@lru_cache(maxsize=64)
def _pieces(body: Body, meta_off_theta6: float) -> tuple:
    """Per piece of :func:`heel_up`: r, r², 2 r, φ, p0 and its pitch range (lo, lo - edge, hi + edge), as
    floats for :func:`_reach_pitch_few` (computed as numpy computes them on the columns)."""
    g = heel_up(body, meta_off_theta6)
    columns = (g.ankle_r, g.ankle_phi, g.p0, g.lo, g.hi)
    return tuple((r, r * r, 2 * r, phi, p0, lo, lo - _EDGE, hi + _EDGE)
                 for r, phi, p0, lo, hi in zip(*(column[:, 0].tolist() for column in columns)))


@lru_cache(maxsize=64)
def _pivots(body: Body, meta_off_theta6: float) -> tuple:
    """The two pivots' x and y (flat ankle at x = 0) as floats, and the band's ends (:func:`_band_ends`)."""
    g = heel_up(body, meta_off_theta6)
    return (*g.pivot_x[:, 0].tolist(), *g.pivot_y[:, 0].tolist()), _band_ends(body, meta_off_theta6).tolist()


def _reach_pitch_few(foot: FlatFoot, g: HeelUp, hips: np.ndarray, radius: list) -> np.ndarray:
    """:func:`reach_pitch` hip by hip on Python floats (see _FEW): :func:`_on_circle`'s two
    intersections about each pivot, :func:`_least`'s choice, the band's root where it lies there."""
    n, foot_x = len(hips), foot.ankle_x
    (px0, px1, py0, py1), ((far_x, far_y), (near_x, near_y)) = _pivots(foot.body, g.q)
    ankle_x, ankle_y = foot.ankle.tolist()
    # the two pivots less the hips, and the flat ankle's (3, 2, n): one hypot, one arctan2
    d = np.array([[px0 + foot_x, py0], [px1 + foot_x, py1], [ankle_x, ankle_y]])[:, :, None] - hips.T
    *dists, flat = np.hypot(d[:, 0], d[:, 1]).tolist()
    headings = np.arctan2(d[:2, 1], d[:2, 0]).tolist()
    pieces = _pieces(foot.body, g.q)
    # |pivot + r e(psi) - hip| = radius  <=>  d . e(psi) = k, psi = phi - (p - p0), as _on_circle
    ks = [[((big * big - dj * dj) - rr) / r2 for big, dj in zip(radius, dists_i)]
          for (_, rr, r2, *_), dists_i in zip(pieces, dists)]
    spreads = np.arccos([[clamp_float(k / (dj if dj > 0 else 1.0), -1.0, 1.0) for k, dj in zip(ks_i, dists_i)]
                         for ks_i, dists_i in zip(ks, dists)]).tolist()
    pitch, pi, turn = [math.inf] * n, math.pi, 2 * math.pi
    for (_, _, _, phi, p0, lo, lo_edge, hi_edge), dists_i, ks_i, headings_i, spreads_i in zip(
            pieces, dists, ks, headings, spreads):
        for j in range(n):
            dj, k = dists_i[j], ks_i[j]
            if not (dj > 0 and abs(k) <= dj):
                continue                   # the circles do not meet: NaN, never inside
            heading, spread, least = headings_i[j], spreads_i[j], pitch[j]
            for psi in (heading + spread, heading + -spread):
                candidate = p0 + ((phi - psi + pi) % turn - pi)
                if lo_edge <= candidate <= hi_edge:
                    candidate = candidate if candidate >= lo else lo
                    if candidate < least:
                        least = candidate
            pitch[j] = least
    reaches_flat = [f <= big for f, big in zip(flat, radius)]
    if g.band > 0:
        # no root about the metatarsal head: where the band's ends bracket the reach, the root is in it
        start = g.q - g.band + _EDGE
        rows = [j for j in range(n) if pitch[j] > start and not reaches_flat[j]]
        if rows:   # the band's ends' distances for those hips in one hypot each
            hx, hy, big = [float(hips[j, 0]) for j in rows], [float(hips[j, 1]) for j in rows], [radius[j] for j in rows]
            far = (_hypot([far_x + foot_x - x for x in hx], [far_y - y for y in hy]) - big).tolist()
            near = (_hypot([near_x + foot_x - x for x in hx], [near_y - y for y in hy]) - big).tolist()
            inside = [i for i, (f, e) in enumerate(zip(far, near)) if f > 0 and e <= 0]
            if inside:
                columns = ([column[i] for i in inside] for column in (hx, hy, big, far, near))
                for i, root in zip(inside, _band_root_few(foot, g.q, g.band, *columns)):
                    pitch[rows[i]] = root
    return np.array([0.0 if flat_j else (p if p <= MAX_PITCH or p != p else MAX_PITCH)
                     for flat_j, p in zip(reaches_flat, pitch)])
