"""The swing foot (§4.3): "a foot is added kinematically to the model whereby the ankle and
metatarsal angles are interpolated between their values at toe-off and heel strike (the former are
known from the kinematic meta-off period, the latter are specified as locomotion attributes)".

One schedule per step, :class:`SwingFoot`, written once for two kinds of numbers: plain numpy
arrays (the body's angles, plots, tests) and CasADi symbols (the swing2 toe-clearance path and the
swing3 heel height, :mod:`klaw_ocp.control.swing_law`), so the foot the solvers constrain is the
foot the animation shows.

Angles (rad): θ5 from the shank's axis to the foot's (90° neutral, more is dorsiflexion), θ6 the
toe segment's angle to the foot (> 0 toe up). Times are the step's own (0 at its heel strike).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

#: the schedule's numbers, in the order the swing context carries them
SCHEDULE_FIELDS = ("t_toe_off", "t1", "t2", "t_heel_strike", "theta5_toe_off", "theta6_toe_off",
                   "theta5_t1", "theta5_heel_strike", "theta6_heel_strike")


def schedule_angles(t, s: dict, clip):
    """θ5, θ6 at ``t`` for the schedule values ``s`` (SCHEDULE_FIELDS -> numbers or symbols);
    ``clip(x, lo, hi)`` is numpy's or CasADi's. Held at the t1 angles until t2, then linear to the
    heel-strike attributes."""
    u = clip((t - s["t2"]) / (s["t_heel_strike"] - s["t2"]), 0.0, 1.0)
    return (s["theta5_t1"] + u * (s["theta5_heel_strike"] - s["theta5_t1"]),
            s["theta6_heel_strike"] + 0.0 * u)


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
        """θ5 and θ6 (rad) at step-local times ``t`` (n,)."""
        t = np.asarray(t, float)
        theta5, theta6 = schedule_angles(t, asdict(self), np.clip)
        return np.broadcast_to(theta5, t.shape).copy(), np.broadcast_to(theta6, t.shape).copy()
