"""The swing foot (§4.3): "a foot is added kinematically to the model whereby the ankle and
metatarsal angles are interpolated between their values at toe-off and heel strike (the former are
known from the kinematic meta-off period, the latter are specified as locomotion attributes)".

One schedule per step, :class:`SwingFoot`, written once for two kinds of numbers: plain numpy
arrays (the body's angles, the summary, tests) and CasADi symbols (the swing2 and swing3 clearance paths,
:mod:`klaw_ocp.control.swing_law`): the foot the solvers constrain and the foot the body shows are
one schedule, which differ only in how θ5 comes back from its t1 angle in swing2 (below).

The interpolation, our choice (the text says only "interpolated"), shaped after the ankle of
people, who go on plantarflexing for a moment after toe-off, dorsiflex while the foot passes under
the body and are back at about neutral from mid-swing to heel strike (docs/human-gait.md):

- θ5 (ankle): over swing1 from its toe-off value, leaving at the stance ankle's own rate
  (``theta5_rate_toe_off``: no jump in rate at toe-off, and the push-off's plantarflexion runs on
  for a few hundredths of a second, as people's), on two constant accelerations: first
  SWING1_ANKLE_BRAKE (braking the push-off, then turning the foot up), then the one that brings
  it to rest at ``theta5_t1`` exactly at t1 (:func:`_swing1_ankle`: the least peak acceleration
  a frame-to-frame rate jump sees, C1); ``theta5_t1`` is the heel-strike attribute, dorsiflexed
  further where the toe under the knee at t1 needs it (:func:`klaw_ocp.control.curve_p.swing1_end_posture`). From
  t1 back to the heel-strike attribute, in one of two ways:

  - **the foot the body shows relaxes with the knee** (``knee`` given): it keeps θ5_t1's
    dorsiflexion in proportion to the knee's flexion, θ5 = θ5_hs + (θ5_t1 - θ5_hs)·S(u),
    S = 3s² - 2s³, u = k·θ4/θ4(t1) + (1 - k)·(t2 - t)/(t2 - t1) clipped to [0, 1], k the knee's
    share KNEE_SHARE_OF_RELAXATION (0.7). While the knee is flexed (the shank behind the
    vertical, the toe low) the foot stays up; as the extending knee swings the shank forward
    under the body the foot comes back towards neutral with it, and reaches the attribute as the
    knee reaches full extension at t2 at rest (swing2's final conditions; S's flat ends), so its
    rate never jumps. S is the cubic, not the quintic smootherstep: the knee extends at up to
    500°/s in swing2, and S'' times its rate squared is the foot's acceleration there; the
    quintic's larger curvature mid-range (5.8 against 3.6 at s = 0.8) made the swing ankle's
    largest rate jump 117°/s at 100 fps at 5 km/h (now under 100). The cubic's acceleration
    step at t1 is bounded (S''(1) times the square of the knee's rate there, 320°/s at 5 km/h:
    about 45°/s at 100 fps), and at
    t2 the knee is at rest. Held at its t1 angle into swing2 instead, the heel met the ground as the
    knee straightened, and the ground guard had to turn the foot by about 17° in 50 ms (rate
    jumps of 350-400°/s at 5 km/h);
  - **the foot swing2's toe-clearance path constrains** (no ``knee``): held through the first half
    of swing2 (SWING2_HOLD_FRACTION), then back to the attribute by t2 (a smoothstep). The paper's
    recovery loop keeps its toe ``toe_clearance`` up, and so the leg high enough for a foot. The
    body's relaxed foot is not constrained in its place: in first steps from rest, closing steps
    and slow steps the dynamic ankle passes lower than it clears, and the recovery then swung the
    thigh forward at 3-30 N m/kg (docs/human-gait.md); there the body's ground guard turns the
    foot and lifts the ankle.

  Held from then on, so the foot lands at eq. 3's angle with no rotation left. Swing1's
  accelerations are bounded rather than smooth: a cubic smoothstep's (6 D/T² at its ends) were rate
  jumps of 190-320°/s between frames at 100 fps, a quintic's after a rest 130°/s at 6 km/h;
- θ6 (toe): from its toe-off value (the meta-off limit) to the heel-strike attribute over swing1.

Where the schedule would put the toe or the heel into the ground, the foot the body shows after
the walk is turned, or lifted with the ankle (:mod:`klaw_ocp.body_motion.swing_foot_guard`); the
solvers never see that guard.

Angles (rad): θ5 from the shank's axis to the foot's (90° neutral, more is dorsiflexion), θ6 the
toe segment's angle to the foot (> 0 toe up). Times are the step's own (0 at its heel strike).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .leg_geometry import clamp

#: the schedule's numbers, in the order the swing context carries them
SCHEDULE_FIELDS = ("t_toe_off", "t1", "t2", "t_heel_strike", "theta5_toe_off", "theta6_toe_off",
                   "theta5_t1", "theta5_heel_strike", "theta6_heel_strike", "theta5_rate_toe_off", "theta4_t1")
#: how fast the swing ankle brakes the push-off's plantarflexion after toe-off (rad/s²): the
#: most a frame-to-frame rate change of 100 deg/s at 100 fps allows, less a tenth. People's ankle
#: plantarflexes for 2-3 % of the cycle after toe-off, 4-6° more (docs/human-gait.md); a quintic
#: from the toe-off rate braked more gently and went on for 5 %, 12° more at 5 km/h
SWING1_ANKLE_BRAKE = float(np.radians(9000.0))
#: guards of the two-phase curve's divisions (a push-off at rest with nothing to travel; rad/s²)
_TINY = 1e-9

#: the fraction of swing2 through which the ankle holds its t1 angle before it relaxes to the
#: heel-strike attribute: the toe is lowest about t1 and rises as the knee extends. Relaxing from t1
#: on lowered the toe onto its clearance bound in first steps from rest, whose swing2 then swung
#: the thigh 30° forward to lift it (the paper's recovery) and back again in swing3.
SWING2_HOLD_FRACTION = 0.5
#: the share of the body's swing2 foot relaxation that follows the knee's extension (the rest
#: follows time from t1 to t2, both 1 at t1 and 0 at t2): all of it, the knee's acceleration as it
#: starts to extend in early swing2 (S'(u) ü) was the swing ankle's largest rate jump, 96-110°/s
#: at 100 fps at 5 km/h, on the edge of issue #36's 100 and over it wherever the swing's timing or
#: hold moved a little; at 0.7 it is 91°/s, and the foot still comes back as the shank swings
#: under the body (the ground guard turns what is left)
KNEE_SHARE_OF_RELAXATION = 0.7


def schedule_angles(t, s: dict, clip, knee=None):
    """θ5, θ6 at ``t`` for the schedule values ``s`` (SCHEDULE_FIELDS -> numbers or symbols);
    ``clip(x, lo, hi)`` is numpy's or CasADi's. ``knee``: the knee's flexion θ4 at ``t`` (read in
    swing2 only) for the foot the body shows, None for the foot swing2's toe-clearance path
    constrains (see the module docstring for both)."""
    span1 = s["t1"] - s["t_toe_off"]
    smooth1 = _smootherstep(clip((t - s["t_toe_off"]) / span1, 0.0, 1.0))
    swing1_offset = _swing1_ankle(clip(t - s["t_toe_off"], 0.0, span1), span1, s["theta5_toe_off"],
                                  s["theta5_rate_toe_off"], s["theta5_t1"], clip) - s["theta5_t1"]
    # how much of theta5_t1's dorsiflexion is kept (1 up to t1)
    if knee is None:
        relax = s["t1"] + SWING2_HOLD_FRACTION * (s["t2"] - s["t1"])
        relaxing = clip((t - relax) / (s["t2"] - relax), 0.0, 1.0)
        kept = 1 - relaxing * relaxing * (3 - 2 * relaxing)
    else:
        # in swing2 as much as the knee keeps of its flexion at t1, none from t2 on: steps in t
        # where both sides agree (the knee is at theta4_t1 at t1 and straight at t2)
        u = clip(knee / s["theta4_t1"], 0.0, 1.0)
        # partly in time: the knee's own acceleration in early swing2 reaches the foot only in part
        u = KNEE_SHARE_OF_RELAXATION * u + (1 - KNEE_SHARE_OF_RELAXATION) * (
            1 - clip((t - s["t1"]) / (s["t2"] - s["t1"]), 0.0, 1.0))
        with_knee = u * u * (3 - 2 * u)      # (the cubic smoothstep: see the module docstring)
        kept = 1 - (t > s["t1"]) * (1 - (t < s["t2"]) * with_knee)
    theta5 = s["theta5_heel_strike"] + (s["theta5_t1"] - s["theta5_heel_strike"]) * kept + swing1_offset
    theta6 = s["theta6_toe_off"] + (s["theta6_heel_strike"] - s["theta6_toe_off"]) * smooth1
    return theta5, theta6


def _swing1_ankle(tau, span, theta0, rate0, theta1, clip):
    """θ5 at ``tau`` s after toe-off (0 <= tau <= span = t1 - toe-off): from ``theta0`` at the
    push-off's rate ``rate0`` to ``theta1`` at rest at t1, on two constant accelerations: first
    SWING1_ANKLE_BRAKE towards the target (braking the push-off's plantarflexion, then turning the
    foot up), then the one that brings it to rest at ``theta1`` exactly at t1. With the first given,
    the switch time is linear in the data: D = θ1 - θ0 = r0 t_s/2 + r0 T/2 + A t_s T/2 (from the
    rate r0 + A t_s = A2 (T - t_s) at the switch). A is at least the symmetric solution's (A2 = A,
    the least peak acceleration that meets both ends: A²T² + (2 r0 T - 4D) A - r0² = 0), so the
    second phase never needs more than the first. At 6 km/h the foot turns 34° up in 0.2 s after
    a push-off at -500°/s: 9000 then 8600°/s² (a rest in between and a quintic to t1 took
    13000°/s², a rate jump of 130°/s a frame at 100 fps). Where the target lies the other way
    (D < r0 T/2) the same with the signs turned. The ankle's rate is continuous (C1); its
    acceleration steps at toe-off, at the switch and at t1."""
    T = span
    distance = theta1 - theta0
    # turned so that the first phase accelerates in the positive sense
    sign = 2.0 * (2.0 * distance - rate0 * T >= 0) - 1.0
    r0, d = sign * rate0, sign * distance
    linear = 2.0 * r0 * T - 4.0 * d
    symmetric = (-linear + (linear * linear + 4.0 * T * T * r0 * r0) ** 0.5) / (2.0 * T * T)
    first = symmetric + clip(SWING1_ANKLE_BRAKE - symmetric, 0.0, float("inf"))      # the larger
    switch = clip((2.0 * d - r0 * T) / clip(r0 + first * T, _TINY, float("inf")), 0.0, T)
    rate_at_switch = r0 + first * switch
    second = rate_at_switch / clip(T - switch, _TINY, float("inf"))
    a = clip(tau, 0.0, switch)
    b = clip(tau - switch, 0.0, T - switch)
    return theta0 + sign * (r0 * a + 0.5 * first * a * a + rate_at_switch * b - 0.5 * second * b * b)


def _smootherstep(x):
    """10x³ - 15x⁴ + 6x⁵: from 0 to 1 with zero rate and zero acceleration at both ends."""
    return x * x * x * (10 + x * (-15 + 6 * x))


@dataclass(frozen=True)
class SwingFoot:
    """The swing foot's angle schedule of one step (step-local times, s; angles, rad)."""
    t_toe_off: float
    t1: float
    t2: float
    t_heel_strike: float
    theta5_toe_off: float
    theta6_toe_off: float
    theta5_t1: float
    theta5_heel_strike: float
    theta6_heel_strike: float
    #: the stance ankle's rate at toe-off (rad/s), which the swing ankle starts with
    theta5_rate_toe_off: float
    #: the knee's flexion at t1 (rad, > 0: curve P's end posture), the scale of the body's foot's
    #: relaxation with the knee
    theta4_t1: float

    def angles(self, t, knee=None) -> tuple[np.ndarray, np.ndarray]:
        """The scheduled θ5 and θ6 (rad) at step-local times ``t`` (n,): of the foot the body shows
        given the knee's flexion ``knee`` (n,) there, of the foot swing2's path constrains
        without (:func:`schedule_angles`)."""
        t = np.asarray(t, float)
        # the fields by name (dataclasses.asdict deep-copies: most of this method's time)
        theta5, theta6 = schedule_angles(t, {name: getattr(self, name) for name in SCHEDULE_FIELDS}, clamp,
                                         None if knee is None else np.asarray(knee, float))
        return np.full(t.shape, theta5), np.full(t.shape, theta6)   # (broadcast_to's copy costs several times more)
