"""The swing foot's ground guard: the foot the body shows after the walk (§4.3's kinematic foot,
:class:`klaw_ocp.kinematics.swing_foot.SwingFoot`, relaxing with the knee in swing2, kept out of
the ground), for every step at once.

Where the schedule would put the toe or the heel into the ground, the foot the body shows is
turned, sample by sample, by the least angle that keeps both on or above it
(:func:`grounded_angles`): in swing1, where the ankle follows curve P and the foot plays no part
in the dynamics, and wherever the straight leg of swing2 and swing3 carries the ankle low. Where
the leg is too low for any foot, the ankle is lifted by a bend of the knee (:func:`ankle_lift`,
:func:`lifted_foot`). The solvers never see this guard: it runs on the solved walk, for the body's
swing legs (:mod:`.swing_legs`) and for the summary's swing-foot clearance
(:func:`klaw_ocp.results.swing_foot_clearances`).

A step's foot costs about 90 small numpy operations, most of their time numpy's fixed overhead on
a grid of about 200 points; the walk has one per step, and the body and the summary each ask for
all of them. So the grids are concatenated (:func:`lifted_feet`, :func:`grounded_feet`): the
elementwise parts (the schedule, the ground limits, the lowest sole point, the knee's bend) run
once on the whole, and the one operation that runs along a step's grid, the smooth turn's two
parabola convolutions, runs on one row per step of a padded array (the padding is -inf for the
maximum and +inf for the minimum, which each passes over), so nothing crosses from one step into
the next. Only the interpolation from each grid to the step's own times stays a call per step
(np.interp). :func:`lifted_foot`, :func:`grounded_angles_on_grid`, :func:`smooth_turn`,
:func:`ankle_lift`: the one-step forms."""
from __future__ import annotations

import math

import numpy as np

from ..kinematics.leg_geometry import clamp, knee_flexion_for_reach, reach_for_knee_flexion
from ..kinematics.swing_foot import SCHEDULE_FIELDS, SwingFoot, schedule_angles

#: the largest angular acceleration (rad/s²) of the ground guard's turn away from the schedule
#: (and of the knee's bend where it lifts the ankle): the turn is C1, so the foot's rate never
#: jumps; at 100 fps 3000°/s² is a change of rate of 30°/s between frames, where people's smooth
#: swing ankle and knee reach about 60. It adds to the schedule's own: in early swing2 at 5 km/h
#: the heel, under t1's dorsiflexed foot, meets the ground as the shank swings forward while the
#: ankle relaxes with the knee at about 70°/s between frames; with 5000°/s² the sum was 122°/s.
#: Its largest rate (rad/s; people's swing ankle moves at up to about 200-300°/s), and the grid
#: it is computed on (s).
GUARD_ACCELERATION = math.radians(3000)
GUARD_RATE = math.radians(400)
GUARD_GRID = 0.002


def guard_grid(foot: SwingFoot) -> np.ndarray:
    """The swing's times at which :func:`grounded_angles` asks for the leg (GUARD_GRID apart)."""
    n = max(int(math.ceil((foot.t_heel_strike - foot.t_toe_off) / GUARD_GRID)), 1) + 1
    return np.linspace(foot.t_toe_off, foot.t_heel_strike, n)


def sole_heights(body, ankle_y, shank_angle, theta5, theta6) -> tuple[np.ndarray, np.ndarray]:
    """Heights above the ground (m) of the heel and the toe tip of a foot whose ankle is at height
    ``ankle_y`` (the foot of :func:`klaw_ocp.dynamics.foot_points_sx`, vectorised)."""
    alpha = math.pi / 2 - np.asarray(shank_angle, float) + theta5     # the backward sole direction
    reach = body.metatarsal_reach
    heel = ankle_y + body.l8 * np.sin(alpha) + body.l9 * np.cos(alpha)
    toe = ankle_y - reach * np.sin(alpha) + body.l9 * np.cos(alpha) - body.l13 * np.sin(alpha + theta6)
    return heel, toe


def _ground_window(body, theta6, ankle_y, shank) -> tuple:
    """The θ5 range (lowest, highest) of :func:`ground_limits` with the toe angle ``theta6``, where
    one fits (``fits``), and θ5 of the level sole (``level``), each (n,)."""
    # in the sole's backward direction α (θ5 = α - π/2 + shank; α = π: the sole level) each point
    # is ankle_y + R sin(α + ω): above the ground on the arc |α - (π/2 - ω)| <= arccos(-ankle_y/R)
    reach = body.metatarsal_reach
    heel = (np.hypot(body.l8, body.l9), math.atan2(body.l9, body.l8))
    toe_a, toe_b = -(reach + body.l13 * np.cos(theta6)), body.l9 - body.l13 * np.sin(theta6)
    toe = (np.hypot(toe_a, toe_b), np.arctan2(toe_b, toe_a))
    lower, upper = np.full(np.shape(ankle_y), -np.inf), np.full(np.shape(ankle_y), np.inf)
    fits = np.ones(np.shape(ankle_y), bool)
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
    return lower + to_theta5, upper + to_theta5, fits, math.pi + to_theta5


def _clip_to(window: tuple, theta5):
    """``theta5`` clipped to a :func:`_ground_window` ``window`` (the level sole where none fits)."""
    return np.where(window[2], clamp(theta5, window[0], window[1]), window[3])


def lowest_sole_point(body, ankle_y, shank_angle, theta5, theta6) -> np.ndarray:
    """Height (m) of the lowest of the heel, the first metatarsal head and the toe tip of the foot
    of :func:`sole_heights` (the metatarsal head is the lowest where the toes are bent up)."""
    heel, toe = sole_heights(body, ankle_y, shank_angle, theta5, theta6)
    alpha = math.pi / 2 - np.asarray(shank_angle, float) + theta5
    metatarsal = ankle_y - body.metatarsal_reach * np.sin(alpha) + body.l9 * np.cos(alpha)
    return np.minimum(np.minimum(heel, toe), metatarsal)


def ground_limits(body, foot: SwingFoot, t, ankle_y, shank_angle, knee=None) -> tuple[np.ndarray, np.ndarray]:
    """θ5 (rad) of the schedule ``foot`` at times ``t`` clipped to the angles that keep both the
    toe and the heel on or above the ground (in closed form), with the swing leg's ankle height
    ``ankle_y`` and shank angle θ3 + θ4 (each (n,)); and the ground-limit-free schedule's θ6. Of
    those angles, the range around the level sole, which fits whenever the ankle is at least l9 up
    (the two ground limits can leave two ranges; this one moves continuously with the leg). Below
    l9 no foot fits, and the sole is level, the least deep."""
    theta5, theta6 = foot.angles(np.asarray(t, float), knee)
    window = _ground_window(body, theta6, np.broadcast_to(ankle_y, theta5.shape), np.broadcast_to(shank_angle, theta5.shape))
    return _clip_to(window, theta5), theta6


class _Grids:
    """Concatenated per-step grids: each step's first and last value broadcast over its points,
    and the smooth envelope of each step's part of a sampled function."""

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
        self.spacing = self.duration[self.ends - 1] / np.maximum(self.lengths - 1, 1)     # each step's grid step
        # each point's place in the flattened rows of the padded (steps, longest) array, and in its
        # rows reversed (one-dimensional indices: cheaper than (row, column) pairs)
        self.flat = self.row * self.shape[1] + self.column
        self.flat_reversed = self.row * self.shape[1] + (self.shape[1] - 1 - self.column)
        self.near_end = np.minimum(self.since, self.duration - self.since)      # from the nearer end
        self._rises = {}

    def first(self, values):
        return np.repeat(values[self.starts], self.lengths)

    def last(self, values):
        return np.repeat(values[self.ends - 1], self.lengths)

    def padded(self, values, fill: float, band: int = 0) -> np.ndarray:
        """(steps, longest grid + 2 ``band``): each step's ``values`` in its row from column ``band``,
        ``fill`` around them."""
        padded = np.full((self.shape[0], self.shape[1] + 2 * band), fill)
        padded.reshape(-1)[self.flat if not band else self.row * padded.shape[1] + self.column + band] = values
        return padded

    def running_max(self, values, backwards=False):
        """np.maximum.accumulate of each step's part (of its reverse, reversed back: ``backwards``)."""
        padded = self.padded(values, -np.inf)
        if backwards:
            return np.maximum.accumulate(padded[:, ::-1], axis=1).reshape(-1)[self.flat_reversed]
        return np.maximum.accumulate(padded, axis=1).reshape(-1)[self.flat]

    def fastest_rise(self, acceleration: np.ndarray) -> np.ndarray:
        """The fastest rise from either end of each step's grid at each step's ``acceleration``
        (rad/s²; then at GUARD_RATE) up to each point: what :func:`_smooth_turn` caps its turn by.
        The same for every turn before an escalation: kept per acceleration."""
        key = acceleration.tobytes()
        if key not in self._rises:
            a, near_end = acceleration[self.row], self.near_end
            self._rises[key] = np.where(near_end * a < GUARD_RATE, 0.5 * a * near_end * near_end,
                                        GUARD_RATE * near_end - 0.5 * GUARD_RATE * GUARD_RATE / a)
        return self._rises[key]

    def cone_envelope(self, part, rate):
        """max_j(part_j - rate |t_i - t_j|) on each step's grid (the least function at least
        ``part`` that changes by at most ``rate``), as the larger of the running maxima from the
        left and from the right (O(n), not an n x n matrix)."""
        slope = rate * self.since
        left = self.running_max(part + slope) - slope
        right = self.running_max(part - slope, backwards=True) + slope
        return np.maximum(left, right)

    def smooth_envelope(self, part, acceleration):
        """The Lasry-Lions regularisation (sup- then inf-convolution with parabolas) of ``part``
        (>= 0) on each step's grid: a C1 function at least ``part`` whose second derivative stays
        within ± ``acceleration`` (rad/s², one per step), and equal to ``part`` wherever that
        already is such a function. With λ = 2/acceleration and μ = λ/2:

            u_i = max_j part_j - (t_i - t_j)² / (2λ),    v_i = min_j u_j + (t_i - t_j)² / (2μ)

        (v >= part as 1/μ > 1/λ; v is semiconcave with constant 1/μ and semiconvex with 1/(λ - μ)).
        Only points within sqrt(2λ max(part)) of each other can matter, so each pass is a band of
        the padded rows, not an n x n matrix."""
        if not (part > 0).any():
            return np.zeros(len(self.t))
        lam = 2.0 / np.asarray(acceleration, float)                                    # (steps,)
        spacing = self.spacing
        band = int(math.ceil(math.sqrt(2 * lam.max() * float(part.max())) / spacing.min())) + 1
        squared = (np.arange(-band, band + 1) * spacing[:, None]) ** 2                 # (steps, 2 band + 1)
        windows = _windows(self.padded(part, -np.inf, band), 2 * band + 1)
        u = (windows - (squared / (2 * lam[:, None]))[:, None, :]).max(axis=2)        # (steps, longest)
        windows = _windows(self.padded(u.reshape(-1)[self.flat], np.inf, band), 2 * band + 1)
        return (windows + (squared / lam[:, None])[:, None, :]).min(axis=2).reshape(-1)[self.flat]


def _windows(padded: np.ndarray, width: int) -> np.ndarray:
    """sliding_window_view(padded, width, axis=1) of a C-contiguous (rows, columns) array, a view
    made directly (the function's Python checks cost more than the windows' arithmetic)."""
    rows, columns = padded.shape
    stride = padded.strides[1]
    return np.ndarray((rows, columns - width + 1, width), padded.dtype, padded, 0, (padded.strides[0], stride, stride))


#: how many times a step's turn may ask for four times the acceleration (GUARD_ACCELERATION up to
#: 256 times it) where the smooth one, brought to 0 at the swing's ends, cannot meet its
#: requirement in time (its rate stays within GUARD_RATE): the foot out of the ground first
GUARD_ESCALATIONS = 4
#: a requirement no larger than this (rad) is met already: the turn that meets a limit exactly
#: leaves the clip a last-bit residue of either sign (1e-16 to 1e-15 in every step's second turn
#: and often in the lift), for which the envelopes would be computed to turn the foot by as much
GUARD_ROUND_OFF = 1e-12


def _smooth_turn(grids: _Grids, required, acceleration=GUARD_ACCELERATION, escalations=GUARD_ESCALATIONS,
                 final=False):
    """The least C1 turn with its rate within ± GUARD_RATE and its acceleration within ±
    ``acceleration`` (about: the regularisation :meth:`_Grids.smooth_envelope` of the cone envelope
    :meth:`_Grids.cone_envelope`; both keep the other's bound) that is at least ``required`` where
    that is positive and at most it where negative, on every step's grid, and 0 at each grid's
    ends with zero rate (the foot leaves and lands as the stance foot has it): capped by the
    fastest such rise from either end. Where a step's caps keep its turn short of a requirement
    (one too large to come and go in time: first and closing steps' low legs), that step's
    acceleration is raised fourfold, up to ``escalations`` times; what the foot's turn leaves
    short then, the ankle's lift takes; the lift (``final``), where still short, takes the
    requirement itself (a foot in the ground is worse than a fast knee: the first steps from rest
    whose dynamic ankle passes up to 31 mm below l9 just before heel strike, issue #36)."""
    out = np.zeros(len(grids.t))
    for sign in (1.0, -1.0):
        part = np.maximum(sign * required, 0.0)
        if not (part > GUARD_ROUND_OFF).any():
            continue
        cone = grids.cone_envelope(part, GUARD_RATE)
        per_step = np.full(len(grids.lengths), float(acceleration))
        for attempt in range(escalations + 1):
            # the fastest rise from an end: at the acceleration, then at the rate
            turn = np.minimum(grids.smooth_envelope(cone, per_step), grids.fastest_rise(per_step))
            short = turn < part - GUARD_ROUND_OFF
            if not short.any():
                break
            per_step[np.unique(grids.row[short])] *= 4.0
        else:
            if final:   # still short: the requirement itself there (the ground first)
                turn = np.maximum(turn, part)
        out += sign * turn
    return out


def _ankle_lift(body, grids: _Grids, hip, ankle, lowest, flexion=None):
    """:func:`ankle_lift` of every step at once (``flexion``: the leg's knee, when the caller has it)."""
    need = np.maximum(-lowest, 0.0)
    dx, drop = ankle[:, 0] - hip[:, 0], hip[:, 1] - ankle[:, 1]
    if flexion is None:
        flexion = knee_flexion_for_reach(body, np.hypot(dx, drop))
    wanted = knee_flexion_for_reach(body, np.hypot(dx, np.maximum(drop - need, 0.0))) - flexion
    bend = _smooth_turn(grids, np.where(need > 0, np.maximum(wanted, 0.0), 0.0), final=True)
    if not (bend > 0).any():
        return np.zeros(len(bend))          # (what the lift below is without a bend)
    reach = reach_for_knee_flexion(body, flexion + bend)
    # (>= 0: where the bend is a round-off above 0, the distance's round-off could lower the ankle)
    return np.where(bend > 0, np.maximum(drop - np.sqrt(np.maximum(reach * reach - dx * dx, 0.0)), 0.0), 0.0)


def _turned(body, on: _Grids, scheduled, theta6, ankle_y, shank):
    """The turn of the ground guard (rad) of the scheduled θ5 ``scheduled`` and θ6 ``theta6`` on
    every step's grid, concatenated in order."""
    window = _ground_window(body, theta6, ankle_y, shank)    # (both clips' limits)
    return _turn_in_window(on, window, scheduled, _clip_to(window, scheduled) - scheduled)


def _turn_in_window(on: _Grids, window: tuple, scheduled, required):
    """:func:`_turned` given the ground's window and the turn it requires of the schedule."""
    turn = _smooth_turn(on, required)
    # the smooth turn lags where a large requirement falls off quickly (the schedule itself moving
    # towards the level sole), and so can overshoot into the other limit: the toe then goes down
    # where the heel needed the turn; clipped to both limits again, the clip smoothed too
    back = _clip_to(window, scheduled + turn) - scheduled - turn
    # (capped at the ends too: there the foot is the stance foot's, on the ground by construction)
    return turn + _smooth_turn(on, back)


def _scheduled(feet: list, on: _Grids, times: list, knee, knee_t) -> tuple:
    """θ5, θ6 of the schedules on the grids (the knee flexion ``knee`` there) and at each step's
    own ``times`` (``knee_t``), in one pass: ((θ5, θ6) on the grids, (θ5, θ6) at the times)."""
    table = np.array([[getattr(f, name) for name in SCHEDULE_FIELDS] for f in feet], float)
    rows = np.concatenate([np.repeat(table, on.lengths, axis=0), np.repeat(table, [len(t) for t in times], axis=0)])
    theta5, theta6 = schedule_angles(np.concatenate([on.t, *times]), dict(zip(SCHEDULE_FIELDS, rows.T)), clamp,
                                     np.concatenate([knee, knee_t]))
    g = len(on.t)
    return (theta5[:g], theta6[:g]), (theta5[g:], theta6[g:])


def _at_times(times: list, on: _Grids, *on_grid) -> list:
    """Each of ``on_grid`` (values on the grids) interpolated linearly to each step's own
    ``times``, concatenated in order."""
    counts = [len(t) for t in times]
    out = [np.empty(sum(counts)) for _ in on_grid]
    for t, start, end, stop in zip(times, on.starts, on.ends, np.cumsum(counts)):
        grid, mine = on.t[start:end], slice(stop - len(t), stop)
        for o, values in zip(out, on_grid):
            o[mine] = np.interp(t, grid, values[start:end])
    return out


def guarded_frames(body, times: list, grids: list, hip, ankle, shank, theta5, theta6, window, required, knee) -> tuple:
    """The ground guard for the body's swing legs, whose leg, schedule and ground window on the
    grids (concatenated in order: ``hip``, ``ankle`` (m, 2), the rest (m,)) come compiled
    (:mod:`.swing_kernel`): :func:`lifted_feet`'s turn and lift, and the knee that relaxes the foot,
    at each step's own ``times``, concatenated in order (the foot's angles follow from them)."""
    on = _Grids(grids)
    turn = _turn_in_window(on, window, theta5, required)
    lift = _ankle_lift(body, on, hip, ankle, lowest_sole_point(body, ankle[:, 1], shank, theta5 + turn, theta6), knee)
    return _at_times(times, on, turn, lift, knee)


def grounded_feet(body, feet: list, times: list, grids: list, ankle_y, shank, knee) -> tuple[np.ndarray, np.ndarray]:
    """:func:`grounded_angles_on_grid` of the steps' swing feet ``feet``, each
    at its own step-local times ``times[k]`` with its guard grid ``grids[k]``; ``ankle_y``,
    ``shank`` and ``knee`` (m,) are the leg on all grids, concatenated in order. Returns θ5, θ6 at
    the times."""
    on = _Grids(grids)
    (scheduled, theta6), (theta5_t, theta6_t) = _scheduled(feet, on, times, knee, *_at_times(times, on, knee))
    (turn_t,) = _at_times(times, on, _turned(body, on, scheduled, theta6, ankle_y, shank))
    return theta5_t + turn_t, theta6_t


def lifted_feet(body, feet: list, times: list, grids: list, hip, ankle, shank) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`lifted_foot` of the steps' swing feet ``feet``, each at its own
    step-local times ``times[k]`` with its guard grid ``grids[k]``; ``hip``, ``ankle`` (m, 2) and
    ``shank`` (m,) are the leg on all grids, concatenated in order (its knee, which the body's foot
    relaxes with, is their distance's). Returns θ5, θ6 and the ankle's lift at the times,
    concatenated in order."""
    on = _Grids(grids)
    knee = knee_flexion_for_reach(body, np.hypot(*(ankle - hip).T))
    (scheduled, theta6), (theta5_t, theta6_t) = _scheduled(feet, on, times, knee, *_at_times(times, on, knee))
    turn = _turned(body, on, scheduled, theta6, ankle[:, 1], shank)
    lowest = lowest_sole_point(body, ankle[:, 1], shank, scheduled + turn, theta6)
    lift = _ankle_lift(body, on, hip, ankle, lowest)
    turn_t, lift_t = _at_times(times, on, turn, lift)
    return theta5_t + turn_t, theta6_t, lift_t


def grounded_angles(body, foot: SwingFoot, t, leg) -> tuple[np.ndarray, np.ndarray]:
    """θ5 and θ6 of the foot the body shows at step-local times ``t`` in the swing (n,), for
    the schedule ``foot`` and the swing leg ``leg``: a function of times -> (ankle height, shank
    angle θ3 + θ4).

    The schedule, turned where it would put the toe or the heel into the ground
    (:func:`ground_limits`). A ground limit can move fast: where the lowest point of the heel's
    circle about the ankle grazes the ground, the limiting angle moves as the square root of
    the ankle's height above it. So the turn away from the schedule is the least C1 one that
    meets the limits with its rate within ``GUARD_RATE`` and its acceleration within
    ``GUARD_ACCELERATION`` (:func:`smooth_turn`: a merely rate-limited turn's kinks were rate
    jumps of up to 400°/s), computed on a fixed grid of the swing (GUARD_GRID s), so the foot is
    the same whatever frames it is sampled at; and it is 0 at toe-off and at heel strike, where the
    foot continues and becomes the stance foot. Between the grid's points the limits hold to a
    fraction of a millimetre. Where the leg is too low for any foot (first steps from rest,
    closing steps, slow steps), turning it cannot help: :func:`lifted_foot` lifts the ankle."""
    grid = guard_grid(foot)
    return grounded_angles_on_grid(body, foot, t, grid, *leg(grid))


def grounded_angles_on_grid(body, foot: SwingFoot, t, grid, ankle_y, shank, knee) -> tuple[np.ndarray, np.ndarray]:
    """:func:`grounded_angles` with the leg's ankle height, shank angle and knee flexion at the
    times :func:`guard_grid` given. One step of :func:`grounded_feet`."""
    return grounded_feet(body, [foot], [np.asarray(t, float)], [grid], ankle_y, shank, knee)


def lifted_foot(body, foot: SwingFoot, t, grid, hip, ankle, shank) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The foot the body shows at step-local times ``t`` (n,) for the schedule ``foot``: θ5 and θ6
    (rad, :func:`grounded_angles`) and the ankle's lift above the leg's (m, :func:`ankle_lift`),
    given the leg at the times :func:`guard_grid` ``grid``: its hip and ankle (m, 2) and its shank
    angle θ3 + θ4 (m,). One step of :func:`lifted_feet`."""
    return lifted_feet(body, [foot], [np.asarray(t, float)], [grid], hip, ankle, shank)


def smooth_turn(grid: np.ndarray, required: np.ndarray, acceleration: float = GUARD_ACCELERATION,
                escalations: int = 0) -> np.ndarray:
    """The least C1 turn (rad) at the times ``grid`` (increasing, evenly spaced) that is at least
    ``required`` where that is positive and at most it where negative, whose acceleration stays
    within ± ``acceleration`` (rad/s²), and that is 0 at both ends (the foot leaves and lands as
    the stance foot has it): :func:`_smooth_turn` of one step."""
    return _smooth_turn(_Grids([np.asarray(grid, float)]), np.asarray(required, float), acceleration, escalations)


def ankle_lift(body, grid: np.ndarray, hip: np.ndarray, ankle: np.ndarray, lowest: np.ndarray) -> np.ndarray:
    """How far (m) the body lifts the swing ankle above the leg's at the times ``grid`` (a step's
    :func:`guard_grid`), given the leg's hip and ankle (n, 2) and its foot's
    lowest point there (:func:`lowest_sole_point`, with the grounded angles).

    The second stage of the ground guard. Where the leg carries the ankle lower than any foot fits
    (the straight knee of swing2's end and swing3 with the hip low: first steps from rest, closing
    steps, slow steps; docs/body.md), turning the foot cannot keep it out of the ground; the body
    then bends its knee, with the hip and the ankle's x kept, by the least angle that lifts the
    lowest point of the foot onto the ground, the bend as smooth as the foot's turn
    (:func:`smooth_turn`) and 0 at toe-off and heel strike. The foot is carried up with the
    ankle, unturned. Where the foot clears the ground the lift is 0 and the body's leg is the leg given."""
    return _ankle_lift(body, _Grids([np.asarray(grid, float)]), hip, ankle, lowest)
