"""The foot's pitch through one stance (§4.2's three periods), as functions of the stance time: the
rocker about the heel after heel strike, then the heel rising under the knee's schedule to toe-off.
:class:`.virtual_leg.StanceFoot` holds the numbers of one stance; :func:`rule_pitch` takes them
as numbers or one per sample, so that the body (:mod:`klaw_ocp.body_motion.stance_legs`) evaluates
many stances at once.

The paper gives heel-off's trigger (θ5 reaching a limit) and meta-off's (θ6 reaching a limit), but
not what the foot does in between. Our rule, after people's late stance (docs/human-gait.md): the
knee is the leg's lever, the foot follows it.

- **The knee's schedule** (:func:`knee_schedule`). From foot flat the knee may straighten to a
  floor that rises smoothly from 0 to ``knee_floor`` (the attribute
  ``terminal_stance_knee_flexion``, about 5°: people's knee is nearly straight in terminal stance)
  by ``t_knee``; from ``t_knee`` (``knee_flexion_lead`` of the cycle before toe-off) it flexes as
  people's knee does, with constant acceleration, to ``knee_toe_off`` at toe-off
  (``toe_off_knee_flexion``; people's knee flexes as s² over the last fifth of the stance, s from 0
  to 1). Where the θ5 limit triggered heel-off first, the knee holds ``knee_hold`` (its flexion
  then) until the schedule overtakes it (a C1 blend).
- **The pitch.** While the flat foot lets the knee stay above the schedule, the foot is flat. Where
  the hip would take the flat-foot leg beyond the schedule's reach, the heel rises by the least
  pitch that keeps the knee on the schedule (:func:`.heel_up_roots.reach_pitch`: about the first
  metatarsal head, then about the toe tip). The heel leaves the ground with zero rate: the hip-ankle
  distance the leg keeps blends into the schedule's over ``heel_blend`` (m) of the flat-foot
  distance (C1, :func:`_soft_excess`), so neither the knee's nor the ankle's rate jumps at heel-off.
  The heel does not come down again: where the rule's pitch would fall, single support keeps its
  deficit from the running maximum at its nodes (:meth:`.virtual_leg.StanceFoot.find_heel_off`),
  the double support at least the pitch it started from.

Pitch ``p`` is the foot's heel-up rotation (clockwise, rad), negative while it rotates toe-up about
the heel; times are the leg's stance time, 0 at its heel strike.
"""
from __future__ import annotations

import math

import numpy as np

from .leg_geometry import clamp, clamp_float, smoothstep

#: The least reach of the leg, as a fraction of l1 (about 10° of knee at 1.8 m): the toe-off pitch
#: is at least the one at which the leg reaches its ankle with it (:func:`.virtual_leg.toe_off_pitch`),
#: so that swing1 never starts from a leg beyond its reach.
REACH_FRACTION = 1 - 4e-3

#: The half width (fraction of l1) of the blend by which the heel leaves the ground: the hip-ankle
#: distance the leg keeps departs from the flat foot's with zero rate where the flat foot comes
#: within this much of the knee schedule's reach and meets it this much beyond (about 2 x 8.7 mm at
#: 1.8 m, 100-200 ms of the hip's travel): near the straight knee a millimetre of reach is degrees of
#: knee, and the flat foot's knee extends fast into the schedule (2 x 1.7 mm: 170-270 deg/s jumps;
#: 2 x 4.3 mm: 120 deg/s at 6 km/h once the hip led at heel strike, its knee extending at 180 deg/s
#: as the hip rose over the foot; 2 x 8.7 mm: 83 deg/s, the stance leg's largest at 100 fps).
HEEL_BLEND_REL = 1e-2
#: The width (rad) of the C1 blend by which the knee schedule overtakes a knee held at a θ5 heel-off.
KNEE_HOLD_BLEND = np.radians(3.0)

#: The rules of :meth:`.virtual_leg.StanceFoot.pitch` that differ from stance to stance.
RULE_FIELDS = ("t_flat", "rocker_pitch", "rocker_rate", "t_step", "t_knee", "t_knee_end", "knee_floor",
               "knee_toe_off", "knee_hold", "t_hold", "heel_blend", "pitch_ds_floor")


def rocker_left(t, t_flat):
    """How much of the heel-strike toe angle is left at ``t`` (1 at heel strike, 0 once flat)."""
    return np.where(t_flat > 0, 1 - smoothstep(t / np.where(t_flat > 0, t_flat, 1.0)), 0.0)


def rocker_pitch(t, t_flat, p0, rate):
    """The pitch while the foot turns about the heel, p0 (1 - s)^k (1 + c s) with s = t/t_flat and
    p0 the heel-strike pitch: it starts at ``rate`` and reaches flat at t_flat with zero rate,
    never overshooting. That is the cubic Hermite curve (k = 2) while the rate is at most three
    times the mean one; a faster start (the hip approaching the heel fast after impact) takes the
    power (1 - s)^(k + 1), k + 1 = rate·t_flat/|p0| (c = -1). Flat throughout for a standing foot."""
    turning = (t_flat > 0) & (p0 != 0)
    t_flat, p0 = np.where(turning, t_flat, 1.0), np.where(turning, p0, -1.0)
    s = clamp(t / t_flat, 0.0, 1.0)
    relative_rate = rate * t_flat / -p0
    k = np.maximum(2.0, relative_rate - 1)
    return np.where(turning, p0 * (1 - s) ** k * (1 + (k - relative_rate) * s), 0.0)


def _soft_plus(v, width):
    """A C1 max(v, 0): 0 for v <= -width, v for v >= width, the parabola (v + width)²/(4 width)
    between (v itself for width 0)."""
    if isinstance(width, float):   # one stance's rule (the walk's calls): no per-sample masks
        if width <= 0:
            return np.maximum(v, 0.0)
        return np.where(v <= -width, 0.0, np.where(v >= width, v, (v + width) ** 2 / (4 * width)))
    width = np.asarray(width, float)
    safe = np.where(width > 0, width, 1.0)
    blend = np.where(v <= -width, 0.0, np.where(v >= width, v, (v + width) ** 2 / (4 * safe)))
    return np.where(width > 0, blend, np.maximum(v, 0.0))


def _floor_ramp(t, t_flat, t_knee):
    """0 at foot flat to 1 at t_knee (a smoothstep; 1 throughout where t_knee <= t_flat)."""
    span = t_knee - t_flat
    if isinstance(span, float):   # one stance's rule
        return smoothstep((t - t_flat) / span) if span > 0 else np.ones(np.shape(t))
    span = np.asarray(span, float)
    return np.where(span > 0, smoothstep((t - t_flat) / np.where(span > 0, span, 1.0)), 1.0)


def knee_schedule(t, t_flat, t_knee, t_knee_end, knee_floor, knee_toe_off, knee_hold=0.0, t_hold=np.inf):
    """The knee's flexion (rad) below which the leg does not straighten at stance times ``t`` >=
    t_flat: ``knee_floor`` reached by a smoothstep from 0 at foot flat to ``t_knee``, then
    knee_floor + (knee_toe_off - knee_floor) s², s = (t - t_knee)/(t_knee_end - t_knee) (people's
    knee over pre-swing), held at ``knee_toe_off`` after t_knee_end; from ``t_hold`` (a heel-off
    by the θ5 limit) at least ``knee_hold`` (blended over KNEE_HOLD_BLEND)."""
    t = np.asarray(t, float)
    ramp = _floor_ramp(t, t_flat, t_knee)
    span = t_knee_end - t_knee
    s = clamp((t - t_knee) / (span if span > 0 else 1.0) if isinstance(span, float)
              else (t - t_knee) / np.where(np.asarray(span) > 0, span, 1.0), 0.0, 1.0)
    knee = knee_floor * ramp + (knee_toe_off - knee_floor) * s * s
    hold = (t >= t_hold) & (knee_hold > 0)
    if np.any(hold):
        knee = np.where(hold, knee_hold + _soft_plus(knee - knee_hold, KNEE_HOLD_BLEND), knee)
    return knee


def rule_pitch(rules: dict, t: np.ndarray, hips: np.ndarray, geometry, deficit) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`.virtual_leg.StanceFoot.pitch` with the rules (RULE_FIELDS) as numbers or one per
    sample: ``geometry`` is the stance's :class:`.virtual_leg.StanceFoot` (its foot's flat ankle
    and :meth:`~.virtual_leg.StanceFoot.reach_pitch`); ``deficit(t, rows)`` what single support adds
    to the rule at those rows to keep the heel from coming down again (None before the heel-off
    search has set it). Returns the pitch and the hip-ankle distance the leg keeps, a fraction of
    l1 (1 where no reach rule applies)."""
    if len(t) <= _FEW and not any(isinstance(value, np.ndarray) and value.ndim for value in rules.values()):
        return _one_stance_few(rules, t, hips, geometry, deficit)

    def at(name, rows):
        value = rules[name]
        return value[rows] if isinstance(value, np.ndarray) and value.ndim else value

    body = geometry.foot.body
    pitch, fraction = np.zeros(len(t)), np.ones(len(t))
    rocker = t < rules["t_flat"]
    if rocker.any():
        pitch[rocker] = rocker_pitch(t[rocker], at("t_flat", rocker), at("rocker_pitch", rocker),
                                      at("rocker_rate", rocker))
    up = ~rocker
    if not up.any():
        return pitch, fraction
    tt, h = t[up], hips[up]
    knee = knee_schedule(tt, at("t_flat", up), at("t_knee", up), at("t_knee_end", up), at("knee_floor", up),
                         at("knee_toe_off", up), at("knee_hold", up), at("t_hold", up))
    l3, l4 = body.l3, body.l4
    width = at("heel_blend", up)
    # the schedule's reach; at foot flat 2 x width beyond the straight leg, so that a leg straight
    # there (a start from rest) does not lift its heel at once, and no more a quarter of the way to
    # t_knee
    t_flat_up = at("t_flat", up)
    ramp = _floor_ramp(tt, t_flat_up, t_flat_up + 0.25 * (at("t_knee", up) - t_flat_up))
    reach = np.sqrt(l3 * l3 + l4 * l4 + 2 * l3 * l4 * np.cos(knee)) + 2 * width * (1 - ramp)
    ankle = geometry.foot.ankle
    flat = np.hypot(ankle[0] - h[:, 0], ankle[1] - h[:, 1])
    # the distance the leg keeps: the flat foot's, less its C1 excess over the schedule's reach
    # (the heel leaves the ground where the flat foot comes within ``width`` of that reach, and the
    # leg keeps the schedule's reach once the flat foot is ``width`` beyond it)
    keep = flat - _soft_plus(flat - reach, width)
    fraction[up] = keep / body.l1
    off = keep < flat
    p = np.zeros(len(tt))
    if off.any():
        p[off] = geometry.reach_pitch(h[off], fraction[up][off])
    if deficit is not None:
        single = tt < at("t_step", up)
        if single.any():
            rows = np.flatnonzero(up)[single]
            mask = np.zeros(len(t), bool)
            mask[rows] = True
            p[single] = p[single] + deficit(t, mask)
    double = tt >= at("t_step", up)
    if double.any():
        floor = at("pitch_ds_floor", up)
        p[double] = np.maximum(p[double], floor[double] if np.ndim(floor) else floor)
    pitch[up] = p
    return pitch, fraction


#: Up to this many samples of one stance (its rules numbers), :func:`rule_pitch` works on Python
#: floats, sample by sample: the walk's step asks for 1 to 21 at a time, where numpy's fixed cost
#: per call was all the time. The same operations in the same order (math's sqrt and cos are
#: numpy's; hypot stays numpy's), so the same numbers to the bit.
_FEW = 32


def _smoothstep_float(u: float) -> float:
    u = clamp_float(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def _ramp_float(t: float, t_flat: float, t_knee: float) -> float:
    """:func:`_floor_ramp` of one sample of one stance."""
    span = t_knee - t_flat
    return _smoothstep_float((t - t_flat) / span) if span > 0 else 1.0


def _soft_plus_float(v: float, width: float) -> float:
    """:func:`_soft_plus` of one number, ``width`` a number."""
    if width <= 0:
        return v if v >= 0.0 or v != v else 0.0
    return 0.0 if v <= -width else (v if v >= width else (v + width) * (v + width) / (4 * width))


def _knee_float(t: float, r: dict) -> float:
    """:func:`knee_schedule` of one sample of one stance's rules ``r``."""
    ramp = _ramp_float(t, r["t_flat"], r["t_knee"])
    span = r["t_knee_end"] - r["t_knee"]
    s = clamp_float((t - r["t_knee"]) / (span if span > 0 else 1.0), 0.0, 1.0)
    knee = r["knee_floor"] * ramp + (r["knee_toe_off"] - r["knee_floor"]) * s * s
    if t >= r["t_hold"] and r["knee_hold"] > 0:
        knee = r["knee_hold"] + _soft_plus_float(knee - r["knee_hold"], KNEE_HOLD_BLEND)
    return knee


def _one_stance_few(rules: dict, t: np.ndarray, hips: np.ndarray, geometry, deficit):
    """:func:`rule_pitch` of one stance's rules at a few samples (see _FEW); the rocker, the
    reach pitches and the deficit are asked for as the arrays ask for them (the same samples
    together: the reach's band root steps them together)."""
    body, (ankle_x, ankle_y), n = geometry.foot.body, geometry.foot.ankle.tolist(), len(t)
    times, t_flat = t.tolist(), rules["t_flat"]
    up = [j for j, tj in enumerate(times) if not tj < t_flat]
    if len(up) < n:
        rocker = [j for j, tj in enumerate(times) if tj < t_flat]
        pitch = np.zeros(n)
        pitch[rocker] = rocker_pitch(t[rocker], t_flat, rules["rocker_pitch"], rules["rocker_rate"])
        if not up:
            return pitch, np.ones(n)
        pitch = pitch.tolist()
    else:
        pitch = [0.0] * n
    flats = np.hypot(ankle_x - hips[:, 0], ankle_y - hips[:, 1]).tolist()
    l3, l4, l1, width = body.l3, body.l4, body.l1, rules["heel_blend"]
    # the schedule's reach, and 2 x width beyond it at foot flat (rule_pitch's comments);
    # _knee_float, _ramp_float and _soft_plus_float written out with the stance's constants
    # taken once (the same operations in the same order: a few us a sample less)
    t_quarter, lengths, lever = t_flat + 0.25 * (rules["t_knee"] - t_flat), l3 * l3 + l4 * l4, 2 * l3 * l4
    t_knee, knee_floor, knee_hold, t_hold = rules["t_knee"], rules["knee_floor"], rules["knee_hold"], rules["t_hold"]
    span, span_quarter, span_knee = t_knee - t_flat, t_quarter - t_flat, rules["t_knee_end"] - t_knee
    span_knee, rise, hold, widths = span_knee if span_knee > 0 else 1.0, rules["knee_toe_off"] - knee_floor, \
        knee_hold > 0, 4 * width
    sqrt, cos = math.sqrt, math.cos
    fraction, off = [1.0] * n, []
    for j in up:
        tj, flat = times[j], flats[j]
        ramp = _smoothstep_float((tj - t_flat) / span) if span > 0 else 1.0
        u = clamp_float((tj - t_knee) / span_knee, 0.0, 1.0)
        knee = knee_floor * ramp + rise * u * u
        if tj >= t_hold and hold:
            knee = knee_hold + _soft_plus_float(knee - knee_hold, KNEE_HOLD_BLEND)
        u = _smoothstep_float((tj - t_flat) / span_quarter) if span_quarter > 0 else 1.0
        reach = sqrt(lengths + lever * cos(knee)) + 2 * width * (1 - u)
        v = flat - reach
        if width <= 0:
            keep = flat - (v if v >= 0.0 or v != v else 0.0)
        else:
            keep = flat - (0.0 if v <= -width else (v if v >= width else (v + width) * (v + width) / widths))
        fraction[j] = keep / l1
        if keep < flat:
            off.append(j)
    p = dict.fromkeys(up, 0.0)
    if off:
        p.update(zip(off, geometry.reach_pitch(hips[off], np.array([fraction[j] for j in off])).tolist()))
    t_step = rules["t_step"]
    single = [j for j in up if times[j] < t_step]
    if deficit is not None and single:
        mask = np.zeros(n, bool)
        mask[single] = True
        added = np.asarray(deficit(t, mask), float)     # one per single-support sample, or a number
        added = added.tolist() if added.ndim else [float(added)] * len(single)
        p.update((j, p[j] + d) for j, d in zip(single, added))
    floor = rules["pitch_ds_floor"]
    for j in up:
        value = p[j]
        pitch[j] = value if not times[j] >= t_step or value >= floor or value != value else floor
    return np.array(pitch), np.array(fraction)
