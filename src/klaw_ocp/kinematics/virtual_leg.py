"""The virtual leg (§4.2, figure 6): a human leg superimposed on the telescopic stance leg.

"H is known from the simulation, T is fixed during stance": between the simulated hip and the
foot on the ground the thigh (l3), shank (l4) and foot (Table B-1 rows 8-13) follow the paper's
three periods, from the leg's heel strike to its toe-off (t_step of its own stance, then the
double support of the next step, t_ds later):

- **normal**: from heel strike the foot rotates about the heel until it is flat, then stays flat
  while the shank rotates over it. The paper leaves open what fixes the foot while it rotates about
  the heel; we let it come down to flat at ``foot_flat_fraction`` of the cycle (about 8 % in
  people), arriving with zero rate and starting with the rate that keeps the hip-ankle distance
  still at heel strike, or where that is faster than the joints follow, landing with the knee a
  little flexed (:meth:`StanceFoot.at_heel_strike`, :mod:`.landing`), and the knee follow by
  inverse kinematics;
- **heel-off**: when the ankle angle θ5 reaches its limit (``heel_off_theta5``, a dorsiflexion:
  θ5 is the angle from the shank's axis to the foot's, 90° neutral, more when the shank leans
  forward over the foot) the foot rotates about the first metatarsal head (radius l12) while the
  toe stays flat on the ground, so θ6 equals the foot's pitch. In single support the ankle stays
  at its limit (the pitch solves θ5 = limit: the heel comes up because the ankle stops giving);
  from the other leg's heel strike the pitch runs linearly to the toe-off pitch (the push-off;
  from MIN_PUSH_OFF before toe-off where the double support is shorter: :mod:`.pitch_rules`);
- **meta-off**: when θ6 reaches its limit (``meta_off_theta6``) the toe angle is held and the whole
  foot rotates about the toe tip until toe-off.

In every period the pitch is raised, where needed, to the least one at which the leg reaches its
ankle (from l1 at foot flat to ``REACH_FRACTION`` of it, about 10° of knee, at the other heel
strike and at toe-off), and it never falls back (the heel does not come down again). Hip and knee angles follow by two-link inverse kinematics (knee forward).

Frames: world x forward, y up, ground y = 0; arrays are over n samples; angles in radians. Pitch
``p`` is the foot's heel-up rotation (clockwise), negative while it rotates toe-up about the heel.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..body import Body
from . import heel_up_roots
from .landing import LANDING_FOOT_RATE, landing_pitch, least_landing_knee
from .leg_geometry import FlatFoot, ankle_angle, leg_ik, reach_for_knee_flexion
from .pitch_rules import MIN_PUSH_OFF, REACH_FRACTION, RULE_FIELDS, push_start, rocker_left, rule_pitch, single_reach_fraction

#: the least time (s) over which the heel's rise from the ground is a straight line in the pitch
HEEL_OFF_CHORD = 0.02
NORMAL, HEEL_OFF, META_OFF = "normal", "heel_off", "meta_off"
_PERIODS = np.array([NORMAL, HEEL_OFF, META_OFF])      # by (pitch > 0) + (pitch > meta-off)


@dataclass(frozen=True)
class VirtualLegFrames:
    """The virtual leg at n samples: world points (n, 2), angles (n,) and the period of each."""
    t: np.ndarray
    hip: np.ndarray
    knee: np.ndarray
    ankle: np.ndarray
    heel: np.ndarray
    metatarsal: np.ndarray
    toe: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    theta5: np.ndarray
    theta6: np.ndarray
    pitch: np.ndarray
    period: np.ndarray
    #: how far the hip was beyond the leg's reach (m; 0 when the leg reached): l1, or the reach the
    #: rules held it to where the foot stands at MAX_PITCH and can rise no further
    overreach: np.ndarray


@dataclass(frozen=True)
class StanceFoot:
    """The rules of one leg's stance, fixed at its heel strike (:meth:`at_heel_strike`) and
    completed as the stance goes on: the heel-off time once it is known, and the double support's
    pitches (:meth:`with_double_support`). ``t`` is the leg's stance time, 0 at its heel strike."""
    foot: FlatFoot
    rocker_pitch: float            # the pitch at heel strike (< 0: toe up about the heel)
    rocker_theta6: float           # the toe angle at heel strike
    t_flat: float                  # when the foot is flat
    heel_off_theta5: float
    meta_off_theta6: float
    t_step: float                  # the other leg's heel strike: the double support begins
    t_heel_off: float = math.inf
    t_toe_off: float = math.inf
    #: the push-off's line starts at t_push (the other leg's heel strike, earlier where the double
    #: support is short: :func:`.pitch_rules.push_start`) from pitch_ds_start; the double support
    #: keeps at least pitch_ds_floor, where single support left the pitch at the other heel strike
    t_push: float = math.inf
    pitch_ds_start: float = 0.0
    pitch_ds_floor: float = 0.0
    pitch_toe_off: float = 0.0
    #: the pitch rate at heel strike (rad/s, >= 0): see :meth:`at_heel_strike`
    rocker_rate: float = 0.0
    #: the fraction of the double support over which the push-off eases in from rest (0: at once);
    #: see :func:`hind_foot_at_rest`
    push_ease: float = 0.0
    #: the single-support pitch at the stance's nodes, never falling (set by :meth:`find_heel_off`):
    #: θ5 rises as the shank leans over the flat foot and falls again as the knee straightens, and
    #: the heel does not come down again once it is off
    single_t: tuple = ()
    single_pitch: tuple = ()
    #: the knee flexion at heel strike (rad; 0: the leg lands straight): see :mod:`.landing`
    landing_knee: float = 0.0

    @classmethod
    def at_heel_strike(cls, body: Body, attrs, ankle_x: float, hip: np.ndarray, t_step: float,
                       hip_velocity=(0.0, 0.0)) -> "StanceFoot":
        """The foot lands on its heel at (ankle_x - l8, 0) with the knee flexed by the least angle
        :mod:`.landing` allows (straight where the leg manages): its ankle is the leg's reach
        from the hip and the heel-ankle distance from the heel, which fixes the heel-strike pitch.

        The foot then comes down about the heel. With the leg straight it starts as fast as the hip
        (``hip_velocity``, m/s) approaches it, so that the hip-ankle distance starts still: any
        shortening rate would bend the straight knee as the square root of time, an infinite knee
        rate (23° in the first frame at 30 fps). With the knee flexed it starts at most
        LANDING_FOOT_RATE, and the knee takes the rest of the approach."""
        t_flat = attrs.foot_flat_fraction * 2 * t_step
        # each knee's landing pitch and still-length rate once (the search asks for a knee's foot
        # with several rates)
        poses = {0.0: landing_pitch(body, ankle_x, hip, body.l1, hip_velocity)}
        straight_pitch = poses[0.0][0]

        def landing(knee: float, rate: float | None) -> "StanceFoot":
            if knee not in poses:
                pitch, still = landing_pitch(body, ankle_x, hip, float(reach_for_knee_flexion(body, knee)), hip_velocity)
                poses[knee] = pitch, min(still, LANDING_FOOT_RATE)
            pitch, still = poses[knee]
            rate = still if rate is None else rate
            return cls(FlatFoot(body, ankle_x), pitch, math.radians(attrs.theta6_impact), t_flat,
                       math.radians(attrs.heel_off_theta5), math.radians(attrs.meta_off_theta6), t_step,
                       rocker_rate=rate, landing_knee=knee)
        return least_landing_knee(landing, hip, hip_velocity, usable=straight_pitch < 0 and t_flat > 0)

    @classmethod
    def standing(cls, body: Body, attrs, ankle_x: float, t_step: float) -> "StanceFoot":
        """The stance foot of a walk's first step from rest: flat on the ground from the start."""
        return cls(FlatFoot(body, ankle_x), 0.0, 0.0, 0.0, math.radians(attrs.heel_off_theta5),
                   math.radians(attrs.meta_off_theta6), t_step)

    # -- the pitch rules ----------------------------------------------------------------------
    def _ankle(self, pitch) -> np.ndarray:
        return self.foot.ankle_at(pitch, self.meta_off_theta6)

    def reach_pitch(self, hips: np.ndarray, fraction=1.0) -> np.ndarray:
        """The least pitch >= 0 at which the leg reaches its ankle with the hip-ankle distance
        ``fraction`` of l1 (a scalar or one per sample): l1 where the foot comes flat, easing to
        REACH_FRACTION by the other leg's heel strike (:func:`single_reach_fraction`), where the
        double support keeps it to toe-off and swing1 takes over its rates. In closed form
        (:func:`.heel_up_roots.reach_pitch`): the distance to the hip falls as the heel rises."""
        hips = np.asarray(hips, float)
        return heel_up_roots.reach_pitch(self.foot, self.meta_off_theta6, self.heel_off_theta5, hips,
                                         self.foot.body.l1 * np.asarray(fraction, float))

    def ankle_limit_pitch(self, hips: np.ndarray, flat_excess=None) -> np.ndarray:
        """The least pitch >= 0 that holds θ5 at ``heel_off_theta5`` (0 while the flat foot is
        below it; ``flat_excess``: the flat foot's θ5 less the limit, when the caller has it). θ5
        need not fall monotonically as the heel rises; this is its first crossing, in closed form
        (:func:`.heel_up_roots.ankle_limit_pitch`)."""
        hips = np.asarray(hips, float)
        if flat_excess is None:
            flat_excess = self._flat_triggers(hips)[0]
        pitch = np.zeros(len(hips))
        need = flat_excess > 0
        if need.any():
            body = self.foot.body
            pitch[need] = heel_up_roots.ankle_limit_pitch(self.foot, self.meta_off_theta6, self.heel_off_theta5,
                                                          hips[need], body.l3, body.l1)
        return pitch

    def pitch(self, t: np.ndarray, hips: np.ndarray) -> np.ndarray:
        """The foot's pitch at stance times ``t`` with the hips ``hips`` (n, 2)."""
        return self._rule_pitch(np.asarray(t, float), np.asarray(hips, float))[0]

    def _rule_pitch(self, t, hips):
        """:func:`.pitch_rules.rule_pitch` of this stance: the pitch and the reach fraction."""
        def held(t, rows):
            return np.interp(t[rows], self.single_t, self.single_pitch) if self.single_t else None
        return rule_pitch({name: getattr(self, name) for name in RULE_FIELDS}, t, hips, self.reach_pitch, held)

    def frames(self, t: np.ndarray, hips: np.ndarray) -> VirtualLegFrames:
        """The leg at stance times ``t`` (n,) with the simulated hips ``hips`` (n, 2)."""
        t, hips = np.asarray(t, float), np.asarray(hips, float)
        return leg_frames(self, t, hips, *self._rule_pitch(t, hips), self.rocker_theta6, self.t_flat)

    # -- completing the rules -----------------------------------------------------------------
    def _flat_triggers(self, hips: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """With the foot flat: θ5 minus its limit (rad) and the hip-ankle distance minus the reach
        (m, against the straight leg); the heel comes off where the first of them reaches zero."""
        body, ankle = self.foot.body, self.foot.ankle
        th3, th4, _ = leg_ik(body, hips, ankle)
        theta5 = ankle_angle(th3, th4, 0.0)
        return theta5 - self.heel_off_theta5, np.hypot(ankle[0] - hips[:, 0], ankle[1] - hips[:, 1]) - body.l1

    def find_heel_off(self, t: np.ndarray, hips: np.ndarray) -> "StanceFoot":
        """The heel-off time from the single-support samples ``t`` (the stance's nodes): the first
        zero after the foot is flat of either trigger (linear between the samples around it), or the
        other leg's heel strike if the heel stays down that long."""
        t, hips = np.asarray(t, float), np.asarray(hips, float)
        first = self.t_step
        limit, distance = self._flat_triggers(hips)
        fraction = single_reach_fraction(t, self.t_flat, self.t_step)
        triggers = (limit, distance + self.foot.body.l1 * (1 - fraction))
        for g in triggers:
            up = np.flatnonzero((g > 0) & (t >= self.t_flat))
            if not up.size:
                continue
            k = up[0]
            if k == 0 or t[k - 1] < self.t_flat or g[k - 1] > 0:
                crossing = max(t[k - 1] if k else t[k], self.t_flat)
            else:
                crossing = t[k - 1] + (t[k] - t[k - 1]) * (-g[k - 1]) / (g[k] - g[k - 1])
            first = min(first, float(crossing))
        after = t >= first
        rule = np.zeros(len(t))
        if after.any():     # the searches only where the heel is off
            rule[after] = np.maximum(self.ankle_limit_pitch(hips[after], triggers[0][after]),
                                     self.reach_pitch(hips[after], fraction[after]))
        held = np.maximum.accumulate(rule)
        # the heel leaves the ground at ``first``: the held pitch rises from 0 there, not along the
        # line between the nodes around it (which would lift the heel by a jump). It rises along a
        # chord of at least HEEL_OFF_CHORD: the ankle-limit pitch grows as the square root of the
        # time since heel-off where θ5 is stationary in the pitch (the knee then snaps, 2.2° in
        # 2 ms at 7 km/h); under the chord the ankle passes its limit by a fraction of a degree
        # for those milliseconds, and the reach still holds the leg (:func:`rule_pitch`).
        chord = after & (t < first + HEEL_OFF_CHORD)
        chord[np.flatnonzero(after)[-1:]] = False     # the last node stays, whatever its distance
        kept = after & ~chord
        single_t = np.r_[t[~after], first, t[kept]]
        return replace(self, t_heel_off=first, single_t=tuple(single_t),
                       single_pitch=tuple(np.r_[held[~after], 0.0, held[kept]]))

    @property
    def starts_standing(self) -> bool:
        """A foot that stood flat from the start (no heel strike, no rocker)."""
        return self.t_flat == 0 and self.rocker_pitch == 0

    @property
    def complete(self) -> bool:
        """Whether the next step's double support has fixed the leg's toe-off."""
        return math.isfinite(self.t_toe_off)

    def pitch_at_other_heel_strike(self, hip: np.ndarray) -> float:
        """Where single support leaves the foot's pitch when the other leg strikes (>= 0), and at
        least the reach there (a hind foot with no single support: the push starts from its
        reach, not below it, where the line would overtake the reach with a kink in the knee)."""
        before, hips = np.array([self.t_step - 1e-12]), np.atleast_2d(hip)
        pitch = max(float(self.pitch(before, hips)[0]), 0.0)
        if self.t_flat < self.t_heel_off < before[0]:
            return pitch          # single support's rule, which holds the leg to that reach already
        fraction = single_reach_fraction(self.t_step, self.t_flat, self.t_step)
        return max(pitch, float(self.reach_pitch(hips, fraction)[0]))

    def with_double_support(self, hip_at_other_heel_strike: np.ndarray, t_ds: float, pitch_toe_off: float,
                            start: float | None = None) -> "StanceFoot":
        """The rules of the double support: the pitch runs from where single support left it
        (``start``, when the caller has :meth:`pitch_at_other_heel_strike` already) to
        ``pitch_toe_off`` at toe-off, t_ds after the other leg's heel strike; where the double
        support is shorter than MIN_PUSH_OFF, the line begins that long before toe-off, from the
        single support's held pitch there."""
        if start is None:
            start = self.pitch_at_other_heel_strike(hip_at_other_heel_strike)
        t_toe_off = self.t_step + t_ds
        t_push = push_start(self.t_step, t_toe_off, self.t_flat)
        # a push-off begun in single support eases out of its held pitch (EARLY_PUSH_EASE); the
        # walking start's, begun before the walk, is at its full rate when the walk begins
        early = t_push < self.t_step and bool(self.single_t)
        line_start = float(np.interp(t_push, self.single_t, self.single_pitch)) if early else start
        # a leg that single support left straight eases into its push-off (PUSH_EASE); a bent one
        # does not: its heel rising at once keeps the leg from straightening as the hip moves away
        reach = np.hypot(*(self._ankle(np.array([start]))[0] - np.asarray(hip_at_other_heel_strike, float).ravel()))
        straight = reach >= self.foot.body.l1 * (REACH_FRACTION - 1e-9)
        return replace(self, t_toe_off=t_toe_off, t_push=t_push, pitch_ds_start=min(line_start, start),
                       pitch_ds_floor=start, pitch_toe_off=max(pitch_toe_off, start),
                       push_ease=max(self.push_ease, PUSH_EASE if straight else 0.0, EARLY_PUSH_EASE if early else 0.0))


def leg_frames(geometry: StanceFoot, t, hips, pitch, reach_fraction, rocker_theta6, t_flat) -> VirtualLegFrames:
    """The leg on ``geometry``'s foot at the pitches ``pitch``: the foot's pose (the toe angle of
    heel strike ``rocker_theta6`` fading out by ``t_flat``, numbers or one per sample), then the
    hip and knee by two-link inverse kinematics. ``reach_fraction``: the reach the rules held the
    leg to at each sample (:func:`.pitch_rules.rule_pitch`)."""
    q = geometry.meta_off_theta6
    pose = geometry.foot.pose(pitch, q, rocker_theta6 * rocker_left(t, t_flat))
    body = geometry.foot.body
    reach = np.hypot(*(pose["ankle"] - hips).T)
    th3, th4, knee = leg_ik(body, hips, pose["ankle"])
    period = _PERIODS[(pitch > 0).astype(np.intp) + (pitch > q)]
    # where the foot can rise no further, the leg keeps the reach the rules held it to, so its
    # knee does not snap straight as the hip moves out of reach
    limit = body.l1 * np.where(pitch >= heel_up_roots.MAX_PITCH, reach_fraction, 1.0)
    return VirtualLegFrames(t, hips, knee, pose["ankle"], pose["heel"], pose["metatarsal"], pose["toe"],
                            th3, th4, ankle_angle(th3, th4, pose["sole"]), pose["theta6"], pitch, period,
                            np.maximum(reach - limit, 0.0))


#: The least forward rotation of the thigh over swing1 (rad): the toe-off posture keeps the thigh at
#: least this far behind its heel-strike angle θ3 (eq. 3). See :func:`toe_off_pitch`.
MIN_SWING1_THIGH_TRAVEL = 0.15


def toe_off_pitch(foot: StanceFoot, hip: np.ndarray, pitch_start: float, pitch_wanted: float,
                  theta3_target: float) -> float:
    """The foot's pitch at toe-off: ``pitch_wanted`` (the ``toe_off_foot_pitch`` attribute), at
    least where the double support starts and the leg's reach, lowered if needed so that the thigh
    is not ahead of ``theta3_target + MIN_SWING1_THIGH_TRAVEL``.

    Swing1 carries the thigh forward to its heel-strike angle while the ankle travels forward along
    curve P (§4.3). Raising the heel with the hip still above the foot, as in the first step from
    standing, bends the knee forwards and puts the thigh ahead of that angle; swing1 would then
    have to swing it back while the ankle moves forward, through the full extension where the
    ankle-on-curve-P constraint is singular. A person starting to walk raises the heel only as far
    as the hip has moved over the foot; so does this rule. In steady walking the attribute holds."""
    hips = np.atleast_2d(np.asarray(hip, float))
    reach = float(foot.reach_pitch(hips, REACH_FRACTION)[0])
    bound = theta3_target + MIN_SWING1_THIGH_TRAVEL

    def thigh_ahead(pitch: float) -> float:
        return float(leg_ik(foot.foot.body, hips, foot._ankle(np.array([pitch])))[0][0]) - bound
    wanted = max(pitch_wanted, pitch_start, reach)
    if thigh_ahead(wanted) >= 0:
        return wanted
    lo = max(pitch_start, reach)
    if thigh_ahead(lo) <= 0:
        return lo
    hi = wanted   # the thigh angle falls monotonically as the heel rises (the ankle nears the hip)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if thigh_ahead(mid) > 0 else (lo, mid)
    return hi


#: A foot whose leg is at its reach when the double support begins (single support leaves it
#: REACH_FRACTION short of full stretch; a start from rest) eases into its push-off over this
#: fraction of the double support: a heel rising at once would bend the knee as the square root of
#: time (3.6° in the first 2 ms from rest, 15° in steps of 0.5 m at 167 steps/min). A bent leg does
#: not ease: a slow heel there lets the hip moving away straighten it, again as a square root
#: (3.2° in 2 ms at 4 km/h). It is below 1 - TOE_OFF_RATE_WINDOW (control/step_stages.py) so that the
#: toe-off posture and rate that start swing1 follow from the push's line.
PUSH_EASE = 0.5
PUSH_EASE_FROM_REST = PUSH_EASE
EARLY_PUSH_EASE = 1.0


def hind_foot_at_rest(body: Body, attrs, ankle_x: float, from_rest: bool = True) -> StanceFoot:
    """The hind foot of a walk's first step, with no stance behind it: flat until the double
    support, which then pitches it from its reach to toe-off, easing in from rest
    (PUSH_EASE_FROM_REST). In a walking start (``from_rest`` False) the walk begins mid-stride:
    the leg is at its reach (REACH_FRACTION, not straight), and where the double support is
    shorter than MIN_PUSH_OFF the push-off began before the walk, so the heel is up at its start."""
    foot = replace(StanceFoot.standing(body, attrs, ankle_x, 0.0), t_heel_off=0.0, push_ease=PUSH_EASE_FROM_REST)
    # mid-stride, its foot was flat and its leg at its reach before the walk began, and its push-off
    # is under way: no easing in
    return foot if from_rest else replace(foot, t_flat=-MIN_PUSH_OFF, push_ease=0.0)
