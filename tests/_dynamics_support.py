"""Test support for the dynamics tests: Appendix A transcribed by hand, and a tight integrator.

The printed matrices are transcribed here from the paper (Appendix A.1, A.2), deliberately *not*
from the code, so that the tests compare two independent sources. A.2's Coriolis term is printed
as ``m4 l3 r4 theta4d (2 theta3d + theta4) sin theta4``; ERRATA 2 corrects it to ``... + theta4d``.
``typo=True`` reproduces the printed version.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from klaw_ocp.body import Body
from klaw_ocp.dynamics import stance_functions, swing_functions

BODIES = (Body(1.8, 80.0), Body(1.2, 25.0))


def printed_a1(b: Body, q, qd, F=(0.0, 0.0, 0.0)):
    """Appendix A.1 as printed: A (with a31 = a13, a32 = a23) and B (with the forces)."""
    w, t1, t2 = q
    wd, t1d, t2d = qd
    m1, m2, r1, r2, I1, I2, g = b.m1, b.m2, b.r1, b.r2, b.I1, b.I2, b.g
    a13 = -m2 * r2 * np.sin(t2 - t1)
    a23 = m2 * r2 * w * np.cos(t2 - t1)
    A = np.array([[m2, 0.0, a13],
                  [0.0, I1 + m1 * r1 ** 2 + m2 * w ** 2, a23],
                  [a13, a23, I2 + m2 * r2 ** 2]])
    B = np.array([
        F[0] + m2 * w * t1d ** 2 + m2 * r2 * t2d ** 2 * np.cos(t2 - t1) - m2 * g * np.cos(t1),
        F[1] - 2 * m2 * w * wd * t1d + (m1 * r1 + m2 * w) * g * np.sin(t1)
        + m2 * r2 * w * t2d ** 2 * np.sin(t2 - t1),
        F[2] + m2 * g * r2 * np.sin(t2) - 2 * m2 * r2 * wd * t1d * np.cos(t2 - t1)
        - m2 * r2 * w * t1d ** 2 * np.sin(t2 - t1),
    ])
    return A, B


def printed_a2(b: Body, q, qd, hip_acc, F=(0.0, 0.0), typo=False):
    """Appendix A.2 as printed, with ERRATA 2 applied unless ``typo`` (a21 = a12)."""
    t3, t4 = q
    t3d, t4d = qd
    xdd, ydd = hip_acc
    m3, m4, l3, r3, r4, I3, I4, g = b.m3, b.m4, b.l3, b.r3, b.r4, b.I3, b.I4, b.g
    a11 = I3 + m3 * r3 ** 2 + m4 * l3 ** 2 + I4 + m4 * r4 ** 2 + 2 * m4 * l3 * r4 * np.cos(t4)
    a12 = I4 + m4 * r4 ** 2 + m4 * l3 * r4 * np.cos(t4)
    a22 = I4 + m4 * r4 ** 2
    A = np.array([[a11, a12], [a12, a22]])
    s34, c34 = np.sin(t3 + t4), np.cos(t3 + t4)
    coriolis = m4 * l3 * r4 * t4d * (2 * t3d + (t4 if typo else t4d)) * np.sin(t4)
    B = np.array([
        F[0] + (m3 * r3 + m4 * l3) * (xdd * np.cos(t3) - ydd * np.sin(t3))
        + m4 * r4 * (xdd * c34 - ydd * s34) + coriolis
        - m3 * g * r3 * np.sin(t3) - m4 * g * (l3 * np.sin(t3) + r4 * s34),
        F[1] + m4 * r4 * (xdd * c34 - ydd * s34) - m4 * l3 * r4 * t3d ** 2 * np.sin(t4)
        - m4 * g * r4 * s34,
    ])
    return A, B


def stance_rhs_function(body: Body, locked: int = 0, k_w: float = 0.0, l_rest: float = 0.0,
                        k_hip: float = 0.0):
    """``x -> xdot`` of the stance model, one CasADi call per evaluation (fast enough for DOP853).

    Optional conservative springs: the leg spring ``F_w = -k_w (w - l_rest)`` and a hip spring
    between leg and upper body, potential ``k_hip (theta2 - theta1)^2 / 2``, whose generalized
    forces are ``F_theta1 = k_hip (theta2 - theta1) = -F_theta2``. See :func:`spring_energy`.
    """
    x = ca.SX.sym("x", 6)
    hip_torque = k_hip * (x[2] - x[1])
    force = ca.vertcat(-k_w * (x[0] - l_rest), hip_torque, -hip_torque)
    qdd = stance_functions()["acc"](x[:3], x[3:], force, ca.DM(body.dynamic_parameters()), locked)
    return ca.Function("rhs", [x], [ca.vertcat(x[3:], qdd)])


def spring_energy(x, k_w=0.0, l_rest=0.0, k_hip=0.0):
    """Potential energy of the springs of :func:`stance_rhs_function`."""
    return 0.5 * k_w * (x[0] - l_rest) ** 2 + 0.5 * k_hip * (x[2] - x[1]) ** 2


def swing_rhs_function(body: Body, locked: int = 0):
    """``(x, hip_acc) -> xdot`` of the passive swing model (F = 0)."""
    x, acc = ca.SX.sym("x", 4), ca.SX.sym("hip_acc", 2)
    qdd = swing_functions()["acc"](x[:2], x[2:], ca.DM.zeros(2), acc, ca.DM(body.dynamic_parameters()), locked)
    return ca.Function("rhs", [x, acc], [ca.vertcat(x[2:], qdd)])


def integrate(rhs, x0, t_end, n_out=200):
    """DOP853 at rtol = atol = 1e-12; returns (t, X) with X of shape (n_out, len(x0))."""
    t_eval = np.linspace(0.0, t_end, n_out)
    sol = solve_ivp(rhs, (0.0, t_end), np.asarray(x0, float), method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=t_eval)
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.t, sol.y.T
