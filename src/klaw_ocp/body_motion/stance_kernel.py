"""The virtual legs of the body's stances at its frames, compiled (:mod:`klaw_ocp.kernels`).

The body asks for every stance leg at every frame, through the next step's double support to
toe-off (:func:`.stance_legs.stance_frames`): the foot's pitch by the rules of §4.2
(:func:`klaw_ocp.kinematics.pitch_rules.rule_pitch`: the rocker about the heel, the knee's
schedule, the least heel-up pitch that keeps the leg on it, :mod:`klaw_ocp.kinematics.heel_up_roots`),
then the leg on that foot (:func:`klaw_ocp.kinematics.virtual_leg.leg_frames`: the foot's pose,
the two-link inverse kinematics). As numpy over a step's 20-25 samples of two or three stances
that was some 250 small array operations (0.6 ms a step on the reference machine, on the
playground's path from asking for a step to its message: docs/serve.md); here it is one CasADi
Function of a sample, mapped over BLOCK samples and compiled as the solvers' kernels are.

The walk itself keeps the numpy and float forms (it asks for a few samples at a time, and its
rules are built from them); this is the same arithmetic on CasADi symbols, every branch taken
per sample (``if_else``), the meta-off band's root by a fixed number of the same safeguarded
Newton steps, each sample stopping where it meets the tolerance. tests/test_stance_kernel.py
holds it to the numpy forms (to 1e-12) over walks across the envelope.

A sample's row is :data:`COLUMNS` (its stance time, the hip in the world, its stance's rules, its
heel-strike toe angle, the single support's deficit there and the stance ankle's x); the body's
and the foot's numbers are :data:`CONSTANTS` (:func:`constants`), shared.
"""
from __future__ import annotations

import math
import sys
from functools import lru_cache

import casadi as ca
import numpy as np

from ..body import Body
from ..casadi_builds import built_once
from ..kernels import source_key
from ..kinematics import heel_up_roots, pitch_rules
from ..kinematics.heel_up_roots import MAX_PITCH, heel_up
from ..kinematics.leg_geometry import foot_pieces
from ..kinematics.pitch_rules import KNEE_HOLD_BLEND, RULE_FIELDS
from .kernel_forms import TWO_PI, clamp, evaluate, leg_ik, mapped_library, mod, smoothstep

BLOCK = 32
COLUMNS = ("t", "hip_x", "hip_y") + RULE_FIELDS + ("rocker_theta6", "deficit", "ankle_x")
CONSTANTS = ("l1", "l3", "l4", "l9", "l13", "metatarsal_reach", "q", "band",
             *(f"{name}{k}" for k in (0, 1) for name in ("pivot_x", "pivot_y", "p0", "lo", "hi", "r", "phi")),
             "far_x", "far_y", "near_x", "near_y", "heel_x", "heel_y", "toe_x", "toe_y",
             *(f"{part}_{point}_{a}" for part in ("heel", "meta") for point in ("heel", "ankle", "metatarsal")
               for a in "xy"))
OUTPUTS = {"pitch": 1, "fraction": 1, "hip": 2, "knee": 2, "ankle": 2, "heel": 2, "metatarsal": 2, "toe": 2,
           "theta3": 1, "theta4": 1, "theta5": 1, "theta6": 1, "overreach": 1}
#: the meta-off band root's Newton steps (numpy's: up to heel_up_roots._BAND_STEPS, all samples
#: until every one has met; from the secant of the band's ends 3-4 reach 1e-14 rad)
BAND_STEPS = 5


@lru_cache(maxsize=64)
def constants(body: Body, meta_off_theta6: float) -> np.ndarray:
    """:data:`CONSTANTS` of a body's foot with its meta-off limit (read-only, one per pair)."""
    g, pieces = heel_up(body, meta_off_theta6), foot_pieces(body, meta_off_theta6)
    ends = heel_up_roots._band_ends(body, meta_off_theta6)    # noqa: SLF001 - the same numbers
    values = [body.l1, body.l3, body.l4, body.l9, body.l13, body.metatarsal_reach, g.q, g.band]
    for k in (0, 1):
        values += [float(v[k, 0]) for v in (g.pivot_x, g.pivot_y, g.p0, g.lo, g.hi, g.ankle_r, g.ankle_phi)]
    values += [*ends[0], *ends[1], *pieces.heel, *pieces.toe, *pieces.heel_offsets.ravel(), *pieces.meta_offsets.ravel()]
    out = np.array(values, float)
    out.flags.writeable = False
    return out


def _soft_plus(v, width):
    blend = ca.if_else(v <= -width, 0.0, ca.if_else(v >= width, v, (v + width) ** 2 / (4 * ca.if_else(width > 0, width, 1.0))))
    return ca.if_else(width > 0, blend, ca.fmax(v, 0.0))


def _ramp(t, t_flat, t_end):
    span = t_end - t_flat
    return ca.if_else(span > 0, smoothstep((t - t_flat) / ca.if_else(span > 0, span, 1.0)), 1.0)


def _toe_flexion(p, q, w):
    v = p - q
    return ca.if_else(w <= 0, ca.fmin(p, q), ca.if_else(v <= -w, p, ca.if_else(v >= w, q, p - (v + w) ** 2 / (4 * w))))


def _reach_pitch(c, hx, hy, radius):
    """heel_up_roots.reach_pitch of one local hip (flat ankle at x = 0) and radius."""
    least = ca.inf
    for k in (0, 1):
        dx, dy = c[f"pivot_x{k}"] - hx, c[f"pivot_y{k}"] - hy
        dist, r = ca.hypot(dx, dy), c[f"r{k}"]
        kk = (radius ** 2 - dist ** 2 - r ** 2) / (2 * r)
        meet = ca.logic_and(dist > 0, ca.fabs(kk) <= dist)
        spread = ca.acos(clamp(kk / ca.if_else(dist > 0, dist, 1.0), -1.0, 1.0))
        for sign in (1.0, -1.0):
            psi = ca.atan2(dy, dx) + sign * spread
            candidate = c[f"p0{k}"] + (mod(c[f"phi{k}"] - psi + math.pi, TWO_PI) - math.pi)
            inside = ca.logic_and(meet, ca.logic_and(candidate >= c[f"lo{k}"] - heel_up_roots._EDGE,   # noqa: SLF001
                                                     candidate <= c[f"hi{k}"] + heel_up_roots._EDGE))  # noqa: SLF001
            least = ca.if_else(ca.logic_and(inside, ca.fmax(candidate, c[f"lo{k}"]) < least),
                               ca.fmax(candidate, c[f"lo{k}"]), least)
    reaches_flat = ca.hypot(0.0 - hx, c["l9"] - hy) <= radius
    q, band = c["q"], c["band"]
    far = ca.hypot(c["far_x"] + 0.0 - hx, c["far_y"] - hy) - radius
    near = ca.hypot(c["near_x"] + 0.0 - hx, c["near_y"] - hy) - radius
    in_band = ca.logic_and(ca.logic_and(band > 0, least > q - band + heel_up_roots._EDGE),     # noqa: SLF001
                           ca.logic_and(ca.logic_not(reaches_flat), ca.logic_and(far > 0, near <= 0)))
    pitch = ca.if_else(in_band, _band_root(c, hx, hy, radius, far, near), least)
    return ca.if_else(reaches_flat, 0.0, ca.fmin(pitch, MAX_PITCH))


def _band_root(c, hx, hy, radius, fa, fb):
    """heel_up_roots._band_root of one hip: safeguarded Newton steps from the secant of the band's
    ends, stopping once the distance meets the radius to _BAND_TOL."""
    q, band, l13 = c["q"], c["band"], c["l13"]
    off_x, off_y = -c["metatarsal_reach"], c["l9"]
    toe_x = 0.0 + c["metatarsal_reach"] + l13
    a, b = q - band, q + band
    p = a + (b - a) * fa / (fa - fb)
    done = 0
    for _ in range(BAND_STEPS):
        rise = (p - q + band) ** 2 / (4 * band)
        cp, sp, cb, sb = ca.cos(p), ca.sin(p), ca.cos(rise), ca.sin(rise)
        ax = toe_x - l13 * cb + (cp * off_x + sp * off_y) - hx
        ay = l13 * sb + (-sp * off_x + cp * off_y) - hy
        dist = ca.hypot(ax, ay)
        g = dist - radius
        done = ca.logic_or(done, ca.fabs(g) <= heel_up_roots._BAND_TOL)     # noqa: SLF001
        rate = (p - q + band) / (2 * band)
        dax = l13 * sb * rate + (-sp * off_x + cp * off_y)
        day = l13 * cb * rate + (-cp * off_x - sp * off_y)
        slope = (ax * dax + ay * day) / dist
        a, b = ca.if_else(g > 0, p, a), ca.if_else(g > 0, b, p)
        step = p - g / ca.if_else(slope != 0, slope, -1.0)
        new = ca.if_else(ca.logic_and(step >= a, step <= b), step, 0.5 * (a + b))
        p = ca.if_else(done, p, new)
    return p


def sample_function() -> ca.Function:
    """One sample: (its row (COLUMNS), the constants (CONSTANTS)) -> OUTPUTS."""
    row, shared = ca.SX.sym("row", len(COLUMNS)), ca.SX.sym("constants", len(CONSTANTS))
    x = {name: row[i] for i, name in enumerate(COLUMNS)}
    c = {name: shared[i] for i, name in enumerate(CONSTANTS)}
    t, hx, hy = x["t"], x["hip_x"] - x["ankle_x"], x["hip_y"] - 0.0          # the stance's own frame
    l1, l3, l4 = c["l1"], c["l3"], c["l4"]
    # the rules' pitch (pitch_rules.rule_pitch): the rocker before foot flat, then the knee's schedule
    turning = ca.logic_and(x["t_flat"] > 0, x["rocker_pitch"] != 0)
    t_flat_r, p0 = ca.if_else(turning, x["t_flat"], 1.0), ca.if_else(turning, x["rocker_pitch"], -1.0)
    s = clamp(t / t_flat_r, 0.0, 1.0)
    relative_rate = x["rocker_rate"] * t_flat_r / -p0
    k = ca.fmax(2.0, relative_rate - 1)
    rocker = ca.if_else(turning, p0 * (1 - s) ** k * (1 + (k - relative_rate) * s), 0.0)
    t_flat, t_knee = x["t_flat"], x["t_knee"]
    span = x["t_knee_end"] - t_knee
    u = clamp((t - t_knee) / ca.if_else(span > 0, span, 1.0), 0.0, 1.0)
    knee = x["knee_floor"] * _ramp(t, t_flat, t_knee) + (x["knee_toe_off"] - x["knee_floor"]) * u * u
    hold = ca.logic_and(t >= x["t_hold"], x["knee_hold"] > 0)
    knee = ca.if_else(hold, x["knee_hold"] + _soft_plus(knee - x["knee_hold"], KNEE_HOLD_BLEND), knee)
    width = x["heel_blend"]
    ramp = _ramp(t, t_flat, t_flat + 0.25 * (t_knee - t_flat))
    reach = ca.sqrt(l3 * l3 + l4 * l4 + 2 * l3 * l4 * ca.cos(knee)) + 2 * width * (1 - ramp)
    flat = ca.hypot(0.0 - hx, c["l9"] - hy)
    keep = flat - _soft_plus(flat - reach, width)
    fraction_up = keep / l1
    p = ca.if_else(keep < flat, _reach_pitch(c, hx, hy, l1 * fraction_up), 0.0)
    p = ca.if_else(t < x["t_step"], p + x["deficit"], ca.fmax(p, x["pitch_ds_floor"]))
    up = ca.logic_not(t < t_flat)
    pitch, fraction = ca.if_else(up, p, rocker), ca.if_else(up, fraction_up, 1.0)
    # the leg on that foot (virtual_leg.leg_frames): the foot's pose, the two-link leg
    rocker_theta6 = x["rocker_theta6"] * ca.if_else(t_flat > 0, 1 - smoothstep(t / ca.if_else(t_flat > 0, t_flat, 1.0)), 0.0)
    q, w = c["q"], c["band"]
    below = pitch < 0
    beta = pitch - _toe_flexion(ca.fmax(pitch, 0.0), q, w)
    pivot_x = ca.if_else(below, c["heel_x"] + 0.0, c["toe_x"] - c["l13"] * ca.cos(beta) + 0.0)
    pivot_y = ca.if_else(below, c["heel_y"], c["l13"] * ca.sin(beta))
    cp, sp = ca.cos(pitch), ca.sin(pitch)
    points = {}
    for point in ("heel", "ankle", "metatarsal"):
        vx = ca.if_else(below, c[f"heel_{point}_x"], c[f"meta_{point}_x"])
        vy = ca.if_else(below, c[f"heel_{point}_y"], c[f"meta_{point}_y"])
        points[point] = (pivot_x + (cp * vx + sp * vy), pivot_y + (-sp * vx + cp * vy))
    theta6 = ca.if_else(below, rocker_theta6, _toe_flexion(pitch, q, w))
    forward = theta6 - pitch
    meta = points["metatarsal"]
    toe = (ca.if_else(below, meta[0] + c["l13"] * ca.cos(forward), c["toe_x"]),
           ca.if_else(below, meta[1] + c["l13"] * ca.sin(forward), c["toe_y"]))
    ankle = points["ankle"]
    theta3, theta4, knee_x, knee_y, distance = leg_ik(l3, l4, hx, hy, ankle[0], ankle[1])
    knee_point = (knee_x, knee_y)
    limit = l1 * ca.if_else(pitch >= MAX_PITCH, fraction, 1.0)
    world = lambda point: ca.vertcat(point[0] + x["ankle_x"], point[1] + 0.0)     # noqa: E731
    out = {"pitch": pitch, "fraction": fraction, "hip": world((hx, hy)), "knee": world(knee_point), "ankle": world(ankle),
           "heel": world(points["heel"]), "metatarsal": world(meta), "toe": world(toe), "theta3": theta3,
           "theta4": theta4, "theta5": mod(-pitch + theta3 + theta4 + math.pi / 2, TWO_PI), "theta6": theta6,
           "overreach": ca.fmax(distance - limit, 0.0)}
    return ca.Function("body_stance", [row, shared], [out[name] for name in OUTPUTS], ["row", "constants"], list(OUTPUTS))


@built_once
def library():
    """The kernel's library (built once; :meth:`~klaw_ocp.kernels.KernelLibrary.load` compiles it)."""
    # the key: the source of every module whose code builds the expressions
    modules = (sys.modules[__name__], heel_up_roots, pitch_rules)
    return mapped_library([source_key(*modules), COLUMNS, CONSTANTS, BAND_STEPS], sample_function,
                          {"body_stance_block": BLOCK})


@lru_cache(maxsize=None)
def _kernel():
    return library().functions()["body_stance_block"]


def stance_at(rows: np.ndarray, shared: np.ndarray) -> dict:
    """The kernel over n samples: their rows (n, len(COLUMNS)), the constants -> OUTPUTS name ->
    (n,) or (n, 2)."""
    return evaluate(_kernel(), BLOCK, rows, shared, OUTPUTS)
