"""The kinematic stages of a step between its stance and its swings (sections 4.2, 4.3), each a
plain function of what the stage before it handed on:

0. :func:`step_pelvis`: the pelvis's rotation and list about the stance hip (§4.2, the
   determinants); its ``swing_side_hips`` put the swing leg's hip, the pelvis's other hip, where
   the hind leg's double support, curve P and the swing models take it from
   (:mod:`klaw_ocp.kinematics.pelvis`: the kinematics reaching back into the dynamics);
1. :func:`stance_leg_rules`: the virtual leg's rules of the stance leg (§4.2) from its own stance:
   its heel-strike foot (:func:`landing_stance_foot`) and its heel-off; the next step's double
   support completes them (stage 2 of that step);
2. the hind leg's virtual leg carried through the double support to toe-off, where swing1 starts
   from its posture ("the continuing stance phase of the hind leg is completed kinematically",
   §3): its rules completed (:func:`completed_hind_leg`), then the leg there
   (:func:`double_support`);
3. :func:`plan_curve_p`: curve P, the ankle path of swing1, from the toe-off ankle to the ankle
   with the toe under the knee at t1, and the swing foot's angle schedule;
4. :func:`swing_context`: the numbers the swing models read (the stance context, the solved stance
   parameters, the foot schedule, curve P, the holding gains and the subphase times).

:class:`klaw_ocp.control.step.StepController` runs them in this order between the stance solve and
the three swing solves. Frames: world x forward, y up, ground y = 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..body import Body
from ..dynamics import stance_hip
from ..kinematics.leg_geometry import reach_for_knee_flexion
from ..kinematics.pelvis import PelvisSchedule
from ..kinematics.swing_foot import SCHEDULE_FIELDS, SwingFoot
from ..kinematics.pitch_rules import REACH_FRACTION
from ..kinematics.virtual_leg import StanceFoot, toe_off_pitch
from .curve_p import curve_p_coefficients, end_slope_for_knee_rate, swing1_end_posture
from .stance_law import STANCE_PARAMETERS
from .swing_law import FOOT_CONTEXT, SWING_CONTEXT
from .torques import exponential_mean

#: Curve P spans at least this fraction of the ankle's travel from toe-off to its landing point
#: (steady steps: about 0.43 from the toe-under-knee rule). See docs/solvers.md, "The first step".
MIN_CURVE_P_TRAVEL = 0.4
#: The thigh rate that starts swing1 is the hind leg's mean rate over this fraction of t_ds before toe-off.
TOE_OFF_RATE_WINDOW = 0.1
#: The stance ankle's rate at toe-off, which the swing foot's schedule starts with, is its
#: difference over this much (s) before toe-off (the knee's schedule makes it smooth there).
ANKLE_RATE_STEP = 1e-4
#: the least knee flexion at t1 (rad) the body's swing foot relaxes against (kinematics/swing_foot.py):
#: a closing step's curve P can end with the knee all but straight
MIN_KNEE_T1 = 1e-3
#: At t1 the toe is held this fraction of l1 above ``toe_clearance`` (swing1's end posture), so
#: that swing2, whose path constraint is the clearance itself, does not start on its bound.
TOE_MARGIN_AT_T1_REL = 0.01
#: Curve P's peak a_max is at least this fraction of l1 above the higher of its two ends, so the
#: quartic has a peak between them at every speed (a_max falls with speed)...
CURVE_P_PEAK_MARGIN_REL = 0.01
#: ... and at least this fraction of its travel D: the ankle rises clear of the toe-off height
#: early in swing1, so that the swing foot can go on plantarflexing after toe-off as people's does
#: (issue #34: 3.5 cm at 5 km/h; with the 0.01 l1 alone the toe stayed within millimetres of the
#: ground and the ground guard held the ankle at its toe-off angle). Proportional to D, so a
#: closing step's short swing keeps the small peak it converges with.
CURVE_P_PEAK_MARGIN_TRAVEL = 0.07
#: A walk's closing step puts its foot down beside the stance foot while the body comes to rest
#: over that foot: the stance leg still leans, its hip still below standing height (by l1 (1 - cos
#: θ1)), and a swing leg as straight and vertical would have its ankle below l9. So its thigh peaks
#: this far (deg) behind its vertical landing angle at t1 and comes forward onto it (the hold's
#: reference, swing_law.thigh_reference), leaning as the stance leg does, the other way, and both
#: come upright together (the lowest ankle -0.9 mm at 5 km/h with the thigh vertical from t1 on).
#: Closing steps of the envelope grid (0.5-8 km/h, 1.5-2.0 m), largest peak swing hip torque and
#: lowest ankle: 1.99 N m/kg, -0.66 mm at 2.5°; 1.90, -0.34 at 3°; 1.93, -0.04 at 4°; 2.08, -0.03 at 5°
CLOSING_APPROACH_DEG = 4.0
#: ... and its curve P peaks at most this fraction of D from toe-off (the attribute
#: ``swing_peak_position``, 0.3, elsewhere). Its ankle comes down from the toe-off height (the heel
#: raised) to its t1 height over a short travel; with the peak at 0.3 D the descent's steepest
#: slope met the direction the extending knee moves the ankle (the shank 30-40° behind vertical),
#: where the knee cannot keep the ankle on the curve (∂g/∂θ4 down to 0.0075 on the envelope grid):
#: swing1 lost the curve by up to 3.5 mm and handed swing2 a knee rate anywhere in −72 to −722 °/s,
#: and some closing steps of tall bodies at 3.5-4.5 km/h peaked at 2.3-3.0 N m/kg of hip torque.
#: Spread over 0.8 D the descent stays clear of it: ∂g/∂θ4 ≥ 0.05 and the ankle on the curve to
#: 2e-5 mm on the grid's closing steps; 0.15 D failed to converge in some steps.
CLOSING_CURVE_P_PEAK = 0.2
#: A closing step whose swing1 does not converge on its curve P is planned again with the curve
#: spanning at least this fraction of the ankle's travel to its landing point (MIN_CURVE_P_TRAVEL,
#: 0.4, first). A stop after steps shorter than the natural one at 2.5-5 km/h (0.7-0.8 ×) has a
#: short travel, and its descent over 0.4 of it met the direction the knee moves the ankle again:
#: swing1's knee jumped between postures from one torque to the next and neither mode converged
#: (docs/envelope.md). At 0.5 every one of them converges. Not the first try: on the envelope grid
#: the longer curve raised the closing steps' swing hip torque at 2.5-4.5 km/h by up to 55 % (90 to
#: 139 N m, a 2.0 m body at 3 km/h) and took plain shooting through more fallbacks.
CLOSING_RETRY_CURVE_P_TRAVEL = 0.5
#: Swing1's knee follows curve P through a Baumgarte term: the ankle's height error decays at this
#: rate (1/s), a time constant of 20 ms, short against swing1's 0.1-0.2 s.
CURVE_P_BAUMGARTE = 50.0


@dataclass(frozen=True)
class DoubleSupport:
    """The hind leg from this step's heel strike to its toe-off, as the virtual leg moves it."""
    #: stance times of the double support's nodes (s) and the leg's angles there (rad)
    t: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    pitch: np.ndarray
    #: the leg at toe-off: thigh, knee, the thigh's rate (the mean over TOE_OFF_RATE_WINDOW),
    #: the ankle (world, m) and the foot's ankle and toe angles θ5, θ6 and the ankle's rate
    theta3_toe_off: float
    theta4_toe_off: float
    theta3d_toe_off: float
    ankle_toe_off: np.ndarray
    theta5_toe_off: float
    theta6_toe_off: float
    theta5d_toe_off: float
    #: the hind leg's virtual leg with its double support, and its samples (leg stance time, world hips)
    hind_foot: StanceFoot
    samples: tuple

    def as_dict(self) -> dict:
        """The samples summary.json and the walk checks read (``t``, ``theta3``, ``theta4``, ``pitch``)."""
        return {"t": self.t, "theta3": self.theta3, "theta4": self.theta4, "pitch": self.pitch}


@dataclass(frozen=True)
class CurveP:
    """Curve P (§4.3), ``y(s) = sum A_i s^(4-i)`` over the ankle's travel s since toe-off, and the
    swing foot's angle schedule that goes with it."""
    a0: float                      # the ankle's height at toe-off (m)
    a_max: float                   # its peak, at s = C (m)
    a_min: float                   # its height at t1, at s = D (m)
    C: float                       # = swing_peak_position D
    D: float                       # the ankle's travel from toe-off to t1 (m)
    x0: float                      # the toe-off ankle's x (world, m)
    coefficients: np.ndarray       # A_0 .. A_4, highest power first
    end_slope: float               # y'(D): the knee's extension rate at t1 (curve_p.end_slope_for_knee_rate)
    theta5_toe_off: float
    theta6_toe_off: float
    theta5_t1: float               # the ankle angle at t1 (its heel-strike value, or more dorsiflexed)
    swing_foot: SwingFoot

    def with_end_slope(self, share: float) -> np.ndarray:
        """The coefficients with ``share`` of the end slope (0: the paper's flat end, 1: the curve)."""
        return curve_p_coefficients(self.a0, self.a_max, self.a_min, self.C, self.D, share * self.end_slope)

    def as_dict(self) -> dict:
        return {"a0": self.a0, "a_max": self.a_max, "a_min": self.a_min, "C": self.C, "D": self.D,
                "x0": self.x0, "coefficients": self.coefficients.tolist(), "end_slope": self.end_slope,
                "theta5_toe_off": self.theta5_toe_off, "theta6_toe_off": self.theta6_toe_off,
                "theta5_t1": self.theta5_t1}


def node_at(t_nodes: np.ndarray, time: float) -> int:
    """The grid node nearest ``time`` (the subphase grids put a node on every breakpoint)."""
    return int(np.argmin(np.abs(t_nodes - time)))


def closing_hip_settle(plan) -> float:
    """The share of a step by which its hip-height reference has reached the next heel strike's
    height (:func:`klaw_ocp.control.torques.hip_height_reference`): 1 (the paper's), but t2 in a
    walk's closing step, which rises to standing height: its swing leg, coming down straight and
    vertical beside the stance leg from t2 on, then finds the hip high enough for a foot (issue #36
    item 6; people rise as the last foot comes down)."""
    t = plan.timings
    return (t.t_ds + t.t_swing2_end) / t.t_step if plan.constraints.closing else 1.0


def step_pelvis(body: Body, attrs, plan, starts_at_rest: bool, rotation_start: float | None = None) -> PelvisSchedule:
    """The pelvis of a step (§4.2): its list at mid-step is the attribute's; its rotation at this
    step's heel strike ``rotation_start``, the one the step before ended with (default: the
    attribute's; none where the walk starts from rest, the feet side by side), at the next heel
    strike the one eq. 3 split the step by (the plan's ``hip_shift``: none at a closing step's
    end). Where the attribute changes from one step to the next, the pelvis turns continuously. A
    walk's closing step does not list: its swing side's hip stays level while the body stops and the
    leg comes down beside the stance leg (with the list it hung 3-7 mm lower there)."""
    if rotation_start is None:
        rotation_start = 0.0 if starts_at_rest else attrs.rad("pelvic_rotation")
    return PelvisSchedule(width=body.l0, rotation_start=rotation_start,
                          rotation_end=math.asin(plan.constraints.hip_shift / body.l0),
                          list_peak=0.0 if plan.constraints.closing else attrs.rad("pelvic_list"),
                          t_step=plan.timings.t_step)


def stance_leg_rules(body: Body, attrs, plan, stance, hips: np.ndarray, origin_x: float,
                     standing: bool = False, next_t_ds: float | None = None) -> StanceFoot:
    """The virtual leg's rules for the stance leg of a step (§4.2), from its solved ``stance`` and
    the world hips at its nodes ``hips``: its heel-strike foot (:func:`landing_stance_foot`), its
    heel-off from the stance's hips. The next step's double support completes them
    (:func:`completed_hind_leg`)."""
    return landing_stance_foot(body, attrs, plan, stance.states[0], hips[0], origin_x, standing,
                               next_t_ds).find_heel_off(stance.t, hips)


def landing_stance_foot(body: Body, attrs, plan, start: np.ndarray, hip: np.ndarray, origin_x: float,
                        standing: bool = False, next_t_ds: float | None = None) -> StanceFoot:
    """The stance leg's rules as its heel strike fixes them, before its heel-off is found
    (:meth:`~klaw_ocp.kinematics.virtual_leg.StanceFoot.find_heel_off`): its heel-strike foot from
    the first hip (flat from the start where it is ``standing``: the first step of a walk from
    rest), its knee's schedule to the toe-off that ends the next step's double support
    (``next_t_ds``; this step's where there is no next step). The swing leg of the step before
    lands on this foot. ``start``: the stance's first state (the heel-strike map's, which the
    solvers keep to the bit), ``hip``: its world hip; so the foot is known before the stance is
    solved (:meth:`klaw_ocp.step_loop.StepLoop.next_landing`)."""
    t_step = plan.timings.t_step
    t_ds_next = plan.timings.t_ds if next_t_ds is None else next_t_ds
    if standing:
        return StanceFoot.standing(body, attrs, origin_x, t_step, t_ds_next)
    _, hip_velocity = stance_hip(body, start, np.array([origin_x, body.l9]))
    return StanceFoot.at_heel_strike(body, attrs, origin_x, hip, t_step, hip_velocity, t_ds_next)


def completed_hind_leg(attrs, plan, stance, hips: np.ndarray, hind: StanceFoot) -> StanceFoot:
    """The hind leg's rules completed by this step's double support: its toe-off pitch where the
    knee has its toe-off flexion, the pitch never below where single support left it."""
    t_to = plan.timings.t_ds
    hip_to = hips[node_at(stance.t, t_to)]
    pitch_ds = hind.pitch_at_other_heel_strike(hips[0])
    # the pitch at which the knee has its toe-off flexion (the knee's schedule ends there)
    # and the least pitch at which the leg reaches its ankle at all (toe_off_pitch's floor), in one pass
    wanted, least = hind.reach_pitch(np.array([hip_to, hip_to]), np.array([_reach_of(hind.foot.body, hind.knee_toe_off),
                                                                          REACH_FRACTION]))
    pitch_to = toe_off_pitch(hind, hip_to, pitch_ds, float(wanted), plan.constraints.theta3, float(least))
    return hind.with_double_support(hips[0], t_to, pitch_to, start=pitch_ds, hip_toe_off=hip_to)


def double_support(plan, stance, hips: np.ndarray, hip_vels: np.ndarray, hind: StanceFoot) -> DoubleSupport:
    """The hind leg (``hind``, its rules completed: :func:`completed_hind_leg`) at the double
    support's nodes and at toe-off, where swing1 starts from its posture."""
    t_to = plan.timings.t_ds
    k_to = node_at(stance.t, t_to)
    hip_to, hip_vel_to = hips[k_to], hip_vels[k_to]
    t0 = hind.t_step                      # this step's heel strike in the hind leg's stance time
    ds_nodes = np.flatnonzero(stance.t <= t_to + 1e-12)
    # swing1 starts with the thigh's mean rate over the last tenth of the double support: the
    # kinematic leg has a kink at toe-off (the heel rise stops; the leg may just have reached
    # full stretch, where its inverse kinematics is singular), and an infinitesimal difference
    # there handed swing1 thigh rates of up to 19 rad/s at 7 km/h
    window = TOE_OFF_RATE_WINDOW * t_to
    # the double support's nodes, then toe-off, the window's start and a moment before toe-off
    # (the ankle's rate there, which the swing foot starts with), in one pass
    m = len(ds_nodes)
    ends = [t0 + t_to, t0 + (t_to - window), t0 + (t_to - ANKLE_RATE_STEP)]       # np.r_ cost ~10 us
    legs = hind.frames(np.concatenate([t0 + stance.t[ds_nodes], ends]),
                       np.vstack([hips[ds_nodes], hip_to, hip_to - window * hip_vel_to,
                                  hip_to - ANKLE_RATE_STEP * hip_vel_to]))
    return DoubleSupport(t=stance.t[ds_nodes], theta3=np.array(legs.theta3[:m]), theta4=np.array(legs.theta4[:m]),
                         pitch=np.array(legs.pitch[:m]), theta3_toe_off=float(legs.theta3[m]),
                         theta4_toe_off=float(legs.theta4[m]),
                         theta3d_toe_off=float(legs.theta3[m] - legs.theta3[m + 1]) / window,
                         ankle_toe_off=legs.ankle[m], theta5_toe_off=float(legs.theta5[m]),
                         theta6_toe_off=float(legs.theta6[m]),
                         theta5d_toe_off=float(legs.theta5[m] - legs.theta5[m + 2]) / ANKLE_RATE_STEP, hind_foot=hind,
                         samples=(t0 + stance.t[ds_nodes], hips[ds_nodes]))


@lru_cache(maxsize=64)
def _reach_of(body: Body, knee: float) -> float:
    """The reach (a fraction of l1) of the knee flexed by ``knee``: the same knee every step."""
    return float(reach_for_knee_flexion(body, knee)) / body.l1


def thigh_peak(attrs, constraints) -> float:
    """θ3 at t1, where swing1 brings the thigh to rest and swing2 holds it: ahead of its
    heel-strike angle (eq. 3; θ3 < 0 ahead of the hip) by ``terminal_swing_retraction``; in a
    walk's closing step behind it by CLOSING_APPROACH_DEG."""
    if constraints.closing:
        return constraints.theta3 + math.radians(CLOSING_APPROACH_DEG)
    return constraints.theta3 - math.radians(attrs.terminal_swing_retraction)


def plan_curve_p(body: Body, attrs, plan, ds: DoubleSupport, hip_t1: np.ndarray, hip_vel_t1: np.ndarray,
                 least_travel: float = MIN_CURVE_P_TRAVEL) -> CurveP:
    """Curve P from the toe-off ankle to the ankle with the toe under the knee at t1, the thigh at
    its peak (:func:`thigh_peak`); the foot reaches its heel-strike angles by t1, dorsiflexing
    further if the toe needs it. It spans at least ``least_travel`` of the ankle's travel from
    toe-off to its landing point."""
    b, a, t, con = body, attrs, plan.timings, plan.constraints
    t_to, t1, t2 = t.t_ds, t.t_ds + t.t_swing1_end, t.t_ds + t.t_swing2_end
    theta5_hs, theta6_hs = math.radians(a.theta5_impact), math.radians(a.theta6_impact)
    thigh_t1 = thigh_peak(a, con)
    knee_t1 = hip_t1 - b.l3 * np.array([math.sin(thigh_t1), math.cos(thigh_t1)])
    ankle_t1, shank_t1, theta5_t1 = swing1_end_posture(b, knee_t1, theta5_hs, theta6_hs,
                                                a.toe_clearance + TOE_MARGIN_AT_T1_REL * b.l1)
    a0, x0 = ds.ankle_toe_off[1], ds.ankle_toe_off[0]
    a_min = ankle_t1[1]
    d_travel = max(ankle_t1[0] - x0, least_travel * (con.next_ankle_x - x0))
    a_max = max(b.l1 * (a.ankle_peak_height_rel - a.ankle_peak_height_speed_slope * plan.parameters.speed_kmh),
                max(a0, a_min) + max(CURVE_P_PEAK_MARGIN_REL * b.l1, CURVE_P_PEAK_MARGIN_TRAVEL * d_travel))
    peak = (min(a.swing_peak_position, CLOSING_CURVE_P_PEAK) if con.closing else a.swing_peak_position) * d_travel
    knee_t1_angle = shank_t1 - thigh_t1
    knee_rate = -a.knee_rate_at_t1 * knee_t1_angle / (t2 - t1)
    end_slope = end_slope_for_knee_rate(b, shank_t1, hip_vel_t1, knee_rate)
    coeffs = curve_p_coefficients(a0, a_max, a_min, peak, d_travel, end_slope)
    swing_foot = SwingFoot(t_to, t1, t2, t.t_step, ds.theta5_toe_off, ds.theta6_toe_off, theta5_t1,
                           theta5_hs, theta6_hs, ds.theta5d_toe_off, max(knee_t1_angle, MIN_KNEE_T1))
    return CurveP(a0=a0, a_max=a_max, a_min=a_min, C=peak, D=d_travel, x0=x0, coefficients=coeffs, end_slope=end_slope,
                  theta5_toe_off=ds.theta5_toe_off, theta6_toe_off=ds.theta6_toe_off, theta5_t1=theta5_t1,
                  swing_foot=swing_foot)


#: the curve P entries of the swing context
_CURVE_P_ENTRIES = [SWING_CONTEXT.names.index(f"P{i}") for i in range(5)]


def with_curve_p(c: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """The swing context ``c`` with curve P's coefficients replaced."""
    c = np.array(c, float)
    c[_CURVE_P_ENTRIES] = coefficients
    return c


def swing_context(body: Body, attrs, gains, plan, stance_context: dict, stance_parameters: dict,
                  origin: np.ndarray, curve: CurveP, pelvis: PelvisSchedule) -> np.ndarray:
    """The swing models' context vector (:data:`klaw_ocp.control.swing_law.SWING_CONTEXT`): they
    re-simulate the stance (its context and solved parameters) and read curve P, the foot's
    schedule, the holding gains and the subphase times from it."""
    b, a, t, con = body, attrs, plan.timings, plan.constraints
    t_to, t1, t2 = t.t_ds, t.t_ds + t.t_swing1_end, t.t_ds + t.t_swing2_end
    tau3, tau4 = a.swing1_torque_time_constant * (t1 - t_to), a.swing2_knee_time_constant * (t2 - t1)
    ctx = dict(stance_context)
    ctx.update({f"stance_{k}": stance_parameters.get(k, 0.0) for k in STANCE_PARAMETERS.names})
    ctx.update(origin_x=origin[0], origin_y=origin[1],
               l8=b.l8, l9=b.l9, l12=b.l12, l13=b.l13, toe_off_time=t_to, swing_end_time=t.t_step,
               **{key: getattr(curve.swing_foot, name) for key, name in zip(FOOT_CONTEXT, SCHEDULE_FIELDS)},
               k_h=gains.k_h, d_h=gains.d_h, theta3_target=con.theta3, theta3_peak=thigh_peak(a, con),
               tau3=tau3, exp3_mean=exponential_mean(t1 - t_to, tau3), curve_x0=curve.x0, baumgarte=CURVE_P_BAUMGARTE,
               swing2_start=t1, tau4=tau4, exp4_mean=exponential_mean(t2 - t1, tau4), pelvis_width=pelvis.width,
               pelvis_rotation_start=pelvis.rotation_start, pelvis_rotation_end=pelvis.rotation_end,
               pelvis_list=pelvis.list_peak, hold_offset=0.0,
               **{f"P{i}": curve.coefficients[i] for i in range(5)})
    return SWING_CONTEXT.pack(ctx)
