"""The swing foot (§4.3): "a foot is added kinematically to the model whereby the ankle and
metatarsal angles are interpolated between their values at toe-off and heel strike (the former are
known from the kinematic meta-off period, the latter are specified as locomotion attributes)".

One schedule per step, :class:`SwingFoot`, written once for two kinds of numbers: plain numpy
arrays (the body's angles, plots, tests) and CasADi symbols (the swing2 and swing3 clearance paths,
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

Where the schedule would put the toe or the heel into the ground, the foot the body shows is
turned, sample by sample, by the least angle that keeps both on or above it
(:meth:`SwingFoot.grounded_angles`): in swing1, where the ankle follows curve P and the foot plays
no part in the dynamics, and wherever the straight leg of swing2 and swing3 carries the ankle low.
Swing2's toe-clearance path constrains the scheduled foot (the paper's recovery loop).

Angles (rad): θ5 from the shank's axis to the foot's (90° neutral, more is dorsiflexion), θ6 the
toe segment's angle to the foot (> 0 toe up). Times are the step's own (0 at its heel strike).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .leg_geometry import clamp

#: the schedule's numbers, in the order the swing context carries them
SCHEDULE_FIELDS = ("t_toe_off", "t1", "t2", "t_heel_strike", "theta5_toe_off", "theta6_toe_off",
                   "theta5_t1", "theta5_heel_strike", "theta6_heel_strike")
#: the fraction of swing1 over which the ankle dorsiflexes from its toe-off angle
ANKLE_LIFT_FRACTION = 0.5
#: the fastest the ground guard turns the ankle away from its schedule (rad/s; people's swing ankle
#: moves at up to about 200-300°/s) and the grid it is computed on (s)
GUARD_RATE = math.radians(400)
GUARD_GRID = 0.002


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


def sole_heights(body, ankle_y, shank_angle, theta5, theta6) -> tuple[np.ndarray, np.ndarray]:
    """Heights above the ground (m) of the heel and the toe tip of a foot whose ankle is at height
    ``ankle_y`` (the foot of :func:`klaw_ocp.dynamics.foot_points_sx`, vectorised)."""
    alpha = math.pi / 2 - np.asarray(shank_angle, float) + theta5     # the backward sole direction
    reach = body.metatarsal_reach
    heel = ankle_y + body.l8 * np.sin(alpha) + body.l9 * np.cos(alpha)
    toe = ankle_y - reach * np.sin(alpha) + body.l9 * np.cos(alpha) - body.l13 * np.sin(alpha + theta6)
    return heel, toe


def _ground_clip(body, theta5, theta6, ankle_y, shank) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`SwingFoot.ground_limits` of the scheduled angles ``theta5``, ``theta6`` (n,)."""
    # in the sole's backward direction α (θ5 = α - π/2 + shank; α = π: the sole level) each point
    # is ankle_y + R sin(α + ω): above the ground on the arc |α - (π/2 - ω)| <= arccos(-ankle_y/R)
    reach = body.metatarsal_reach
    heel = (np.hypot(body.l8, body.l9), math.atan2(body.l9, body.l8))
    toe_a, toe_b = -(reach + body.l13 * np.cos(theta6)), body.l9 - body.l13 * np.sin(theta6)
    toe = (np.hypot(toe_a, toe_b), np.arctan2(toe_b, toe_a))
    lower, upper = np.full(theta5.shape, -np.inf), np.full(theta5.shape, np.inf)
    fits = np.ones(theta5.shape, bool)
    for radius, phase in (heel, toe):
        centre = math.pi / 2 - phase
        centre = centre + 2 * math.pi * np.round((math.pi - centre) / (2 * math.pi))   # nearest the level sole
        half = np.arccos(clamp(-ankle_y / radius, -1.0, 1.0))
        fits &= np.abs(math.pi - centre) <= half
        # a point nearer the ankle than the ankle's height is above the ground at every angle:
        # no limit (its arc's edges, π either side, are where it points straight down)
        free = ankle_y >= radius
        lower = np.where(free, lower, np.maximum(lower, centre - half))
        upper = np.where(free, upper, np.minimum(upper, centre + half))
    to_theta5 = shank - math.pi / 2
    level = math.pi + to_theta5
    return np.where(fits, clamp(theta5, lower + to_theta5, upper + to_theta5), level), theta6


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

    def ground_limits(self, body, t, ankle_y, shank_angle) -> tuple[np.ndarray, np.ndarray]:
        """θ5 (rad) at times ``t`` clipped to the angles that keep both the toe and the heel on or
        above the ground (in closed form), with the swing leg's ankle height ``ankle_y`` and
        shank angle θ3 + θ4 (each (n,)); and the ground-limit-free schedule's θ6. Of those angles,
        the range around the level sole, which fits whenever the ankle is at least l9 up (the two
        ground limits can leave two ranges; this one moves continuously with the leg). Below l9 no
        foot fits, and the sole is level, the least deep."""
        t = np.asarray(t, float)
        return _ground_clip(body, *self.angles(t), np.broadcast_to(ankle_y, t.shape),
                            np.broadcast_to(shank_angle, t.shape))

    def grounded_angles(self, body, t, leg) -> tuple[np.ndarray, np.ndarray]:
        """θ5 and θ6 of the foot the body shows at step-local times ``t`` in the swing (n,), for
        the swing leg ``leg``: a function of times -> (ankle height, shank angle θ3 + θ4).

        The schedule, turned where it would put the toe or the heel into the ground
        (:meth:`ground_limits`). A ground limit can move fast: where the lowest point of the heel's
        circle about the ankle grazes the ground, the limiting angle moves as the square root of
        the ankle's height above it. So the turn away from the schedule is the least one that
        meets the limits and changes by at most ``GUARD_RATE`` (the smallest cone envelope of the
        required turns), computed on a fixed grid of the swing (GUARD_GRID s), so the foot is the
        same whatever frames it is sampled at; and it is 0 at toe-off and at heel strike, where the
        foot continues and becomes the stance foot. Between the grid's points the limits hold to a
        fraction of a millimetre. Where the leg is too low for any foot (first steps from rest,
        closing steps, slow steps), turning it cannot help: :meth:`lifted_foot` lifts the ankle."""
        grid = self.guard_grid()
        return self.grounded_angles_on_grid(body, t, grid, *leg(grid))

    def guard_grid(self) -> np.ndarray:
        """The swing's times at which :meth:`grounded_angles` asks for the leg (GUARD_GRID apart)."""
        n = max(int(math.ceil((self.t_heel_strike - self.t_toe_off) / GUARD_GRID)), 1) + 1
        return np.linspace(self.t_toe_off, self.t_heel_strike, n)

    def lifted_foot(self, body, t, grid, hip, ankle, shank) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The foot the body shows at step-local times ``t`` (n,): θ5 and θ6 (rad,
        :meth:`grounded_angles`) and the ankle's lift above the leg's (m,
        :func:`.swing_feet.ankle_lift`), given the leg at the times :meth:`guard_grid` ``grid``:
        its hip and ankle (m, 2) and its shank angle θ3 + θ4 (m,). One step of
        :func:`.swing_feet.lifted_feet`."""
        from .swing_feet import lifted_feet    # (swing_feet is built on this module)
        return lifted_feet(body, [self], [np.asarray(t, float)], [grid], hip, ankle, shank)

    def grounded_angles_on_grid(self, body, t, grid, ankle_y, shank) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`grounded_angles` with the leg's ankle height and shank angle at the times
        :meth:`guard_grid` given. One step of :func:`.swing_feet.grounded_feet`."""
        from .swing_feet import grounded_feet
        return grounded_feet(body, [self], [np.asarray(t, float)], [grid], ankle_y, shank)


def lowest_sole_point(body, ankle_y, shank_angle, theta5, theta6) -> np.ndarray:
    """Height (m) of the lowest of the heel, the first metatarsal head and the toe tip of the foot
    of :func:`sole_heights` (the metatarsal head is the lowest where the toes are bent up)."""
    heel, toe = sole_heights(body, ankle_y, shank_angle, theta5, theta6)
    alpha = math.pi / 2 - np.asarray(shank_angle, float) + theta5
    metatarsal = ankle_y - body.metatarsal_reach * np.sin(alpha) + body.l9 * np.cos(alpha)
    return np.minimum(np.minimum(heel, toe), metatarsal)
