"""The foot's pitch through one stance (§4.2's three periods), as functions of the stance time: the
rocker about the heel after heel strike, single support's heel rise, and the push-off to toe-off.
:class:`.virtual_leg.StanceFoot` holds the numbers of one stance; :func:`rule_pitch` takes them
as numbers or one per sample, so that the body (:mod:`klaw_ocp.body_motion.stance_legs`) evaluates
many stances at once.

Pitch ``p`` is the foot's heel-up rotation (clockwise, rad), negative while it rotates toe-up about
the heel; times are the leg's stance time, 0 at its heel strike.
"""
from __future__ import annotations

import numpy as np

from .leg_geometry import clamp, smoothstep

#: The leg reaches its ankle with the hip-ankle distance this fraction of l1 (about 10° of knee
#: flexion at 1.8 m) at the other leg's heel strike and at toe-off: a fully straight knee is a
#: singular point of the inverse kinematics, and near it a millimetre of reach is degrees of knee.
#: With 5° (1 - 1e-3) the knee extending into that limit moved 2.1-2.5° a frame at 500 fps at the
#: end of single support (3.5 km/h, 1.5 m) and at toe-off (8 km/h), and started swing1 with its
#: thigh at 675°/s. People's knee is 5-10° at the other heel strike and 35-40° at toe-off.
REACH_FRACTION = 1 - 4e-3

#: The push-off lasts at least this long (s): where the double support is shorter (eq. 2 gives
#: 17 ms at 167 steps/min), the heel's rise towards the toe-off pitch begins in single support, as
#: the knee of people begins to flex before the other foot lands. Over 17 ms the knee would go
#: from 10° to 44°, 7° a frame at 500 fps.
MIN_PUSH_OFF = 0.06

#: The rules of :meth:`.virtual_leg.StanceFoot.pitch` that differ from stance to stance.
RULE_FIELDS = ("t_flat", "rocker_pitch", "rocker_rate", "t_heel_off", "t_step", "t_toe_off", "t_push",
               "pitch_ds_start", "pitch_ds_floor", "pitch_toe_off", "push_ease")


def push_start(t_step: float, t_toe_off: float, earliest: float) -> float:
    """When the push-off's line begins: the other leg's heel strike, or MIN_PUSH_OFF before toe-off
    where the double support is shorter (not before ``earliest``: the foot is flat then)."""
    return min(t_step, max(t_toe_off - MIN_PUSH_OFF, earliest))


def single_reach_fraction(t, t_flat, t_step):
    """The hip-ankle distance, as a fraction of l1, that single support lets the leg reach at its
    stance times ``t``: l1 when the foot is flat (the rocker's end, continuous with it), easing to
    REACH_FRACTION by the other leg's heel strike (a smoothstep), where the double support keeps
    it. A leg allowed to go fully straight straightens as the square root of time (up to 3.6° of
    knee in the last 2 ms of single support in configs/accelerate.yaml); kept REACH_FRACTION short,
    its knee meets that limit at a finite rate."""
    s = clamp((np.asarray(t, float) - t_flat) / np.maximum(np.asarray(t_step, float) - t_flat, 1e-12), 0.0, 1.0)
    return 1 - (1 - REACH_FRACTION) * s * s * (3 - 2 * s)


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


def _push_through(t, t_push, t_toe_off, ease):
    """How far along the push-off's line (0 at t_push, 1 at toe-off), eased in over the fraction
    ``ease`` of it (a cubic with zero start rate, joining the line with its slope)."""
    through = clamp((t - t_push) / np.maximum(t_toe_off - t_push, 1e-12), 0.0, 1.0)
    if (np.asarray(ease) > 0).any():
        s = np.minimum(through / np.where(ease > 0, ease, 1.0), 1.0)
        through = np.where((ease > 0) & (s < 1), ease * s * s * (2 - s), through)
    return through


def rule_pitch(rules: dict, t: np.ndarray, hips: np.ndarray, reach, held) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`.virtual_leg.StanceFoot.pitch` with the rules (RULE_FIELDS) as numbers or one per
    sample: ``reach(hips, fraction)`` is :meth:`.virtual_leg.StanceFoot.reach_pitch` of the foot's
    geometry, ``held(t, rows)`` the single support's held pitch at those rows (None before the
    heel-off search has set it). Returns the pitch and the reach fraction the leg is held to at
    each sample (1 where no reach rule applies)."""
    def at(name, rows):
        value = rules[name]
        return value[rows] if np.ndim(value) else value

    def line(rows):       # (t_push is inf until the double support is known: the line starts at t_step)
        through = _push_through(t[rows], np.minimum(at("t_push", rows), at("t_step", rows)), at("t_toe_off", rows),
                                at("push_ease", rows))
        start = at("pitch_ds_start", rows)
        return start + (at("pitch_toe_off", rows) - start) * through, through
    # each rule only where it applies (the walk asks mostly for one of them at a time, and each
    # numpy operation costs about as much on no samples as on a few)
    pitch, fraction = np.zeros(len(t)), np.ones(len(t))
    rocker = t < rules["t_flat"]
    if rocker.any():
        pitch[rocker] = rocker_pitch(t[rocker], at("t_flat", rocker), at("rocker_pitch", rocker),
                                      at("rocker_rate", rocker))
    single = ~rocker & (t >= np.minimum(rules["t_heel_off"], rules["t_push"])) & (t < rules["t_step"])
    if single.any():
        fraction[single] = single_reach_fraction(t[single], at("t_flat", single), at("t_step", single))
        pitch[single] = reach(hips[single], fraction[single])
        kept = held(t, single)
        if kept is not None:
            pitch[single] = np.maximum(pitch[single], kept)
        early = single & (t >= rules["t_push"])     # a short double support's push, begun early
        if early.any():
            pitch[early] = np.maximum(pitch[early], line(early)[0])
    push = ~rocker & (t >= rules["t_step"])
    if push.any():
        t_step = at("t_step", push)
        linear, through = line(push)
        # the reach goes on from where single support left it (REACH_FRACTION; l1 for a foot that
        # stood still) to REACH_FRACTION by toe-off, as the line goes
        left = single_reach_fraction(t_step, at("t_flat", push), t_step)
        fraction[push] = left + (REACH_FRACTION - left) * through
        pitch[push] = np.maximum(np.maximum(linear, at("pitch_ds_floor", push)), reach(hips[push], fraction[push]))
    return pitch, fraction
