"""The closed-loop stance dynamics of section 4.2, as one symbolic right-hand side.

State ``x = [w, theta1, theta2, wd, theta1d, theta2d]`` (m, rad, rad, m/s, rad/s, rad/s),
relative to the stance ankle. Free parameters ``u = [F_theta1 magnitude (N m), pa offset (m)]``.
The context ``c`` (:data:`STANCE_CONTEXT`) holds the body, the gains and the step's numbers.

- F_theta1: step input of magnitude u[0], off at ``t_off`` = 0.4 t_step.
- F_w: spring-damper with position actuator ``pa`` (ERRATA 8). pa is monitored (§4.2): it is
  raised when the hip falls below the sinusoid of human walking and lowered when it rises above
  it; the offset u[1] is what the solver chooses so that w reaches its eq. 3 value at t_step.
- F_theta2: spring-damper that balances the upper body about ``theta2_ref``, applied directly as
  F_theta2 like the paper (ERRATA "Generalized forces").
- ``locked`` = 1 gives the rigid leg (wdd = 0) of the lock rules.
"""
from __future__ import annotations

import casadi as ca

from ..body import DYNAMIC_PARAMETER_NAMES
from ..dynamics.stance import stance_accelerations_sx
from .layout import VectorLayout
from .torques import hip_height_reference, leg_force, position_actuator, spring_damper, step_torque

STANCE_STATE = VectorLayout(["w", "theta1", "theta2", "wd", "theta1d", "theta2d"])
STANCE_UNKNOWNS = VectorLayout(["F_theta1_magnitude", "pa_offset"])
STANCE_CONTEXT = VectorLayout(
    DYNAMIC_PARAMETER_NAMES,
    ["k_w", "v_w", "k_t", "d_t", "theta2_ref", "k_y", "c_y",
     "t_off", "t_step", "y_start", "y_end", "excursion", "locked", "theta1_target", "w_target"],
)
STANCE_FORCES = ("F_w", "F_theta1", "F_theta2", "pa")


def body_vector(c: ca.SX) -> ca.SX:
    """The body-parameter slice of a context vector (every context starts with it)."""
    return c[: len(DYNAMIC_PARAMETER_NAMES)]


def stance_forces(x, t, u, c):
    """Generalized forces [F_w, F_theta1, F_theta2] and the actuator pa at state x, time t."""
    n = STANCE_CONTEXT.bind(c)
    w, th1, th2, wd, th1d, th2d = (x[i] for i in range(6))
    y = w * ca.cos(th1)                      # hip height above the ankle
    yd = wd * ca.cos(th1) - w * th1d * ca.sin(th1)
    y_ref, yd_ref = hip_height_reference(t, n.t_step, n.y_start, n.y_end, n.excursion)
    pa = position_actuator(u[1] * late_extension(t, n.t_step), n.k_y, n.c_y, y_ref, yd_ref, y, yd)
    f_w = leg_force(w, wd, n.k_w, n.v_w, n.l1, pa)
    f_th1 = step_torque(t, n.t_off, u[0])
    if u.numel() > 2:   # closing step: a braking level after t_off brings the leg to rest
        f_th1 = f_th1 + u[2] - step_torque(t, n.t_off, u[2])
    f_th2 = spring_damper(th2, th2d, n.k_t, n.d_t, n.theta2_ref)
    return ca.vertcat(f_w, f_th1, f_th2), pa


def late_extension(t, t_step):
    """0 until mid-step, then a smooth rise to 1 at t_step: where the pa offset acts.

    "an increase in pa extends the leg to the desired length at the end of the step" (§4.2); acting
    only after mid-step keeps the offset's effect on w(t_step) direct and its effect on theta1 small,
    which is what lets the paper's one-unknown-at-a-time shooting converge.
    """
    phase = ca.fmax(0, 2 * t / t_step - 1)
    return 0.5 * (1 - ca.cos(ca.pi * phase))


def stance_rhs(x, t, u, c):
    """dx/dt of the closed-loop stance model."""
    n = STANCE_CONTEXT.bind(c)
    force, _ = stance_forces(x, t, u, c)
    qdd = stance_accelerations_sx(x[0:3], x[3:6], force, body_vector(c), n.locked)
    return ca.vertcat(x[3:6], qdd)


def stance_final_conditions(x, c, at_rest: bool = False):
    """theta1 and w at t_step minus their eq. 3 values (and theta1d for a stop at rest)."""
    n = STANCE_CONTEXT.bind(c)
    conditions = [x[1] - n.theta1_target, x[0] - n.w_target]
    return ca.vertcat(*conditions, x[4]) if at_rest else ca.vertcat(*conditions)
