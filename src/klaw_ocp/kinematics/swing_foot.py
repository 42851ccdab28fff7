"""The swing foot (§4.3): "a foot is added kinematically to the model whereby the ankle and
metatarsal angles are interpolated between their values at toe-off and heel strike (the former are
known from the kinematic meta-off period, the latter are specified as locomotion attributes)".

One schedule per step, :class:`SwingFoot`, written once for two kinds of numbers: plain numpy
arrays (the body's angles, the summary, tests) and CasADi symbols (the swing2 and swing3 clearance paths,
:mod:`klaw_ocp.control.swing_law`), so the foot the solvers constrain is the foot the body shows.

The interpolation, our choice (the text says only "interpolated"), shaped after the ankle of
people, who dorsiflex quickly after toe-off, hold the foot up while it passes under the body and
are back at neutral before the heel lands:

- θ5 (ankle): from its toe-off value to ``theta5_t1`` over the first half of swing1 (a
  smoothstep: it leaves the push-off's nearly still ankle without a jump in rate; an ease-out,
  fastest at toe-off, turned the steep foot of long steps by 2.3° in the first 2 ms), held to t1; ``theta5_t1`` is the heel-strike
  attribute, dorsiflexed further where the toe under the knee at t1 needs it
  (:func:`klaw_ocp.control.curve_p.swing1_end_posture`), through swing2 (the toe stays up
  while the knee extends: the paper's recovery loop keeps it ``toe_clearance`` up); then to the
  heel-strike attribute over swing3 (a smoothstep: zero rate at both ends), so the foot lands at
  eq. 3's angle with no rotation left;
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
                   "theta5_t1", "theta5_heel_strike", "theta6_heel_strike")
#: the fraction of swing1 over which the ankle dorsiflexes from its toe-off angle
ANKLE_LIFT_FRACTION = 0.5


def schedule_angles(t, s: dict, clip):
    """θ5, θ6 at ``t`` for the schedule values ``s`` (SCHEDULE_FIELDS -> numbers or symbols);
    ``clip(x, lo, hi)`` is numpy's or CasADi's (see the module docstring for the shape)."""
    lift = clip((t - s["t_toe_off"]) / (ANKLE_LIFT_FRACTION * (s["t1"] - s["t_toe_off"])), 0.0, 1.0)
    swing1 = clip((t - s["t_toe_off"]) / (s["t1"] - s["t_toe_off"]), 0.0, 1.0)
    swing3 = clip((t - s["t2"]) / (s["t_heel_strike"] - s["t2"]), 0.0, 1.0)
    smooth_lift = lift * lift * (3 - 2 * lift)
    smooth3 = swing3 * swing3 * (3 - 2 * swing3)
    smooth1 = swing1 * swing1 * (3 - 2 * swing1)
    theta5 = (s["theta5_toe_off"] + (s["theta5_t1"] - s["theta5_toe_off"]) * smooth_lift
              + (s["theta5_heel_strike"] - s["theta5_t1"]) * smooth3)
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

    def angles(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The scheduled θ5 and θ6 (rad) at step-local times ``t`` (n,)."""
        t = np.asarray(t, float)
        # the fields by name (dataclasses.asdict deep-copies: most of this method's time)
        theta5, theta6 = schedule_angles(t, {name: getattr(self, name) for name in SCHEDULE_FIELDS}, clamp)
        return np.full(t.shape, theta5), np.full(t.shape, theta6)   # (broadcast_to's copy costs several times more)
