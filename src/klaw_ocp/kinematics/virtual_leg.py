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
  forward over the flat foot), or when the hip would take the flat-foot leg straighter than the
  knee's schedule allows, the foot rotates about the first metatarsal head (radius l12) while the
  toe stays flat on the ground, so θ6 equals the foot's pitch. The paper does not say what fixes
  the foot then; our rule (:mod:`.pitch_rules`) follows people's late stance: the knee keeps its
  schedule (nearly straight, ``terminal_stance_knee_flexion``, then flexing as s² from
  ``knee_flexion_lead`` of the cycle before toe-off to ``toe_off_knee_flexion`` at toe-off) and
  the heel rises by the least pitch that lets it, leaving the ground with zero rate;
- **meta-off**: as θ6 nears its limit (``meta_off_theta6``) the toe joint stops following the pitch
  (a C1 blend over ``leg_geometry.META_OFF_BLEND`` either side of the limit, from where the period
  starts), the toe angle is held and the whole foot rotates about the toe tip until toe-off, on the
  same schedule.

The pitch never falls back (the heel does not come down again). Hip and knee angles follow by
two-link inverse kinematics (knee forward).

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
from .leg_geometry import (FlatFoot, ankle_angle, foot_pieces, knee_flexion_for_reach, leg_ik, leg_ik_float,
                           meta_off_band, reach_for_knee_flexion)
from .pitch_rules import HEEL_BLEND_REL, REACH_FRACTION, RULE_FIELDS, _knee_float, knee_schedule, rocker_left, rule_pitch
NORMAL, HEEL_OFF, META_OFF = "normal", "heel_off", "meta_off"
_PERIODS = np.array([NORMAL, HEEL_OFF, META_OFF])      # by (pitch > 0) + (pitch in or past the meta-off band)


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
    #: the knee's schedule (:func:`.pitch_rules.knee_schedule`, rad and stance times): its floor in
    #: terminal stance, reached by t_knee, then its flexion to knee_toe_off at t_knee_end (the
    #: toe-off, as expected at heel strike; the double support confirms it)
    t_knee: float = math.inf
    t_knee_end: float = math.inf
    #: t_knee_end - t_knee (s): the double support keeps it when it confirms the toe-off (inf: keep
    #: t_knee itself)
    knee_lead: float = math.inf
    knee_floor: float = 0.0
    knee_toe_off: float = 0.0
    #: a heel-off by the θ5 limit holds the knee at least at its flexion then, from t_hold
    knee_hold: float = 0.0
    t_hold: float = math.inf
    #: the half width (m) of the heel's C1 departure from the ground (0: a foot that stood still,
    #: whose schedule starts from rest itself)
    heel_blend: float = 0.0
    #: the double support keeps at least the pitch single support left at the other heel strike
    pitch_ds_floor: float = 0.0
    #: the pitch at toe-off (where swing1 starts)
    pitch_toe_off: float = 0.0
    #: the pitch rate at heel strike (rad/s, >= 0): see :meth:`at_heel_strike`
    rocker_rate: float = 0.0
    #: single support's nodes and what they add to the rule's pitch so that it never falls (set by
    #: :meth:`find_heel_off`): the running maximum of the rule's pitch less the rule's pitch
    single_t: tuple = ()
    single_deficit: tuple = ()
    #: the knee flexion at heel strike (rad; 0: the leg lands straight): see :mod:`.landing`
    landing_knee: float = 0.0

    @classmethod
    def at_heel_strike(cls, body: Body, attrs, ankle_x: float, hip: np.ndarray, t_step: float,
                       hip_velocity=(0.0, 0.0), t_ds_next: float | None = None) -> "StanceFoot":
        """The foot lands on its heel at (ankle_x - l8, 0) with the knee flexed by the least angle
        :mod:`.landing` allows (straight where the leg manages): its ankle is the leg's reach
        from the hip and the heel-ankle distance from the heel, which fixes the heel-strike pitch.

        The foot then comes down about the heel. With the leg straight it starts as fast as the hip
        (``hip_velocity``, m/s) approaches it, so that the hip-ankle distance starts still: any
        shortening rate would bend the straight knee as the square root of time, an infinite knee
        rate (23° in the first frame at 30 fps). With the knee flexed it starts at most
        LANDING_FOOT_RATE, and the knee takes the rest of the approach.

        ``t_ds_next``: the next step's double support (toe-off comes that long after the other leg's
        heel strike; the knee's schedule is fixed now, so that single support and the double support
        follow one curve); this step's own where not given."""
        t_flat = attrs.foot_flat_fraction * 2 * t_step
        schedule = knee_rules(body, attrs, t_flat, t_step, t_step if t_ds_next is None else t_ds_next)
        # each knee's landing pitch and still-length rate once (the search asks for a knee's foot
        # with several rates)
        poses = {0.0: landing_pitch(body, ankle_x, hip, body.l1, hip_velocity)}
        straight_pitch = poses[0.0][0]

        def pose(knee: float) -> tuple[float, float]:
            if knee not in poses:
                pitch, still = landing_pitch(body, ankle_x, hip, float(reach_for_knee_flexion(body, knee)), hip_velocity)
                poses[knee] = pitch, min(still, LANDING_FOOT_RATE)
            return poses[knee]

        def landing(knee: float, rate: float | None) -> "StanceFoot":
            pitch, still = pose(knee)
            rate = still if rate is None else rate
            return cls(FlatFoot(body, ankle_x), pitch, math.radians(attrs.theta6_impact), t_flat,
                       math.radians(attrs.heel_off_theta5), math.radians(attrs.meta_off_theta6), t_step,
                       rocker_rate=rate, landing_knee=knee, **schedule)

        def landings(knees: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return tuple(np.array(column) for column in zip(*(pose(float(knee)) for knee in knees)))
        return least_landing_knee(landing, landings, hip, hip_velocity, usable=straight_pitch < 0 and t_flat > 0)

    @classmethod
    def standing(cls, body: Body, attrs, ankle_x: float, t_step: float, t_ds_next: float | None = None) -> "StanceFoot":
        """The stance foot of a walk's first step from rest: flat on the ground from the start."""
        schedule = knee_rules(body, attrs, 0.0, t_step, 0.5 * t_step if t_ds_next is None else t_ds_next)
        return cls(FlatFoot(body, ankle_x), 0.0, 0.0, 0.0, math.radians(attrs.heel_off_theta5),
                   math.radians(attrs.meta_off_theta6), t_step, **schedule)

    # -- the pitch rules ----------------------------------------------------------------------
    def _ankle(self, pitch) -> np.ndarray:
        return self.foot.ankle_at(pitch, self.meta_off_theta6)

    def reach_pitch(self, hips: np.ndarray, fraction=1.0) -> np.ndarray:
        """The least pitch >= 0 at which the leg reaches its ankle with the hip-ankle distance
        ``fraction`` of l1 (a scalar or one per sample; the knee's schedule gives it,
        :mod:`.pitch_rules`). In closed form except about meta-off
        (:func:`.heel_up_roots.reach_pitch`): the distance to the hip falls as the heel rises."""
        hips = np.asarray(hips, float)
        return heel_up_roots.reach_pitch(self.foot, self.meta_off_theta6, hips,
                                         self.foot.body.l1 * np.asarray(fraction, float))

    def pitch(self, t: np.ndarray, hips: np.ndarray) -> np.ndarray:
        """The foot's pitch at stance times ``t`` with the hips ``hips`` (n, 2)."""
        return self._rule_pitch(np.asarray(t, float), np.asarray(hips, float))[0]

    def _rules(self) -> dict:
        """The numbers of this stance's rules (:data:`.pitch_rules.RULE_FIELDS`)."""
        return {name: getattr(self, name) for name in RULE_FIELDS}

    def _rule_pitch(self, t, hips):
        """:func:`.pitch_rules.rule_pitch` of this stance: the pitch and the reach fraction."""
        def deficit(t, rows):
            return np.interp(t[rows], self.single_t, self.single_deficit, right=0.0) if self.single_t else 0.0
        return rule_pitch(self._rules(), t, hips, self, deficit)

    def knee_schedule(self, t) -> np.ndarray:
        """The knee's schedule at stance times ``t`` (rad; :func:`.pitch_rules.knee_schedule`)."""
        return knee_schedule(np.asarray(t, float), self.t_flat, self.t_knee, self.t_knee_end, self.knee_floor,
                             self.knee_toe_off, self.knee_hold, self.t_hold)

    def frames(self, t: np.ndarray, hips: np.ndarray) -> VirtualLegFrames:
        """The leg at stance times ``t`` (n,) with the simulated hips ``hips`` (n, 2)."""
        t, hips = np.asarray(t, float), np.asarray(hips, float)
        return leg_frames(self, t, hips, *self._rule_pitch(t, hips), self.rocker_theta6, self.t_flat)

    # -- completing the rules -----------------------------------------------------------------
    def _flat_theta5(self, hips: np.ndarray) -> np.ndarray:
        """θ5 (rad) of the flat foot's leg at the hips (n, 2)."""
        th3, th4, _ = leg_ik(self.foot.body, hips, self.foot.ankle)
        return ankle_angle(th3, th4, 0.0)

    def find_heel_off(self, t: np.ndarray, hips: np.ndarray) -> "StanceFoot":
        """Heel-off from the single-support samples ``t`` (the stance's nodes), the first after the
        foot is flat of: θ5 reaching its limit (the paper's trigger: from then the knee holds at
        least its flexion there, ``knee_hold``), or the rule's pitch leaving 0 (the hip would take
        the flat-foot leg straighter than the knee's schedule); linear between the samples around
        it, or the other leg's heel strike if the heel stays down that long. Also what single
        support adds to the rule's pitch so that the heel never comes down again."""
        t, hips = np.asarray(t, float), np.asarray(hips, float)
        foot = self
        after_flat = t >= self.t_flat
        excess = self._flat_theta5(hips) - self.heel_off_theta5
        up = np.flatnonzero((excess > 0) & after_flat)
        if up.size and self.heel_blend > 0:
            k = up[0]
            flat = np.hypot(*(self.foot.ankle - hips[k]))
            schedule = _knee_float(float(t[k]), self._rules())     # one sample: on floats, the same number
            # held where the flat foot's knee is at θ5's limit, unless the schedule asks for more
            hold = float(knee_flexion_for_reach(self.foot.body, flat + self.heel_blend))
            if hold > schedule:
                foot = _replace(self, knee_hold=hold, t_hold=float(t[k]))
        pitch = foot.pitch(t, hips)
        off = np.flatnonzero((pitch > 0) & after_flat)
        first = self.t_step
        if off.size:
            k = off[0]
            first = float(t[k - 1]) if k > 0 and t[k - 1] >= self.t_flat else float(max(t[k], self.t_flat))
        # the heel does not come down again: what the running maximum adds at each node
        single = after_flat & (t < self.t_step)
        deficit = np.zeros(len(t))
        deficit[single] = np.maximum.accumulate(pitch[single]) - pitch[single] if single.any() else 0.0
        return _replace(foot, t_heel_off=first, single_t=tuple(t[single]), single_deficit=tuple(deficit[single]))

    @property
    def starts_standing(self) -> bool:
        """A foot that stood flat from the start (no heel strike, no rocker)."""
        return self.t_flat == 0 and self.rocker_pitch == 0

    @property
    def complete(self) -> bool:
        """Whether the next step's double support has fixed the leg's toe-off."""
        return math.isfinite(self.t_toe_off)

    def pitch_at_other_heel_strike(self, hip: np.ndarray) -> float:
        """Where single support leaves the foot's pitch when the other leg strikes (>= 0)."""
        before, hips = np.array([self.t_step - 1e-12]), np.atleast_2d(hip)
        return max(float(self.pitch(before, hips)[0]), 0.0)

    def with_double_support(self, hip_at_other_heel_strike: np.ndarray, t_ds: float, pitch_toe_off: float,
                            start: float | None = None, hip_toe_off: np.ndarray | None = None) -> "StanceFoot":
        """The rules of the double support: the knee's schedule goes on to toe-off, t_ds after the
        other leg's heel strike, where the foot reaches ``pitch_toe_off`` (:func:`toe_off_pitch`);
        the pitch never falls below where single support left it (``start``, when the caller has
        :meth:`pitch_at_other_heel_strike` already). Where the toe-off pitch is not the schedule's
        (a first step from rest lowers it), the schedule ends at the knee that pitch gives at
        ``hip_toe_off``."""
        if start is None:
            start = self.pitch_at_other_heel_strike(hip_at_other_heel_strike)
        t_toe_off = self.t_step + t_ds
        t_knee = t_toe_off - self.knee_lead if math.isfinite(self.knee_lead) else self.t_knee
        foot = _replace(self, t_toe_off=t_toe_off, t_knee_end=t_toe_off, t_knee=min(t_knee, t_toe_off),
                        pitch_ds_floor=start, pitch_toe_off=max(pitch_toe_off, start))
        if hip_toe_off is not None:
            hip = np.atleast_2d(np.asarray(hip_toe_off, float))
            if abs(float(foot.pitch(np.array([t_toe_off]), hip)[0]) - foot.pitch_toe_off) > 1e-12:
                ankle = self._ankle(np.array([foot.pitch_toe_off]))
                knee = float(knee_flexion_for_reach(self.foot.body, np.hypot(*(ankle[0] - hip[0]))))
                foot = _replace(foot, knee_toe_off=knee)
        return foot


def _replace(foot: StanceFoot, **changes) -> StanceFoot:
    """``dataclasses.replace(foot, **changes)`` without its checks of every field (5 us a call, four
    calls a step): StanceFoot has no ``__post_init__``, so a copy of its fields is the same foot."""
    new = object.__new__(type(foot))
    new.__dict__.update(foot.__dict__, **changes)
    return new


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
    period = leg_periods(pitch, q)
    # where the foot can rise no further, the leg keeps the reach the rules held it to, so its
    # knee does not snap straight as the hip moves out of reach
    limit = body.l1 * np.where(pitch >= heel_up_roots.MAX_PITCH, reach_fraction, 1.0)
    return VirtualLegFrames(t, hips, knee, pose["ankle"], pose["heel"], pose["metatarsal"], pose["toe"],
                            th3, th4, ankle_angle(th3, th4, pose["sole"]), pose["theta6"], pitch, period,
                            np.maximum(reach - limit, 0.0))


def leg_periods(pitch: np.ndarray, meta_off_theta6: float) -> np.ndarray:
    """The foot's period at each pitch: normal (flat or on the heel), heel-off (heel up), meta-off
    from where the toe joint stops following the pitch (the band about the limit, leg_geometry)."""
    q = meta_off_theta6
    return _PERIODS[(pitch > 0).astype(np.intp) + (pitch > q - meta_off_band(q))]


#: The least forward rotation of the thigh over swing1 (rad): the toe-off posture keeps the thigh at
#: least this far behind its heel-strike angle θ3 (eq. 3). See :func:`toe_off_pitch`.
MIN_SWING1_THIGH_TRAVEL = 0.15


def toe_off_pitch(foot: StanceFoot, hip: np.ndarray, pitch_start: float, pitch_wanted: float,
                  theta3_target: float, reach: float | None = None) -> float:
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
    if reach is None:   # the pitch at which the leg reaches with REACH_FRACTION (callers may have it)
        reach = float(foot.reach_pitch(hips, REACH_FRACTION)[0])
    bound = theta3_target + MIN_SWING1_THIGH_TRAVEL

    pieces, (hip_x, hip_y) = foot_pieces(foot.foot.body, foot.meta_off_theta6), hips[0].tolist()

    def thigh_ahead(pitch: float) -> float:     # leg_ik's θ3 at the ankle of ``pitch``, on floats
        return leg_ik_float(foot.foot.body, hip_x, hip_y, *pieces.ankle_float(foot.foot.ankle_x, pitch))[0] - bound
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


def knee_rules(body: Body, attrs, t_flat: float, t_step: float, t_ds_next: float) -> dict:
    """The knee's schedule of a stance (:func:`.pitch_rules.knee_schedule`) from the attributes:
    toe-off expected ``t_ds_next`` after the other leg's heel strike, the knee's flexion for it
    starting ``knee_flexion_lead`` of the cycle (2 t_step) before."""
    t_end = t_step + t_ds_next
    lead = attrs.knee_flexion_lead * 2 * t_step
    return {"t_knee": max(t_end - lead, t_flat), "t_knee_end": t_end, "knee_lead": lead,
            "knee_floor": attrs.rad("terminal_stance_knee_flexion"),
            "knee_toe_off": attrs.rad("toe_off_knee_flexion"), "heel_blend": HEEL_BLEND_REL * body.l1}


def hind_foot_at_rest(body: Body, attrs, ankle_x: float, from_rest: bool = True, t_cycle: float = 1.0,
                      t_ds: float = 0.1) -> StanceFoot:
    """The hind foot of a walk's first step, with no stance behind it; the first step's double
    support lasts ``t_ds`` (s). From rest it stands flat with its leg straight until the double
    support, where its heel rises as the hip moves over it and its knee bends only as far as that
    needs (no scheduled flexion: with the walking toe-off flexion, 40°, the first swing1 starts
    with the knee bent and the thigh far behind, and multiple shooting found no swing1 that
    brings the thigh to rest at t1 from there, in 4 of 13 first steps from rest). In a walking
    start (``from_rest`` False) the walk begins mid-stride: the leg has had its single support, its knee on the schedule of a walk of cycle
    ``t_cycle`` (s), its heel up where that needs it."""
    foot = replace(StanceFoot.standing(body, attrs, ankle_x, 0.0, t_ds), t_heel_off=0.0)
    if from_rest:
        return replace(foot, t_knee=0.0, knee_lead=math.inf, knee_floor=0.0, knee_toe_off=0.0, heel_blend=0.0)
    lead = attrs.knee_flexion_lead * t_cycle
    return replace(foot, t_flat=-t_cycle, t_knee=t_ds - lead, knee_lead=lead, heel_blend=HEEL_BLEND_REL * body.l1)
