"""Every step's swing foot in one pass: :meth:`.swing_foot.SwingFoot.lifted_foot` of many steps,
each on its own guard grid, with the same numbers to the last bit.

A step's foot costs about 90 small numpy operations, most of their time numpy's fixed overhead on
a grid of about 200 points; the walk has one per step, and the body and the summary each ask for
all of them. Here the grids are concatenated: the elementwise parts (the schedule, the ground
limits, the lowest sole point, the knee's bend) run once on the whole, and the two operations that
run along a step's grid, the running maxima of the rate-limited turn and of the cone envelope, run
on one row per step of a padded array (the padding is -inf, which a running maximum passes over),
so no maximum crosses from one step into the next. Only the interpolation from each grid to the
step's own times stays a call per step (np.interp, the function the per-step form calls).

Where the per-step form skips a sign or a step that needs no turn or lift (``part.any()``,
``need.any()``), this form computes it anyway: a zero requirement gives a turn of exactly 0.
"""
from __future__ import annotations

import numpy as np

from .leg_geometry import knee_flexion_for_reach, reach_for_knee_flexion
from .swing_foot import GUARD_RATE, SCHEDULE_FIELDS, _clip, _ground_clip, lowest_sole_point, schedule_angles


class _Grids:
    """Concatenated per-step grids: each step's first and last value broadcast over its points,
    and running maxima that restart at every step."""

    def __init__(self, grids: list):
        self.lengths = np.array([len(g) for g in grids])
        self.ends = np.cumsum(self.lengths)
        self.starts = self.ends - self.lengths
        self.t = np.concatenate(grids)
        self.row = np.repeat(np.arange(len(grids)), self.lengths)
        self.column = np.arange(len(self.t)) - np.repeat(self.starts, self.lengths)
        self.shape = (len(grids), int(self.lengths.max()))
        self.since = self.t - self.first(self.t)            # grid - grid[0], step by step
        self.duration = self.last(self.since)               # since[-1]

    def first(self, values):
        return np.repeat(values[self.starts], self.lengths)

    def last(self, values):
        return np.repeat(values[self.ends - 1], self.lengths)

    def running_max(self, values, backwards=False):
        """np.maximum.accumulate of each step's part (of its reverse, reversed back: ``backwards``)."""
        padded = np.full(self.shape, -np.inf)
        padded[self.row, self.column] = values
        if backwards:
            return np.maximum.accumulate(padded[:, ::-1], axis=1)[:, ::-1][self.row, self.column]
        return np.maximum.accumulate(padded, axis=1)[self.row, self.column]

    def envelope(self, part, slope):
        """max_j(part_j - slope |t_i - t_j|) as :func:`.swing_foot.rate_limited_turn` has it."""
        left = self.running_max(part + slope) - slope
        right = self.running_max(part - slope, backwards=True) + slope
        return np.maximum(left, right)


def _rate_limited_turn(grids: _Grids, required, rate=GUARD_RATE):
    """:func:`.swing_foot.rate_limited_turn` of every step at once."""
    turn = np.zeros(len(grids.t))
    ends = rate * np.minimum(grids.since, grids.duration - grids.since)
    slope = rate * grids.since
    for sign in (1.0, -1.0):
        turn += sign * np.minimum(grids.envelope(np.maximum(sign * required, 0.0), slope), ends)
    return turn


def _cone_envelope(grids: _Grids, required, rate=GUARD_RATE):
    """:func:`.swing_foot._cone_envelope` of every step at once."""
    out = np.zeros(len(grids.t))
    slope = rate * grids.since
    for sign in (1.0, -1.0):
        out += sign * grids.envelope(np.maximum(sign * required, 0.0), slope)
    return out


def _ankle_lift(body, grids: _Grids, hip, ankle, lowest):
    """:func:`.swing_foot.ankle_lift` of every step at once."""
    need = np.maximum(-lowest, 0.0)
    dx, drop = ankle[:, 0] - hip[:, 0], hip[:, 1] - ankle[:, 1]
    flexion = knee_flexion_for_reach(body, np.hypot(dx, drop))
    wanted = knee_flexion_for_reach(body, np.hypot(dx, np.maximum(drop - need, 0.0))) - flexion
    bend = _rate_limited_turn(grids, np.where(need > 0, np.maximum(wanted, 0.0), 0.0))
    reach = reach_for_knee_flexion(body, flexion + bend)
    return np.where(bend > 0, drop - np.sqrt(np.maximum(reach * reach - dx * dx, 0.0)), 0.0)


def lifted_feet(body, feet: list, times: list, grids: list, hip, ankle, shank) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`.swing_foot.SwingFoot.lifted_foot` of the steps' swing feet ``feet``, each at its own
    step-local times ``times[k]`` with its guard grid ``grids[k]``; ``hip``, ``ankle`` (m, 2) and
    ``shank`` (m,) are the dynamic leg on all grids, concatenated in order. Returns θ5, θ6 and the
    ankle's lift at the times, concatenated in order."""
    on = _Grids(grids)
    schedule = {name: np.repeat([getattr(f, name) for f in feet], on.lengths) for name in SCHEDULE_FIELDS}
    scheduled, theta6 = schedule_angles(on.t, schedule, _clip)
    ankle_y = ankle[:, 1]
    required = _ground_clip(body, scheduled, theta6, ankle_y, shank)[0] - scheduled
    turn = _rate_limited_turn(on, required)
    back = _ground_clip(body, scheduled + turn, theta6, ankle_y, shank)[0] - scheduled - turn
    turn = turn + _cone_envelope(on, back)
    # the per-step form interpolates the turn at the grid's own points: there it is the turn itself
    lowest = lowest_sole_point(body, ankle_y, shank, scheduled + turn, theta6)
    lift = _ankle_lift(body, on, hip, ankle, lowest)
    counts = [len(t) for t in times]
    at = {name: np.repeat(values[on.starts], counts) for name, values in schedule.items()}
    theta5_t, theta6_t = schedule_angles(np.concatenate(times), at, _clip)
    turn_t, lift_t = np.empty(len(theta5_t)), np.empty(len(theta5_t))
    for t, start, end, stop in zip(times, on.starts, on.ends, np.cumsum(counts)):
        grid, mine = on.t[start:end], slice(stop - len(t), stop)
        turn_t[mine], lift_t[mine] = np.interp(t, grid, turn[start:end]), np.interp(t, grid, lift[start:end])
    return theta5_t + turn_t, theta6_t, lift_t
