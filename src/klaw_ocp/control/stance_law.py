"""The closed-loop stance dynamics of section 4.2, as one symbolic right-hand side.

State ``x = [w, theta1, theta2, wd, theta1d, theta2d]`` (m, rad, rad, m/s, rad/s, rad/s),
relative to the stance ankle. The torque-shape parameters ``p`` (:data:`STANCE_PARAMETERS`) are the
F_theta1 magnitude (N m), the pa offset (m), the closing step's braking level (N m) and the
knots of a pa profile (m); the context ``c`` (:data:`STANCE_CONTEXT`) holds the body, the gains
and the step's numbers.

- F_theta1: step input of the magnitude, off at ``t_off`` = 0.4 t_step.
- F_w: spring-damper with position actuator ``pa`` (ERRATA 8). pa is monitored (§4.2): it is
  raised when the hip falls below the sinusoid of human walking and lowered when it rises above
  it; the offset is what the paper's solver chooses so that w reaches its eq. 3 value at t_step.
  The profile (piecewise linear in t / t_step, zero in the paper's formulation) is "pa free over
  the grid": the tracking formulation of the stance optimises it (control/stance_spec.py).
- F_theta2: spring-damper that balances the upper body about ``theta2_ref``, applied directly as
  F_theta2 like the paper (ERRATA "Generalized forces").
- ``locked`` = 1 gives the rigid leg (wdd = 0) of the lock rules.
"""
from __future__ import annotations

import casadi as ca

from ..casadi_builds import built_once
from ..body import DYNAMIC_PARAMETER_NAMES
from ..dynamics.stance import hip_kinematics_sx, stance_accelerations_sx
from .layout import VectorLayout
from .torques import (hip_height_reference, leg_force, piecewise_linear, position_actuator, spring_damper,
                      step_torque)

STANCE_STATE = VectorLayout(["w", "theta1", "theta2", "wd", "theta1d", "theta2d"])
#: intervals of the pa profile over the stance (its knots sit at t_step * i / PA_PROFILE_INTERVALS)
PA_PROFILE_INTERVALS = 10
PA_KNOTS = tuple(f"pa_knot_{i}" for i in range(PA_PROFILE_INTERVALS + 1))
STANCE_PARAMETERS = VectorLayout(["F_theta1_magnitude", "pa_offset", "F_theta1_brake"], PA_KNOTS)
STANCE_CONTEXT = VectorLayout(
    DYNAMIC_PARAMETER_NAMES,
    ["k_w", "v_w", "k_t", "d_t", "theta2_ref", "k_y", "c_y",
     "t_off", "t_step", "y_start", "y_end", "excursion", "hip_rise", "hip_fall", "hip_fall_power", "locked", "theta1_target", "w_target",
     "hip_settle"],
)
STANCE_FORCES = ("F_w", "F_theta1", "F_theta2", "pa")
STANCE_PATH = ("leg_lock_margin", "hip_above_floor", "hip_vertical_velocity")
#: hip-height error that costs as much as one unit of objective in the tracking formulation
TRACKING_SCALE_M = 0.01


def body_vector(c: ca.SX) -> ca.SX:
    """The body-parameter slice of a context vector (every context starts with it)."""
    return c[: len(DYNAMIC_PARAMETER_NAMES)]


def hip_height(x):
    """Hip height above the stance ankle and its rate, from the dynamics' hip kinematics (the one
    definition of the stance geometry, :func:`klaw_ocp.dynamics.stance.hip_kinematics_sx`)."""
    pos, vel, _ = hip_kinematics_sx(x[0:3], x[3:6], ca.DM.zeros(3))
    return pos[1], vel[1]


@built_once
def hip_height_function(nodes: int) -> ca.Function:
    """:func:`hip_height` of ``nodes`` stance states at once: ``X[6, nodes] -> (y, yd)``."""
    x = ca.SX.sym("x", 6)
    return ca.Function("hip_height", [x], list(hip_height(x))).map(nodes)


def stance_forces(x, t, p, c):
    """Generalized forces [F_w, F_theta1, F_theta2] and the actuator pa at state x, time t, for
    the parameter vector ``p`` laid out as :data:`STANCE_PARAMETERS`."""
    n, q = STANCE_CONTEXT.bind(c), STANCE_PARAMETERS.bind(p)
    y, yd = hip_height(x)
    y_ref, yd_ref = hip_height_reference(t, n.t_step, n.y_start, n.y_end, n.excursion, n.hip_rise, n.hip_fall,
                                         n.hip_fall_power, n.hip_settle)
    knots = [getattr(q, k) for k in PA_KNOTS]
    command = q.pa_offset * late_extension(t, n.t_step) + piecewise_linear(t / n.t_step, knots)
    pa = position_actuator(command, n.k_y, n.c_y, y_ref, yd_ref, y, yd)
    f_w = leg_force(x[0], x[3], n.k_w, n.v_w, n.l1, pa)
    # the closing step's braking level after t_off brings the leg to rest (0 in other steps)
    f_th1 = step_torque(t, n.t_off, q.F_theta1_magnitude) + q.F_theta1_brake - step_torque(t, n.t_off, q.F_theta1_brake)
    f_th2 = spring_damper(x[2], x[5], n.k_t, n.d_t, n.theta2_ref)
    return ca.vertcat(f_w, f_th1, f_th2), pa


def late_extension(t, t_step):
    """0 until mid-step, then a smooth rise to 1 at t_step: where the pa offset acts.

    "an increase in pa extends the leg to the desired length at the end of the step" (§4.2); acting
    only after mid-step keeps the offset's effect on w(t_step) direct and its effect on theta1 small,
    which is what lets the paper's one-unknown-at-a-time shooting converge.
    """
    phase = ca.fmax(0, 2 * t / t_step - 1)
    return 0.5 * (1 - ca.cos(ca.pi * phase))


def stance_rhs(x, t, p, c):
    """dx/dt of the closed-loop stance model."""
    n = STANCE_CONTEXT.bind(c)
    force, _ = stance_forces(x, t, p, c)
    qdd = stance_accelerations_sx(x[0:3], x[3:6], force, body_vector(c), n.locked)
    return ca.vertcat(x[3:6], qdd)


def stance_path(x, c):
    """The stance inequalities, each >= a per-node lower bound (control/stance_spec.py says where):

    - ``leg_lock_margin`` = l1 - w: the lock rule's "w > l1 too early" may not happen;
    - ``hip_above_floor``: hip height minus the lower of the two heel-strike heights (§4: the hip
      "must never be allowed to drop below its minimal value at heel strike");
    - ``hip_vertical_velocity``: at t_step, so the hip meets the next heel strike at its lowest.
    """
    n = STANCE_CONTEXT.bind(c)
    y, yd = hip_height(x)
    return ca.vertcat(n.l1 - x[0], y - ca.fmin(n.y_start, n.y_end), yd)


def tracking_residuals(x, t, p, c):
    """Least-squares residuals of the tracking formulation (its running cost is their sum of
    squares): the hip's distance from the sinusoid of human walking, in units of
    :data:`TRACKING_SCALE_M`, and a small price on kinks of the pa profile so that the optimum is a
    smooth actuator, not a saw-tooth the grid cannot see. The profile replaces the offset of the
    monitored formulation (the two overlap after mid-step), so the offset is priced too."""
    n, q = STANCE_CONTEXT.bind(c), STANCE_PARAMETERS.bind(p)
    y, _ = hip_height(x)
    y_ref, _ = hip_height_reference(t, n.t_step, n.y_start, n.y_end, n.excursion, n.hip_rise, n.hip_fall,
                                    n.hip_fall_power, n.hip_settle)
    knots = ca.vertcat(*[getattr(q, k) for k in PA_KNOTS])
    kinks = ca.diff(ca.diff(knots))
    return ca.vertcat((y - y_ref) / TRACKING_SCALE_M, 0.1 * kinks / TRACKING_SCALE_M, 0.1 * q.pa_offset / TRACKING_SCALE_M)


def stance_final_conditions(x, c, at_rest: bool = False):
    """theta1 and w at t_step minus their eq. 3 values (and theta1d for a stop at rest)."""
    n = STANCE_CONTEXT.bind(c)
    conditions = [x[1] - n.theta1_target, x[0] - n.w_target]
    return ca.vertcat(*conditions, x[4]) if at_rest else ca.vertcat(*conditions)


def stance_plausible(x, c):
    """Margins of a physically meaningful stance state (all >= 0): the leg between half and one
    and a half leg lengths, neither the leg nor the trunk more than 1.2 rad (69 deg) from vertical.
    Far outside every walk; they only reject spurious roots of the discretised equations."""
    n = STANCE_CONTEXT.bind(c)
    return ca.vertcat(x[0] - 0.5 * n.l1, 1.5 * n.l1 - x[0], 1.2 - ca.fabs(x[1]), 1.2 - ca.fabs(x[2]))
