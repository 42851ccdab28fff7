"""The swing foot (§4.3): "a foot is added kinematically to the model whereby the ankle and
metatarsal angles are interpolated between their values at toe-off and heel strike (the former are
known from the kinematic meta-off period, the latter are specified as locomotion attributes)".

One schedule per step, :class:`SwingFoot`, written once for two kinds of numbers: plain numpy
arrays (the body's angles, the summary, tests) and CasADi symbols (the swing2 and swing3 clearance paths,
:mod:`klaw_ocp.control.swing_law`), so the foot the solvers constrain is the foot the body shows.

The interpolation, our choice (the text says only "interpolated"), shaped after the ankle of
people, who go on plantarflexing for a moment after toe-off, dorsiflex while the foot passes under
the body and are back at about neutral from mid-swing to heel strike (docs/human-gait.md):

- θ5 (ankle): over swing1 a cubic Hermite curve from its toe-off value, leaving at the stance
  ankle's own rate there (``theta5_rate_toe_off``: no jump in rate at toe-off, and the push-off's
  plantarflexion runs on for a few hundredths of a second), to ``theta5_t1`` at t1 with zero rate;
  ``theta5_t1`` is the heel-strike attribute, dorsiflexed further where the toe under the knee at
  t1 needs it (:func:`klaw_ocp.control.curve_p.swing1_end_posture`). Held through the first half of
  swing2 (SWING2_HOLD_FRACTION), where the toe is lowest, then, while the extending knee lifts the
  toe, back to the heel-strike attribute by t2 (a smoothstep: zero rate at both ends; swing2's
  toe-clearance path constrains this foot: the paper's recovery loop keeps its toe
  ``toe_clearance`` up), held through swing3, so the foot lands at eq. 3's angle with no rotation
  left. Held dorsiflexed through swing2 instead, its heel came down to the ground as the knee
  straightened and the ground guard turned it (a 6° wiggle near 90 % of the cycle);
- θ6 (toe): from its toe-off value (the meta-off limit) to the heel-strike attribute over swing1.

Swing2's toe-clearance path constrains the scheduled foot (the paper's recovery loop). Where the
schedule would put the toe or the heel into the ground, the foot the body shows after the walk is
turned, or lifted with the ankle (:mod:`klaw_ocp.body_motion.swing_foot_guard`); the solvers never
see that guard.

Angles (rad): θ5 from the shank's axis to the foot's (90° neutral, more is dorsiflexion), θ6 the
toe segment's angle to the foot (> 0 toe up). Times are the step's own (0 at its heel strike).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .leg_geometry import clamp

#: the schedule's numbers, in the order the swing context carries them
SCHEDULE_FIELDS = ("t_toe_off", "t1", "t2", "t_heel_strike", "theta5_toe_off", "theta6_toe_off",
                   "theta5_t1", "theta5_heel_strike", "theta6_heel_strike", "theta5_rate_toe_off")
#: the fraction of swing2 through which the ankle holds its t1 angle before it relaxes to the
#: heel-strike attribute: the toe is lowest about t1 and rises as the knee extends. Relaxing from t1
#: on lowered the toe onto its clearance bound in first steps from rest, whose swing2 then swung
#: the thigh 30° forward to lift it (the paper's recovery) and back again in swing3.
SWING2_HOLD_FRACTION = 0.5


def schedule_angles(t, s: dict, clip):
    """θ5, θ6 at ``t`` for the schedule values ``s`` (SCHEDULE_FIELDS -> numbers or symbols);
    ``clip(x, lo, hi)`` is numpy's or CasADi's (see the module docstring for the shape)."""
    span1 = s["t1"] - s["t_toe_off"]
    swing1 = clip((t - s["t_toe_off"]) / span1, 0.0, 1.0)
    relax = s["t1"] + SWING2_HOLD_FRACTION * (s["t2"] - s["t1"])
    swing2 = clip((t - relax) / (s["t2"] - relax), 0.0, 1.0)
    smooth1 = swing1 * swing1 * (3 - 2 * swing1)
    smooth2 = swing2 * swing2 * (3 - 2 * swing2)
    # the cubic Hermite curve over swing1: from the toe-off angle at its rate to theta5_t1 at rest
    rising = swing1 * (1 - swing1) * (1 - swing1)          # h10, the start rate's basis
    theta5 = (s["theta5_toe_off"] + (s["theta5_t1"] - s["theta5_toe_off"]) * smooth1
              + s["theta5_rate_toe_off"] * span1 * rising
              + (s["theta5_heel_strike"] - s["theta5_t1"]) * smooth2)
    theta6 = s["theta6_toe_off"] + (s["theta6_heel_strike"] - s["theta6_toe_off"]) * smooth1
    return theta5, theta6


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
    theta5_rate_toe_off: float = 0.0

    def angles(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The scheduled θ5 and θ6 (rad) at step-local times ``t`` (n,)."""
        t = np.asarray(t, float)
        # the fields by name (dataclasses.asdict deep-copies: most of this method's time)
        theta5, theta6 = schedule_angles(t, {name: getattr(self, name) for name in SCHEDULE_FIELDS}, clamp)
        return np.full(t.shape, theta5), np.full(t.shape, theta6)   # (broadcast_to's copy costs several times more)
