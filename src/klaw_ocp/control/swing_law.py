"""The closed-loop swing dynamics of section 4.3, one right-hand side per subphase.

The swing leg hangs from the pelvis's other hip (§4.2): the hip of the stance model of the same
step (assumption 4) plus the pelvis's offset (:func:`klaw_ocp.kinematics.pelvis.swing_hip_offset`,
its rotation and list, with their rates and accelerations). Rather than
interpolating a sampled hip trajectory, every swing state carries the stance state along and
integrates the stance model with its solved parameters: the hip acceleration fed to the swing
model is then exact, and identical in both solver modes.

States (stance part first, see :mod:`.stance_law`):

- swing1: ``[w, theta1, theta2, wd, theta1d, theta2d, theta3, theta4, theta3d]``. The knee is
  locked for the dynamics (eq. 5) while theta4 is driven kinematically by forcing the ankle onto
  curve P; theta4's rate comes from differentiating that constraint, with a Baumgarte term that
  keeps the ankle on the curve (ERRATA "Swing1": the paper accepts this inconsistency).
  F_theta3 = a decaying exponential about its mean (ERRATA 7: F_theta3, not F_theta1): two
  unknowns, so that the thigh reaches its peak at t1 at rest ("the hip angle reaches a maximum",
  §4.3): the heel-strike angle, or ``terminal_swing_retraction`` ahead of it.
- swing2: ``[..6.., theta3, theta4, theta3d, theta4d]``. F_theta3 is a spring-damper holding the
  thigh at its peak (retracting towards the heel-strike angle late in the swing where the peak is
  ahead of it: :func:`thigh_reference`), shifted by the recovery actuator; F_theta4 a decaying exponential
  about its mean, two unknowns, so that the knee reaches full extension at t2 at rest and
  swing3's lock (eq. 5) is not an impact. In a walk's closing step (:func:`closing_swing2_torques`)
  the recovery actuator gives way to a torque a s + b s² added to the hold, two more unknowns,
  so that the thigh also ends swing2 on its reference and moving with it.
- swing3: ``[..6.., theta3, theta3d]``, knee locked at full extension (theta4 = 0). F_theta3 is the
  spring-damper about the thigh's reference (the heel-strike angle at heel strike) plus a small constant moment that brings the heel down
  in time.

The kinematic foot (ankle angle theta5, toe angle theta6) follows the schedule of
kinematics/swing_foot.py, the same one the body's angles use.
"""
from __future__ import annotations

import casadi as ca

from ..body import DYNAMIC_PARAMETER_NAMES
from ..dynamics.points import foot_points_sx
from ..dynamics.stance import hip_kinematics_sx, stance_accelerations_sx
from ..dynamics.swing import swing_accelerations_sx, swing_points
from ..kinematics.pelvis import swing_hip_offset
from ..kinematics.swing_foot import SCHEDULE_FIELDS, schedule_angles
from .layout import VectorLayout
from .stance_law import STANCE_CONTEXT, STANCE_PARAMETERS, body_vector, stance_forces
from .torques import decaying_exponential_about_mean, spring_damper

#: Swing1's knee tracks curve P with a damped least-squares rate of its one equation
#: g(θ3, θ4, hip) = ankle_y - P(ankle_x) (after Nakamura & Hanafusa 1986): θ̇4 = -(b g + g_θ3 θ̇3
#: + g_h ḣ) g_θ4 / (g_θ4² + ε² exp(-(g_θ4/ε)⁴)). Where the shank swings tangent to the curve,
#: g_θ4 -> 0 and the exact rate is unbounded: there the swing1 map was noisy, and closing steps
#: had no solution to 1e-2 (plain shooting, 2-3.5 km/h, 1.5 and 1.8 m, heel_strike_hip_lead 0.06-0.1:
#: 6 of 24 walks failed without the damping, none with it). With ε = 5 % of the shank (m/rad) the
#: ankle leaves the curve for a moment there and the Baumgarte term brings it back. The damping
#: fades out as |g_θ4| grows (exp(-16) at 2ε), so elsewhere the rate is the exact one and curve P's
#: end slope still gives the knee its rate at t1 (a plain ε² changed it by 5 %).
CURVE_P_KNEE_DAMPING_REL = 0.05

#: the swing foot's schedule (kinematics/swing_foot.py), under these names in the swing context
FOOT_CONTEXT = tuple(f"foot_{name}" for name in SCHEDULE_FIELDS)
#: the solved stance parameters, under these names in the swing context
STANCE_PARAMETERS_IN_SWING = tuple(f"stance_{name}" for name in STANCE_PARAMETERS.names)
SWING_CONTEXT = VectorLayout(
    STANCE_CONTEXT,
    STANCE_PARAMETERS_IN_SWING,
    ["origin_x", "origin_y", "l8", "l9", "l12", "l13",
     "toe_off_time", "swing_end_time", *FOOT_CONTEXT,
     "k_h", "d_h", "theta3_target", "theta3_peak", "tau3", "exp3_mean", "P0", "P1", "P2", "P3", "P4", "curve_x0", "baumgarte",
     "swing2_start", "tau4", "exp4_mean", "pelvis_width", "pelvis_rotation_start", "pelvis_rotation_end",
     "pelvis_list", "hold_offset"],
)
SWING_FORCES = ("F_w", "F_theta1", "F_theta2", "pa", "F_theta3", "F_theta4")
SWING1_STATE = ("w", "theta1", "theta2", "wd", "theta1d", "theta2d", "theta3", "theta4", "theta3d")
SWING2_STATE = ("w", "theta1", "theta2", "wd", "theta1d", "theta2d", "theta3", "theta4", "theta3d", "theta4d")
SWING3_STATE = ("w", "theta1", "theta2", "wd", "theta1d", "theta2d", "theta3", "theta3d")


def names(c):
    return SWING_CONTEXT.bind(c)


def stance_part(xs, t, c):
    """Stance rates, its forces, and the swing hip's world position, velocity and acceleration:
    the stance hip's, plus the pelvis's offset to its other hip."""
    n = names(c)
    first = SWING_CONTEXT.index[STANCE_PARAMETERS_IN_SWING[0]]
    p_stance = c[first: first + len(STANCE_PARAMETERS)]
    force, pa = stance_forces(xs, t, p_stance, c[: len(STANCE_CONTEXT)])
    qdd = stance_accelerations_sx(xs[0:3], xs[3:6], force, body_vector(c), n.locked)
    pos, vel, acc = hip_kinematics_sx(xs[0:3], xs[3:6], qdd)
    (dx, dy), (vx, vy), (ax, ay) = swing_hip_offset(n.pelvis_width, n.pelvis_rotation_start, n.pelvis_rotation_end,
                                                    n.pelvis_list, n.swing_end_time, t, ca)
    hip = pos + ca.vertcat(n.origin_x + dx, n.origin_y + dy)
    return ca.vertcat(xs[3:6], qdd), ca.vertcat(force, pa), hip, vel + ca.vertcat(vx, vy), acc + ca.vertcat(ax, ay)


def foot_angles(t, c):
    """theta5, theta6 of the swing foot at ``t``: the schedule of kinematics/swing_foot.py, the same
    formula the body's angles use."""
    n = names(c)
    values = {name: getattr(n, f"foot_{name}") for name in SCHEDULE_FIELDS}
    return schedule_angles(t, values, lambda x, lo, hi: ca.fmin(ca.fmax(x, lo), hi))


def foot(q_swing, hip, t, c):
    """World positions of heel and toe tip of the swing foot."""
    n = names(c)
    ankle = swing_points(q_swing, hip, body_vector(c))["ankle"]
    theta5, theta6 = foot_angles(t, c)
    pts = foot_points_sx(ankle, q_swing[0] + q_swing[1], theta5, theta6, n.l8, n.l9, n.l12, n.l13)
    return pts["heel"], pts["toe"]


def curve_p(c, s):
    n = names(c)
    return (((n.P0 * s + n.P1) * s + n.P2) * s + n.P3) * s + n.P4


def swing1_rhs(x, t, u, c):
    n = names(c)
    stance_rates, _, hip, hip_vel, hip_acc = stance_part(x[0:6], t, c)
    th3, th4, th3d = x[6], x[7], x[8]
    f3 = swing1_torque(t, u, c)
    qdd = swing_accelerations_sx(ca.vertcat(th3, th4), ca.vertcat(th3d, 0), ca.vertcat(f3, 0), hip_acc,
                                 body_vector(c), 1)
    th3dd = qdd[0]
    # knee driven kinematically: d/dt [ankle_y - P(ankle_x - x0)] = -baumgarte * (ankle_y - P(...))
    q_sym, h_sym = ca.SX.sym("q", 2), ca.SX.sym("h", 2)
    ankle = swing_points(q_sym, h_sym, body_vector(c))["ankle"]
    constraint = ankle[1] - curve_p(c, ankle[0] - n.curve_x0)
    grad_q = ca.jacobian(constraint, q_sym)
    grad_h = ca.jacobian(constraint, h_sym)
    subs = lambda e: ca.substitute(ca.substitute(e, q_sym, ca.vertcat(th3, th4)), h_sym, hip)
    g_val, gq, gh = subs(constraint), subs(grad_q), subs(grad_h)
    # the damped least-squares rate (CURVE_P_KNEE_DAMPING_REL): bounded where the knee cannot move
    # the ankle across the curve
    damping = CURVE_P_KNEE_DAMPING_REL * body_vector(c)[DYNAMIC_PARAMETER_NAMES.index("l4")]
    damped = damping ** 2 * ca.exp(-(gq[1] / damping) ** 4)
    th4d = -(n.baumgarte * g_val + gq[0] * th3d + ca.mtimes(gh, hip_vel)) * gq[1] / (gq[1] ** 2 + damped)
    return ca.vertcat(stance_rates, th3d, th4d, th3dd)


def swing1_torque(t, u, c):
    """F_theta3 of swing1, u = (fall, mean)."""
    n = names(c)
    return decaying_exponential_about_mean(t, n.toe_off_time, n.tau3, n.exp3_mean, u[0], u[1])


def swing1_forces(x, t, u, c):
    _, stance_f, *_ = stance_part(x[0:6], t, c)
    return ca.vertcat(stance_f, swing1_torque(t, u, c), 0)


#: The thigh's hold keeps its peak over this share of the time from t1 to heel strike (the shank
#: passes under the knee at about 0.3-0.45 of it, where the ankle is lowest), then retracts to the
#: heel-strike angle (:func:`thigh_reference`). A retraction confined to swing3 (0.15 of the swing)
#: cost about 0.45 N m/kg of peak hip torque per degree at 5 km/h, this one about 0.17.
RETRACTION_START_SHARE = 0.35


def thigh_reference(t, c, shift=0):
    """The swing hold's target and its rate at ``t``: the thigh's peak (``theta3_peak``, at t1),
    moved by ``shift`` (the recovery actuator, §4.3: forward where the toe would touch the ground),
    over RETRACTION_START_SHARE of the time from t1 to heel strike, then to the heel-strike angle
    (``theta3_target``) on S(s) = 3s² − 2s³, at rest at heel strike (§4.3: the hip angle "reaches
    a maximum" at t1; people's thighs retract in terminal swing). The shift fades out with the
    retraction: held to t2 and dropped there, it was retracted by swing3's constant moment alone
    (a closing step's 4.2 N m/kg at 5 km/h). Where the peak is the heel-strike angle and nothing
    shifts it, the target is that angle throughout, the paper's hold. A closing step's peak is
    behind its vertical landing angle (step_stages.CLOSING_APPROACH_DEG): the same curve brings
    the thigh forward onto it."""
    n = names(c)
    t_r = n.swing2_start + RETRACTION_START_SHARE * (n.swing_end_time - n.swing2_start)
    span = n.swing_end_time - t_r
    s = ca.fmin(ca.fmax((t - t_r) / span, 0), 1)
    start = n.theta3_peak + shift
    return start + (n.theta3_target - start) * s * s * (3 - 2 * s), (n.theta3_target - start) * 6 * s * (1 - s) / span


def _hold(th3, th3d, t, c, shift):
    """The swing hold, a spring-damper about :func:`thigh_reference` (its damper on the rate
    against the target's)."""
    n = names(c)
    target, target_rate = thigh_reference(t, c, shift)
    return spring_damper(th3, th3d - target_rate, n.k_h, n.d_h, target)


def swing2_torques(x, t, u, c):
    """F_theta3 (the hold at the thigh's peak, shifted by the recovery actuator u[1]) and F_theta4,
    u = (fall, actuator, mean)."""
    n = names(c)
    return _hold(x[6], x[8], t, c, u[1]), decaying_exponential_about_mean(t, n.swing2_start, n.tau4, n.exp4_mean, u[0], u[2])


def swing2_rhs(x, t, u, c, torques=swing2_torques):
    stance_rates, _, hip, hip_vel, hip_acc = stance_part(x[0:6], t, c)
    f3, f4 = torques(x, t, u, c)
    qdd = swing_accelerations_sx(x[6:8], x[8:10], ca.vertcat(f3, f4), hip_acc, body_vector(c), 0)
    return ca.vertcat(stance_rates, x[8:10], qdd)


def swing2_forces(x, t, u, c, torques=swing2_torques):
    _, stance_f, *_ = stance_part(x[0:6], t, c)
    return ca.vertcat(stance_f, *torques(x, t, u, c))


def closing_swing2_torques(x, t, u, c):
    """A closing step's swing2, u = (F_theta4's fall, a, F_theta4's mean, b): F_theta3 is the hold
    about :func:`thigh_reference` plus a s + b s², s = (t - t1)/(t2 - t1) (none at t1, where
    swing1's torque hands over), F_theta4 as in :func:`swing2_torques`.

    Why: in the last step the foot lands beside the stance foot with the leg all but vertical, and
    as the knee extends into full extension at rest at t2 its braking throws the thigh forward
    (gravity does not brake the shank past the vertical, as it does in a step that lands ahead).
    The soft hold let the thigh run 2-3° past its target at up to 70 °/s, and swing3's one
    constant moment had to pull it back in 15 % of the swing: 2.3 N m/kg at 5 km/h, 4.2 at 9 km/h.
    With the thigh on its reference and moving with it at t2 (:func:`closing_swing2_final`),
    swing3's moment has next to nothing left to do."""
    n = names(c)
    s = (t - n.swing2_start) / (n.foot_t2 - n.swing2_start)
    f3 = _hold(x[6], x[8], t, c, 0) + s * (u[1] + u[3] * s)
    return f3, decaying_exponential_about_mean(t, n.swing2_start, n.tau4, n.exp4_mean, u[0], u[2])


def closing_swing2_rhs(x, t, u, c):
    return swing2_rhs(x, t, u, c, closing_swing2_torques)


def closing_swing2_forces(x, t, u, c):
    return swing2_forces(x, t, u, c, closing_swing2_torques)


def closing_swing2_final(x, c):
    """A closing step's swing2 ends with the knee straight and at rest (as every swing2) and the
    thigh on its reference at t2, moving with it."""
    target, target_rate = thigh_reference(names(c).foot_t2, c)
    return ca.vertcat(x[7], x[9], x[6] - target, x[8] - target_rate)


def swing2_clearance(x, t, u, c):
    """Toe tip and heel heights of the swing foot: the toe kept ``toe_clearance`` above the
    ground (§4.3's recovery); the heel reported only (its lower bound is -inf: control/step.py,
    docs/paper-map.md)."""
    _, _, hip, _, _ = stance_part(x[0:6], t, c)
    heel, toe = foot(x[6:8], hip, t, c)
    return ca.vertcat(toe[1], heel[1])


def swing3_torque(x, t, u, c):
    """The hold (with swing2's recovery shift fading on, ``hold_offset``) plus the constant moment
    that lands the thigh at its heel-strike angle."""
    return _hold(x[6], x[7], t, c, names(c).hold_offset) + u[0]


def swing3_rhs(x, t, u, c):
    stance_rates, _, hip, hip_vel, hip_acc = stance_part(x[0:6], t, c)
    f3 = swing3_torque(x, t, u, c)
    qdd = swing_accelerations_sx(ca.vertcat(x[6], 0), ca.vertcat(x[7], 0), ca.vertcat(f3, 0), hip_acc,
                                 body_vector(c), 1)
    return ca.vertcat(stance_rates, x[7], qdd[0])


def swing3_forces(x, t, u, c):
    _, stance_f, *_ = stance_part(x[0:6], t, c)
    return ca.vertcat(stance_f, swing3_torque(x, t, u, c), 0)


def swing3_clearance(x, t, u, c):
    """The heel's height before it strikes (reported as the step's heel clearance: swing3's one
    unknown is fixed by the landing, so it is not constrained)."""
    _, _, hip, _, _ = stance_part(x[0:6], t, c)
    heel, _ = foot(ca.vertcat(x[6], 0), hip, t, c)
    return heel[1]
