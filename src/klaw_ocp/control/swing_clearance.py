"""The swing leg high enough for a foot (issue #36 item 6): the thigh's peak planned per step.

The dynamic swing ankle is lowest where the shank passes under the knee in swing2, at
hip − l3 cos θ3 − l4 whatever the knee does there (docs/human-gait.md), so only the thigh's angle
at that moment (or the hip's height) can lift it. Where a step's swing leaves the ankle less than
l9 above the ground (a foot would not fit: the first steps from rest, whose stance hip falls while
the leg swings, and slow steps, whose thighs swing little), the thigh's peak at t1 is planned ahead
of its heel-strike angle by the least retraction that lifts the ankle to
l9 + :data:`CLEARANCE_MARGIN_REL` l1 (:func:`clearance_retraction`), as people's thighs peak ahead
of their landing angle and retract in terminal swing. The hold's target then retracts over the
rest of the swing (:func:`klaw_ocp.control.swing_law.thigh_reference`), which costs a fraction of
the hip torque a retraction in swing3 alone did. Steps that clear the ground keep the walk's
``terminal_swing_retraction`` (0 by default) exactly.
"""
from __future__ import annotations

import math

import numpy as np

from ..dynamics import stance_hips
from ..errors import ConvergenceError
from ..kinematics.leg_geometry import leg_fk

#: how far above l9 (a fraction of l1) the planned peak puts the lowest ankle at the swing's nodes:
#: between the nodes and in the continuous model it dips by a fraction of a millimetre more
CLEARANCE_MARGIN_REL = 1.5e-3
#: the search stops within this fraction of l1 above its target (a few tenths of a millimetre)
CLEARANCE_TOLERANCE_REL = 5e-4
#: the largest retraction the search tries (deg; the attribute's range)
MAX_RETRACTION_DEG = 15.0
#: swing solves the search may spend on one step
MAX_SEARCH_SOLVES = 8


def lowest_ankle(body, swings, origin_x: float, pelvis) -> float:
    """The dynamic swing ankle's lowest height above l9 (m) in swing2 and swing3 (heel strike
    excluded), at the nodes, refined by the parabola through the lowest node and its neighbours
    (the minimum passes between nodes). Swing1's ankle follows curve P up from its toe-off
    height, which the thigh's peak does not change."""
    swings = [s for s in swings if s.name != "swing1"]
    t = np.concatenate([s.t for s in swings])
    x = np.concatenate([s.states[:, :7] for s in swings])     # (np.vstack's, without its wrapper)
    knee = np.concatenate([s.states[:, 7] if s.name != "swing3" else np.zeros(len(s.t)) for s in swings])
    hips = pelvis.swing_side_hips(t, stance_hips(body, x[:, :6], np.array([origin_x, body.l9]))[0])
    y = leg_fk(body, hips, x[:, 6], knee)[2][:, 1]
    inside = np.flatnonzero(t < t[-1])
    j = inside[np.argmin(y[inside])]
    lowest = float(y[j])
    if 0 < j < len(t) - 1 and t[j - 1] < t[j] < t[j + 1]:
        (ta, tb, tc), (ya, yb, yc) = t[j - 1:j + 2], y[j - 1:j + 2]
        # the vertex of the parabola through the three samples, where it lies between them
        denom = (ta - tb) * (ta - tc) * (tb - tc)
        a = (tc * (yb - ya) + tb * (ya - yc) + ta * (yc - yb)) / denom
        b = (tc ** 2 * (ya - yb) + tb ** 2 * (yc - ya) + ta ** 2 * (yb - yc)) / denom
        if a > 0:
            vertex = -b / (2 * a)
            if ta < vertex < tc:
                lowest = min(lowest, float(yb + a * (vertex - tb) ** 2 + (2 * a * tb + b) * (vertex - tb)))
    return lowest - body.l9


def clearance_retraction(body, solve, origin_x: float, base_deg: float, hint_deg: float | None = None):
    """A step's swings with the least thigh retraction (deg, at least ``base_deg``) whose lowest
    ankle is at least CLEARANCE_MARGIN_REL l1 above l9 (within CLEARANCE_TOLERANCE_REL l1 above
    that), by regula falsi between a retraction that falls short and one that clears. ``solve(deg)``
    solves the swings with that retraction and returns a tuple (swings, pelvis, ...). Returns (that
    tuple, retraction): the one at ``base_deg`` where it clears, and the most lifting one tried
    where even MAX_RETRACTION_DEG falls short (the body then lifts the rest:
    body_motion/swing_foot_guard.py). ``hint_deg``, the retraction the step before took, is tried
    first where it is more than ``base_deg``: a steady walk's steps then take one solve each."""
    target, tolerance = CLEARANCE_MARGIN_REL * body.l1, CLEARANCE_TOLERANCE_REL * body.l1

    def attempt(deg):
        try:
            result = solve(deg)
        except ConvergenceError:
            return None, None
        return result, lowest_ankle(body, result[0], origin_x, result[1]) - target

    lo = f_lo = hi = f_hi = found = best = None
    ceiling = MAX_RETRACTION_DEG        # lowered to a retraction whose swings did not converge
    if hint_deg is not None and hint_deg > base_deg:
        result, f = attempt(min(hint_deg, ceiling))
        if f is None:
            ceiling = min(hint_deg, ceiling)
        elif f >= 0:
            if f <= tolerance:
                return result, min(hint_deg, ceiling)
            hi, f_hi, found = min(hint_deg, ceiling), f, result
        else:
            lo, f_lo, best = min(hint_deg, ceiling), f, (f, result, min(hint_deg, ceiling))
    if lo is None:
        # the walk's own retraction: where its swings do not converge, the step fails as it would
        # without the search
        result = solve(base_deg)
        f = lowest_ankle(body, result[0], origin_x, result[1]) - target
        if f >= 0:
            return result, base_deg
        lo, f_lo, best = base_deg, f, (f, result, base_deg)
    if hi is None:
        # the first try up: the thigh angle that lifts a vertical shank's ankle by the deficit,
        # d(l3 cos θ3) = l3 sin θ3 dθ3, about a 20° thigh
        trial = min(lo + max(1.0, math.degrees(-f_lo / (body.l3 * math.sin(math.radians(20.0))))), ceiling)
    else:
        trial = lo + (hi - lo) * (-f_lo) / (f_hi - f_lo)
    for _ in range(MAX_SEARCH_SOLVES):
        result, f = attempt(trial)
        if f is not None and f >= 0:
            hi, f_hi, found = trial, f, result
            if f <= tolerance:
                break
        elif f is None:
            ceiling = trial
        else:
            if f > best[0]:
                best = (f, result, trial)
            lo, f_lo = trial, f
        if hi is None:
            # nothing clears yet: on, doubling the step, but below a retraction that did not
            # converge (half-way back to the last one that did)
            if lo >= ceiling - 0.25:
                break
            trial = min(lo + 2 * max(lo - base_deg, 1.0), MAX_RETRACTION_DEG)
            if trial >= ceiling:
                trial = 0.5 * (lo + ceiling)
            continue
        # regula falsi between the retraction that falls short and the one that clears, kept
        # inside the bracket
        trial = lo + (hi - lo) * (-f_lo) / (f_hi - f_lo)
        trial = min(max(trial, lo + 0.05 * (hi - lo)), hi - 0.05 * (hi - lo))
    if found is not None:
        return found, hi
    return best[1], best[2]
